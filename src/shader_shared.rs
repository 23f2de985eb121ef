// Constants shared by Rust and GLSL: the single source of truth (../shared/DESIGN.md, rule 7).
//
// This file is `include!`d twice: by the library (src/lib.rs, where the macros make
// `pub const`s) and by build.rs (where the same macros emit `#define`s into the generated
// GLSL header `prism_shared.glsl`). Edit a value here and both sides change together.
shared_constants! {
    // Material kinds (GpuMaterial.albedo_a.w).
    MATERIAL_DIFFUSE: u32 = 0;
    MATERIAL_MIRROR: u32 = 1;
    MATERIAL_CONDUCTOR: u32 = 2;
    MATERIAL_DIELECTRIC: u32 = 3;

    // Light kinds (GpuLight.position.w).
    LIGHT_POINT: u32 = 0;
    LIGHT_DIRECTIONAL: u32 = 1;

    // At most this many lights; each owns 6 layers of the shadow atlas (a cube for a point
    // light, layer 0 of its 6 for a directional light's orthographic map).
    MAX_LIGHTS: u32 = 4;
    SHADOW_LAYERS_PER_LIGHT: u32 = 6;

    // Descriptor set 0 (frame set) bindings, shared by every pass.
    BINDING_FRAME: u32 = 0;
    BINDING_MATERIALS: u32 = 1;
    BINDING_ENVIRONMENT: u32 = 2;
    BINDING_SHADOW_CUBE: u32 = 3;
    BINDING_SHADOW_2D: u32 = 4;
    // The caustic map atlas (src/technique/caustics/caustics_map.rs), laid out like the shadow atlas:
    // flux per texel in W, looked up by the receivers as a cube or as layers.
    BINDING_CAUSTIC_CUBE: u32 = 5;
    BINDING_CAUSTIC_2D: u32 = 6;
    // Photon-buffer caustics (Hu & Qin 2007 §3; src/technique/caustics/photon_buffer.rs): the filtered
    // caustic textures TEX_CAUSTICS_i (one array layer per receiver rectangle) and the
    // rectangles; a 1x1 stand-in and one zero rectangle when no photon pass runs.
    BINDING_PHOTON_CAUSTICS: u32 = 7;
    BINDING_PHOTON_RECTS: u32 = 8;

    // Descriptor set 1 (G-buffer inputs) bindings.
    BINDING_GBUF_NORMAL: u32 = 0;
    BINDING_GBUF_ALBEDO: u32 = 1;
    BINDING_GBUF_DEPTH: u32 = 2;
    BINDING_HDR: u32 = 3;
    // The adaptive tone map's state (scale, 1/L_white^2, ...) in set 1 of tonemap/adaptive.frag.
    BINDING_TONEMAP_STATE: u32 = 4;

    // The adaptive tone map's reduction kernels (glsl/tonemap/*.comp; src/technique/baseline/tonemap.rs):
    // one set 0. A workgroup of TONEMAP_GROUP^2 invocations, each summing a TONEMAP_BLOCK^2
    // block of pixels in a loop: a tile of (TONEMAP_GROUP TONEMAP_BLOCK)^2 pixels. Few
    // invocations and a serial loop because every barrier of the shared-memory tree costs a
    // CPU device (lavapipe) more than the pixels do: 16x16 invocations of one pixel each made
    // tonemap_log_average 17x the tone map pass itself (caustic_sphere, 512^2).
    TONEMAP_BINDING_HDR: u32 = 0;
    TONEMAP_BINDING_PARTIALS: u32 = 1;
    TONEMAP_BINDING_STATE: u32 = 2;
    TONEMAP_BINDING_STATS: u32 = 3;
    TONEMAP_GROUP: u32 = 8;
    TONEMAP_BLOCK: u32 = 4;

    // Reference path tracer (src/reference, glsl/reference): one descriptor set.
    REF_BINDING_UNIFORMS: u32 = 0;
    REF_BINDING_MATERIALS: u32 = 1;
    REF_BINDING_ENVIRONMENT: u32 = 2;
    REF_BINDING_VERTICES: u32 = 3;
    REF_BINDING_TRIANGLES: u32 = 4;
    REF_BINDING_NODES: u32 = 5;
    REF_BINDING_SPHERES: u32 = 6;
    REF_BINDING_OBJECTS: u32 = 7;
    REF_BINDING_ACCUM: u32 = 8;
    REF_BINDING_PIXELS: u32 = 9;
    REF_BINDING_PHOTONS: u32 = 10;
    REF_BINDING_GRID: u32 = 11;
    REF_BINDING_COUNTERS: u32 = 12;
    REF_BINDING_DEBUG: u32 = 13;
    // A volume's voxel fields (glsl/reference/volume.glsl).
    REF_BINDING_VOLUME: u32 = 14;
    // Specular objects photons are aimed at, at most.
    REF_MAX_TARGETS: u32 = 16;
    // Traversal stack depth (a SAH BVH over 1e6 triangles is far shallower).
    REF_STACK_SIZE: u32 = 64;
    // Threads per workgroup of the 1D reference kernels.
    REF_WORKGROUP: u32 = 64;
    // The raytrace technique's most specular interactions per branch: its shader keeps one
    // pending branch per depth (40 bytes each) in a fixed array.
    RAYTRACE_MAX_DEPTH: u32 = 64;
    // Photon outcomes written to the debug buffer (tests of energy conservation).
    PHOTON_MISSED: u32 = 0;
    PHOTON_DEPOSITED: u32 = 1;
    PHOTON_ESCAPED: u32 = 2;
    PHOTON_LOST: u32 = 3;
    PHOTON_DIRECT: u32 = 4;

    // Compute workgroup edge for 2D image kernels.
    WORKGROUP_2D: u32 = 8;

    // Specular-pass modes (specialisation constant 0 of specular/single.frag).
    SPECULAR_MODE_REFRACTION: u32 = 0;
    SPECULAR_MODE_REFLECTION: u32 = 1;

    // Image-space refraction (src/technique/refraction/refractor_layers.rs). Set 1 of the layer passes:
    // the per-vertex d_N storage buffer (Wyman 2005 only) and BINDING_GBUF_DEPTH (peeling).
    BINDING_REFR_DN: u32 = 4;
    // Set 1 of the refraction shading passes, besides BINDING_GBUF_NORMAL / _DEPTH.
    BINDING_REFR_BACK_NORMAL: u32 = 5;
    BINDING_REFR_BACK_DEPTH: u32 = 6;
    BINDING_REFR_FRONT_NORMAL: u32 = 7;
    BINDING_REFR_FRONT_DEPTH: u32 = 8;

    // Which surface of the refractors a layer pass keeps (specialisation constant 0 of
    // refraction/layers.frag): the nearest front face, the nearest back face, the furthest
    // back face, or the second surface behind the G-buffer's first (depth peeling).
    LAYER_FRONT: u32 = 0;
    LAYER_BACK_NEAREST: u32 = 1;
    LAYER_BACK_FURTHEST: u32 = 2;
    LAYER_SECOND: u32 = 3;

    // Distance impostors (Szirmay-Kalos et al. 2005, src/technique/impostor/distance_impostor.rs). Set 1
    // of the impostor shading passes, besides BINDING_GBUF_NORMAL / _DEPTH: the environment
    // impostor's radiance (rgb, distance in a unless separate) and distance cubes, and the
    // refractor map (xyz outward normal, w distance from the refractor's centre).
    BINDING_IMPOSTOR_RADIANCE: u32 = 9;
    BINDING_IMPOSTOR_DISTANCE: u32 = 10;
    BINDING_IMPOSTOR_REFRACTOR: u32 = 11;
    // The probe kernel's record buffer (glsl/impostor/probe.comp, tests).
    BINDING_IMPOSTOR_PROBE: u32 = 12;
    // Probe modes: Hit() against a map, and the conductor Fresnel terms.
    IMPOSTOR_PROBE_HIT: u32 = 0;
    IMPOSTOR_PROBE_FRESNEL: u32 = 1;
    // Caustics mapping (Shah et al. 2007; src/technique/caustics/caustics_map.rs). Set 1 of the splat
    // pass: the source faces and lights, the materials, the receivers' distance atlas (as a
    // cube array and as layers) and the refractor layers seen from the light.
    CAUSTIC_BINDING_FACES: u32 = 0;
    CAUSTIC_BINDING_MATERIALS: u32 = 1;
    CAUSTIC_BINDING_RECEIVER_CUBE: u32 = 2;
    CAUSTIC_BINDING_RECEIVER_2D: u32 = 3;
    CAUSTIC_BINDING_FRONT_POSITION: u32 = 4;
    CAUSTIC_BINDING_FRONT_NORMAL: u32 = 5;
    CAUSTIC_BINDING_BACK_POSITION: u32 = 6;
    CAUSTIC_BINDING_BACK_NORMAL: u32 = 7;
    // Eq. 6's V per source face (occlusion-query sample counts, u32), and how the splat
    // pass weighs each vertex's flux (render.caustics_map.flux).
    CAUSTIC_BINDING_VISIBLE: u32 = 9;
    FLUX_SOLID_ANGLE: u32 = 0;
    FLUX_OCCLUSION_QUERY: u32 = 1;
    // Intersection estimate (§III.D): the paper's approximate Newton-Raphson or the true one
    // of the appendix (with the bisection fallback of §III.D against oscillation).
    NEWTON_APPROXIMATE: u32 = 0;
    NEWTON_TRUE: u32 = 1;
    // Refractor layer passes (specialisation constant 0 of caustics/refractor.frag).
    CAUSTIC_LAYER_FRONT: u32 = 0;
    CAUSTIC_LAYER_BACK: u32 = 1;
    // Source-face kinds of the vertex grid.
    CAUSTIC_FACE_PERSPECTIVE: u32 = 0;
    CAUSTIC_FACE_ORTHOGRAPHIC: u32 = 1;
    // Light-map caustics with distance impostors (Szirmay-Kalos et al. 2005 §5;
    // src/technique/impostor/impostor_lightmap.rs). Set 1 of the caustic-map pass: the uv cube map,
    // filtered (its distance, for Hit()) and unfiltered (uv and receiver id), and the refractor
    // map; of the splat pass: the caustic map's two targets; of the apply pass (besides
    // BINDING_GBUF_*): the light maps.
    LIGHTMAP_BINDING_UV_LINEAR: u32 = 0;
    LIGHTMAP_BINDING_UV_NEAREST: u32 = 1;
    LIGHTMAP_BINDING_REFRACTOR: u32 = 2;
    LIGHTMAP_BINDING_PHOTON_HIT: u32 = 3;
    LIGHTMAP_BINDING_PHOTON_POWER: u32 = 4;
    BINDING_LIGHTMAPS: u32 = 14;
    // Photon buffer (Hu & Qin 2007 §3.1): the receiver rectangles, besides the caustic
    // bindings above (faces, materials, refractor layers).
    PHOTON_BINDING_RECTS: u32 = 8;
    // render.photon_buffer.normalization: irradiance from the photons' power through the
    // normalised filter, or the paper's s * (filtered photon count).
    PHOTON_PHYSICAL: u32 = 0;
    PHOTON_PAPER: u32 = 1;
    // Eikonal rendering (Ihrke et al. 2007; src/technique/eikonal/eikonal_view.rs). The volume compute
    // passes read EIKONAL_BINDING_SRC and write EIKONAL_BINDING_DST (storage images); set 1
    // of eikonal_view samples the field (grad n, n - 1) at BINDING_EIKONAL_FIELD besides
    // BINDING_GBUF_DEPTH.
    EIKONAL_BINDING_SRC: u32 = 0;
    EIKONAL_BINDING_DST: u32 = 1;
    BINDING_EIKONAL_FIELD: u32 = 13;
    // The material volumes of eikonal_view (src/scene/volume_sources.rs):
    // (extinction RGB, HG g), (albedo RGB, reflectance), (emission RGB, boundary band).
    BINDING_EIKONAL_EXTINCTION: u32 = 20;
    BINDING_EIKONAL_ALBEDO: u32 = 21;
    BINDING_EIKONAL_EMISSION: u32 = 22;
    // render.eikonal.integrator: Euler (Eqs. 11-12) or classical Runge-Kutta of Eqs. 9-10.
    EIKONAL_EULER: u32 = 0;
    EIKONAL_RK4: u32 = 1;
    // Compute workgroup edge of the volume passes (4^3 invocations).
    EIKONAL_GROUP: u32 = 4;
    // Hu & Qin 2007 §2.2 nearby geometry (src/technique/refraction/nearby_impostors.rs): set 1 of
    // refraction_hu_qin also holds the impostor rectangles (storage buffer) and TEX_i /
    // TEX_DEPTH_i (2D array: rgb radiance, a axial depth). At most MAX_NEARBY_RECTS
    // rectangles (the nearest objects are kept); the shader loops over them per ray.
    BINDING_NEARBY_RECTS: u32 = 14;
    BINDING_NEARBY_TEXTURE: u32 = 15;
    // Set 1 of the impostor-texture passes only: the dielectric OBJ_k's nearest back faces in
    // each rectangle's parallel projection (2D array: xyz outward normal, w axial depth).
    BINDING_NEARBY_BACK: u32 = 16;
    // ... and their nearest front faces, the same layout (recursive_exit = "full").
    BINDING_NEARBY_FRONT: u32 = 17;
    MAX_NEARBY_RECTS: u32 = 8;
    // Rectangle sets, one per OBJ_R (every dielectric, and the specular objects whose
    // recursive impostor textures look up their own set), each of at most MAX_NEARBY_RECTS.
    MAX_NEARBY_SETS: u32 = 8;
    // Eikonal light simulator (Ihrke et al. 2007 section 5.2; src/technique/eikonal/eikonal_light.rs,
    // src/technique/eikonal/histopyramid.rs). One descriptor set for every light/HistoPyramid kernel.
    LIGHT_BINDING_STATE: u32 = 0;
    LIGHT_BINDING_CLASSES: u32 = 1;
    LIGHT_BINDING_LEVELS: u32 = 2;
    LIGHT_BINDING_PAIRS: u32 = 3;
    LIGHT_BINDING_HISTORY: u32 = 4;
    LIGHT_BINDING_SRC: u32 = 5;
    LIGHT_BINDING_DST: u32 = 6;
    LIGHT_BINDING_FIELD: u32 = 7;
    // The additive irradiance accumulator (r32ui 3D image, six slabs along y).
    LIGHT_BINDING_ACCUM: u32 = 8;
    LIGHT_BINDING_IRRADIANCE: u32 = 10;
    LIGHT_BINDING_DIRECTION: u32 = 11;
    LIGHT_BINDING_EXTINCTION: u32 = 12;
    // Invocations per workgroup of the 1D light/HistoPyramid kernels.
    LIGHT_GROUP: u32 = 64;
    // The irradiance and direction volumes in set 1 of eikonal_view and deferred_shading.
    BINDING_EIKONAL_IRRADIANCE: u32 = 14;
    BINDING_EIKONAL_LIGHT_DIR: u32 = 15;
    // What exit and reflected view rays meet (src/technique/eikonal/eikonal_nearby.rs). Set 1
    // of eikonal_view also holds the impostor rectangles and TEX_i of
    // Hu & Qin 2007 §2.2 around the volume (the 14/15 of BINDING_NEARBY_* are taken by the
    // light volumes there) and the triangles of the exactly intersected flat receivers
    // (Ihrke et al. 2007 §6, Fig. 7), at most MAX_EIKONAL_TRIANGLES.
    BINDING_EIKONAL_NEARBY_RECTS: u32 = 23;
    BINDING_EIKONAL_NEARBY_TEXTURE: u32 = 24;
    BINDING_EIKONAL_TRIANGLES: u32 = 25;
    MAX_EIKONAL_TRIANGLES: u32 = 64;
    // The window's water animation (glsl/common/heightfield.comp; src/frame/heightfield.rs):
    // one set 0.
    HEIGHTFIELD_BINDING_FIELDS: u32 = 0;
    HEIGHTFIELD_BINDING_WAVES: u32 = 1;
    HEIGHTFIELD_BINDING_VERTICES: u32 = 2;
}

// Float constants, written into the GLSL header as float literals.
shared_floats! {
    // Cleared distance where a distance impostor sees no surface from its centre: far beyond
    // any scene (prism handles 1e-3..1e4 m) yet small enough that its square stays finite in
    // float (length()). glsl/include/impostor.glsl, src/technique/impostor/distance_impostor.rs.
    IMPOSTOR_NO_SURFACE: f32 = 1e15;
    // A looked-up distance above this is (a texel filtered with) "no surface": the ray leaves
    // the map and the environment is seen. 1e-5 of IMPOSTOR_NO_SURFACE still exceeds any scene.
    IMPOSTOR_MISS: f32 = 1e10;
}
