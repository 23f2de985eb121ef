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

    // At most this many materials: the shading passes read them from a uniform buffer of
    // MAX_MATERIALS GpuMaterials, 16 KiB, the least maxUniformBufferRange Vulkan guarantees.
    // Not a storage buffer: a CPU device (lavapipe) loads a storage buffer at a per-pixel index
    // lane by lane and a uniform buffer with one gather, and the material loads were about
    // half of the baseline's refraction pass (docs/BENCHMARKS.md).
    MAX_MATERIALS: u32 = 256;
    SHADOW_LAYERS_PER_LIGHT: u32 = 6;

    // The scene's environment and lights as the shading passes' specialisation constants
    // ENVIRONMENT, LIGHT_COUNT and LIGHT_KINDS (glsl/include/common.glsl; set from the scene by
    // src/technique/mod.rs `scene_specialization`). The *_ANY values, the shaders' defaults,
    // decide per lookup from the frame's data.
    ENVIRONMENT_ANY: u32 = 0;
    ENVIRONMENT_CONSTANT: u32 = 1;
    ENVIRONMENT_GRID: u32 = 2;
    ENVIRONMENT_MAP: u32 = 3;
    LIGHT_COUNT_ANY: u32 = 255;
    LIGHT_KINDS_POINT: u32 = 1;
    LIGHT_KINDS_DIRECTIONAL: u32 = 2;
    LIGHT_KINDS_ANY: u32 = 3;

    // The adaptive tone map's reduction kernels (glsl/tonemap/*.comp; src/technique/baseline/tonemap.rs).
    // A workgroup of TONEMAP_GROUP^2 invocations, each summing a TONEMAP_BLOCK^2
    // block of pixels in a loop: a tile of (TONEMAP_GROUP TONEMAP_BLOCK)^2 pixels. Few
    // invocations and a serial loop because every barrier of the shared-memory tree costs a
    // CPU device (lavapipe) more than the pixels do: 16x16 invocations of one pixel each made
    // tonemap_log_average 17x the tone map pass itself (caustic_sphere, 512^2).
    TONEMAP_GROUP: u32 = 8;
    TONEMAP_BLOCK: u32 = 4;

    // Specular objects photons are aimed at, at most (reference path tracer).
    REF_MAX_TARGETS: u32 = 16;
    // Threads per workgroup of the 1D kernels (the reference's, caustics mapping's splat hits),
    // dispatched in rows by src/reference/mod.rs `dispatch_size`.
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
    // Slots of the reference's stats buffer (REF_BINDING_STATS, glsl/reference/sppm.glsl):
    // the canary loop's trip count (written 2 by the host), then counters: invocations of
    // each kernel whose driver loop budget ran out (the canary ran once), and paths of the
    // camera and photon kernels that ended at volume.glsl's step cap.
    REF_STAT_CANARY_TRIPS: u32 = 0;
    REF_STAT_CUT_CAMERA: u32 = 1;
    REF_STAT_CUT_PHOTONS: u32 = 2;
    REF_STAT_CUT_GATHER: u32 = 3;
    REF_STAT_STEP_CAP_CAMERA: u32 = 4;
    REF_STAT_STEP_CAP_PHOTONS: u32 = 5;
    REF_STATS: u32 = 6;

    // Compute workgroup edge for 2D image kernels.
    WORKGROUP_2D: u32 = 8;

    // Specular-pass modes (specialisation constant MODE of specular/single.frag).
    // The step of Hu & Qin's d_T iteration (render.hu_qin.d_t_step, glsl/include/hu_qin_exit.glsl).
    D_T_STEP_PAPER: u32 = 0;
    D_T_STEP_NEWTON: u32 = 1;
    // Which rectangle's surface Hu & Qin's nearby lookup keeps (render.hu_qin.nearby_lookup,
    // recursive_lookup; glsl/include/nearby.glsl).
    NEARBY_LOOKUP_PAPER: u32 = 0;
    NEARBY_LOOKUP_NEAREST: u32 = 1;

    // The intermediates an oracle replaces by the exact tracer's (render.wyman.oracle,
    // render.hu_qin.oracle; the bit set of specialisation constant ORACLE of
    // glsl/refraction/wyman.glsl and hu_qin.glsl, compiled with ORACLE_TRACE).
    ORACLE_EXIT_POINT: u32 = 1;
    ORACLE_EXIT_NORMAL: u32 = 2;
    ORACLE_NEARBY: u32 = 4;

    SPECULAR_MODE_REFRACTION: u32 = 0;
    SPECULAR_MODE_REFLECTION: u32 = 1;
    // raytrace.frag only: every pixel traced from the camera (render.volume = "raytrace").
    RAYTRACE_MODE_FRAME: u32 = 2;

    // Distance impostor probe modes: Hit() against a map, and the conductor Fresnel terms.
    IMPOSTOR_PROBE_HIT: u32 = 0;
    IMPOSTOR_PROBE_FRESNEL: u32 = 1;
    // How the caustics-mapping splat pass weighs each vertex's flux (render.caustics_map.flux).
    FLUX_SOLID_ANGLE: u32 = 0;
    FLUX_OCCLUSION_QUERY: u32 = 1;
    // Intersection estimate (Shah et al. 2007 §III.D): the paper's approximate Newton-Raphson
    // or the true one of the appendix (with the bisection fallback of §III.D against
    // oscillation).
    NEWTON_APPROXIMATE: u32 = 0;
    NEWTON_TRUE: u32 = 1;
    // render.caustics_map.exit: where double-surface refraction leaves the object, by
    // Wyman 2005's d_V/d_N interpolation (Shah et al. 2007 §IV) or a march with bisection.
    CAUSTIC_EXIT_MARCH: u32 = 0;
    CAUSTIC_EXIT_WYMAN: u32 = 1;
    // render.caustics_map.splat: the paper's fixed Gaussian or one sized by the footprint
    // of the neighbouring grid vertices' hits.
    SPLAT_FIXED: u32 = 0;
    SPLAT_FOOTPRINT: u32 = 1;
    // Refractor layer passes (specialisation constant MODE of caustics/refractor.frag).
    CAUSTIC_LAYER_FRONT: u32 = 0;
    CAUSTIC_LAYER_BACK: u32 = 1;
    // Source-face kinds of the vertex grid.
    CAUSTIC_FACE_PERSPECTIVE: u32 = 0;
    CAUSTIC_FACE_ORTHOGRAPHIC: u32 = 1;
    // render.photon_buffer.normalization: irradiance from the photons' power through the
    // normalised filter, or the paper's s * (filtered photon count).
    PHOTON_PHYSICAL: u32 = 0;
    PHOTON_PAPER: u32 = 1;
    // render.eikonal.integrator and light_integrator: forward Euler (Eqs. 11-12, 14-15),
    // classical Runge-Kutta or the explicit midpoint rule.
    EIKONAL_EULER: u32 = 0;
    EIKONAL_RK4: u32 = 1;
    EIKONAL_MIDPOINT: u32 = 2;
    // The view renderer's velocity Verlet of x'' = n grad n (render.eikonal.integrator).
    EIKONAL_VERLET: u32 = 3;
    // Compute workgroup edge of the eikonal volume passes (4^3 invocations).
    EIKONAL_GROUP: u32 = 4;
    // At most MAX_NEARBY_RECTS impostor rectangles of Hu & Qin 2007 §2.2 (the nearest
    // objects are kept); the shader loops over them per ray.
    MAX_NEARBY_RECTS: u32 = 8;
    // Rectangle sets, one per OBJ_R (every dielectric, and the specular objects whose
    // recursive impostor textures look up their own set), each of at most MAX_NEARBY_RECTS.
    MAX_NEARBY_SETS: u32 = 8;
    // Invocations per workgroup of the 1D light/HistoPyramid kernels.
    LIGHT_GROUP: u32 = 64;
    // Levels above the classes that a HistoPyramid may have: a list of up to 4^16 entries.
    HP_MAX_LEVELS: u32 = 16;
    // The exactly intersected flat receivers of eikonal_view, at most.
    MAX_EIKONAL_TRIANGLES: u32 = 64;
}

// Descriptor bindings, in groups. A group's bindings always share one descriptor set, and
// several groups may share one (`descriptor_sets!` below); every group and every listed set
// is checked at compile time for two bindings of one number. A pass's set is the union of
// the groups it names, so the same binding has the same number in every set it is part of.
shared_bindings! {
    // Set 0 of every raster pass (the frame set).
    FRAME_BINDINGS {
        BINDING_FRAME = 0;
        BINDING_MATERIALS = 1;
        BINDING_ENVIRONMENT = 2;
        BINDING_SHADOW_CUBE = 3;
        BINDING_SHADOW_2D = 4;
        // The caustic map atlas (src/technique/caustics/caustics_map.rs), laid out like the
        // shadow atlas: flux per texel in W, looked up by the receivers as a cube or as layers.
        BINDING_CAUSTIC_CUBE = 5;
        BINDING_CAUSTIC_2D = 6;
        // Photon-buffer caustics (Hu & Qin 2007 §3; src/technique/caustics/photon_buffer.rs):
        // the filtered caustic textures TEX_CAUSTICS_i (one array layer per receiver
        // rectangle) and the rectangles; a 1x1 stand-in and one zero rectangle when no photon
        // pass runs.
        BINDING_PHOTON_CAUSTICS = 7;
        BINDING_PHOTON_RECTS = 8;
        // The caustic map's receivers (src/technique/caustics/caustics_map.rs): distance from
        // the light to the nearest diffuse receiver per caustic-map texel, for the lookup's
        // depth test; laid out like the caustic atlas.
        BINDING_CAUSTIC_RECEIVERS_CUBE = 9;
        BINDING_CAUSTIC_RECEIVERS_2D = 10;
    }
    // The G-buffer and HDR inputs of the full-screen passes' set 1.
    GBUFFER_BINDINGS {
        BINDING_GBUF_NORMAL = 0;
        BINDING_GBUF_ALBEDO = 1;
        BINDING_GBUF_DEPTH = 2;
        BINDING_HDR = 3;
    }
    // The adaptive tone map's state (scale, 1/L_white^2, ...) in set 1 of tonemap/adaptive.frag.
    TONEMAP_APPLY_BINDINGS {
        BINDING_TONEMAP_STATE = 4;
    }
    // Set 0 of the adaptive tone map's reduction kernels.
    TONEMAP_BINDINGS {
        TONEMAP_BINDING_HDR = 0;
        TONEMAP_BINDING_PARTIALS = 1;
        TONEMAP_BINDING_STATE = 2;
        TONEMAP_BINDING_STATS = 3;
    }
    // Reference path tracer (src/reference, glsl/reference): one descriptor set.
    REF_BINDINGS {
        REF_BINDING_UNIFORMS = 0;
        REF_BINDING_MATERIALS = 1;
        REF_BINDING_ENVIRONMENT = 2;
        REF_BINDING_VERTICES = 3;
        REF_BINDING_TRIANGLES = 4;
        REF_BINDING_NODES = 5;
        REF_BINDING_SPHERES = 6;
        REF_BINDING_OBJECTS = 7;
        REF_BINDING_ACCUM = 8;
        REF_BINDING_PIXELS = 9;
        REF_BINDING_PHOTONS = 10;
        REF_BINDING_GRID = 11;
        REF_BINDING_COUNTERS = 12;
        REF_BINDING_DEBUG = 13;
        // A volume's voxel fields (glsl/reference/volume.glsl).
        REF_BINDING_VOLUME = 14;
        // The canary's trip count and the cut / step-cap counters (REF_STAT_*).
        REF_BINDING_STATS = 15;
    }
    // Image-space refraction (src/technique/refraction/refractor_layers.rs). Set 1 of the
    // layer passes: the per-vertex d_N storage buffer (Wyman 2005 only); set 1 of the
    // refraction shading passes: the refractor layers, besides BINDING_GBUF_*.
    REFRACTION_BINDINGS {
        BINDING_REFR_DN = 4;
        BINDING_REFR_BACK_NORMAL = 5;
        BINDING_REFR_BACK_DEPTH = 6;
        BINDING_REFR_FRONT_NORMAL = 7;
        BINDING_REFR_FRONT_DEPTH = 8;
        // Per object, its slot in a per-refractor layer (u32::MAX for other objects).
        BINDING_REFR_SLOTS = 9;
    }
    // Distance impostors (Szirmay-Kalos et al. 2005, src/technique/impostor/distance_impostor.rs).
    // Set 1 of the impostor shading passes, besides BINDING_GBUF_NORMAL / _DEPTH: the
    // environment impostor's radiance (rgb, distance in a unless separate) and distance cubes,
    // and the refractor map (xyz outward normal, w distance from the refractor's centre); and
    // the probe kernel's record buffer (glsl/impostor/probe.comp, tests).
    IMPOSTOR_BINDINGS {
        BINDING_IMPOSTOR_RADIANCE = 9;
        BINDING_IMPOSTOR_DISTANCE = 10;
        BINDING_IMPOSTOR_REFRACTOR = 11;
        BINDING_IMPOSTOR_PROBE = 12;
    }
    // Caustics mapping (Shah et al. 2007; src/technique/caustics/caustics_map.rs). Set 0 of
    // the splat-hits pass: the source faces and lights, the materials, the receivers' distance
    // atlas (as a cube array and as layers), the refractor layers seen from the light, and
    // Eq. 6's V per source face (occlusion-query sample counts, u32).
    CAUSTIC_BINDINGS {
        CAUSTIC_BINDING_FACES = 0;
        CAUSTIC_BINDING_MATERIALS = 1;
        CAUSTIC_BINDING_RECEIVER_CUBE = 2;
        CAUSTIC_BINDING_RECEIVER_2D = 3;
        CAUSTIC_BINDING_FRONT_POSITION = 4;
        CAUSTIC_BINDING_FRONT_NORMAL = 5;
        CAUSTIC_BINDING_BACK_POSITION = 6;
        CAUSTIC_BINDING_BACK_NORMAL = 7;
        CAUSTIC_BINDING_VISIBLE = 9;
        // The refractor layers' own set: Wyman's d_N per scene vertex (f32).
        CAUSTIC_BINDING_DN = 11;
        // Each caustic-atlas layer's world -> clip matrix (mat4; zero where the layer is not
        // drawn), and the splat record of every grid vertex (GpuCausticSplat).
        CAUSTIC_BINDING_DESTINATIONS = 12;
        CAUSTIC_BINDING_SPLATS = 13;
        // Which layers the records reach (src/technique/caustics/caustics_map.rs,
        // `SplatLayers`): per atlas layer the records counted into it this frame (u32) and its
        // light's records (uvec2: first, count); and, written by
        // glsl/caustics/splat_layers.comp, per layer the splat draw's and the clear draw's
        // VkDrawIndirectCommand (uvec4) and the count its last drawn frame had (u32).
        CAUSTIC_BINDING_COUNTS = 14;
        CAUSTIC_BINDING_SPANS = 15;
        CAUSTIC_BINDING_SPLAT_DRAWS = 16;
        CAUSTIC_BINDING_CLEAR_DRAWS = 17;
        CAUSTIC_BINDING_SEEN = 18;
    }
    // Photon buffer (Hu & Qin 2007 §3.1): the receiver rectangles, besides the caustic
    // bindings (faces, materials, refractor layers).
    PHOTON_BINDINGS {
        PHOTON_BINDING_RECTS = 8;
        // TEX_DEPTH_i of §2.2.2 per rectangle: each receiver's signed distance from its
        // rectangle's plane along O_R O_i, for the photon's depth correction (Fig. 16).
        PHOTON_BINDING_RECEIVER_DEPTH = 10;
    }
    // Light-map caustics with distance impostors (Szirmay-Kalos et al. 2005 §5;
    // src/technique/impostor/impostor_lightmap.rs). Set 1 of the caustic-map pass: the uv
    // cube map, filtered (its distance, for Hit()) and unfiltered (uv and receiver id), and
    // the refractor map, and the specular surfaces seen from the light (position and
    // material + 1, normal); set 0 of the splat pass: the caustic map's two targets.
    LIGHTMAP_BINDINGS {
        LIGHTMAP_BINDING_UV_LINEAR = 0;
        LIGHTMAP_BINDING_UV_NEAREST = 1;
        LIGHTMAP_BINDING_REFRACTOR = 2;
        LIGHTMAP_BINDING_PHOTON_HIT = 3;
        LIGHTMAP_BINDING_PHOTON_POWER = 4;
        LIGHTMAP_BINDING_SURFACE_POSITION = 5;
        LIGHTMAP_BINDING_SURFACE_NORMAL = 6;
        // Per light map: the texels its splats and their bilinear lookup can reach (u32 x 4:
        // lowest column, lowest row, u32::MAX - highest column, u32::MAX - highest row).
        LIGHTMAP_BINDING_REACH = 7;
    }
    // The light maps in set 1 of the apply pass (besides BINDING_GBUF_*).
    LIGHTMAP_APPLY_BINDINGS {
        BINDING_LIGHTMAPS = 14;
        // The light maps' reach (LIGHTMAP_BINDING_REACH), read by the vertex shader.
        BINDING_LIGHTMAP_REACH = 15;
    }
    // Hu & Qin 2007 §2.2 nearby geometry (src/technique/refraction/nearby_impostors.rs): the
    // impostor rectangles (storage buffer) and TEX_i / TEX_DEPTH_i (2D array: rgb radiance, a
    // axial depth), in set 1 of refraction_hu_qin and eikonal_view; in set 1 of the
    // impostor-texture passes also the dielectric OBJ_k's nearest back faces in each
    // rectangle's parallel projection (2D array: xyz outward normal, w axial depth) and
    // their nearest front faces, the same layout (recursive_exit = "full").
    NEARBY_BINDINGS {
        BINDING_NEARBY_RECTS = 14;
        BINDING_NEARBY_TEXTURE = 15;
        BINDING_NEARBY_BACK = 16;
        BINDING_NEARBY_FRONT = 17;
    }
    // Eikonal rendering (Ihrke et al. 2007; src/technique/eikonal/eikonal_view.rs): the volume
    // compute passes read EIKONAL_BINDING_SRC and write EIKONAL_BINDING_DST (storage images).
    EIKONAL_VOLUME_BINDINGS {
        EIKONAL_BINDING_SRC = 0;
        EIKONAL_BINDING_DST = 1;
    }
    // The probe of the device's linear filter (glsl/eikonal/filter_probe.comp;
    // src/technique/eikonal/eikonal_view.rs `filters_in_full_precision`): two texels and
    // the error of each sample between them.
    FILTER_PROBE_BINDINGS {
        BINDING_FILTER_PROBE_TEXELS = 0;
        BINDING_FILTER_PROBE_ERRORS = 1;
    }
    // Set 1 of eikonal_view, besides BINDING_GBUF_DEPTH: the field (grad n, n - 1), the
    // material volumes of src/scene/volume_sources.rs ((extinction RGB, HG g), (albedo RGB,
    // reflectance), (emission RGB, boundary band)) and the triangles of the exactly
    // intersected flat receivers (§6, Fig. 7; src/technique/eikonal/eikonal_nearby.rs).
    EIKONAL_VIEW_BINDINGS {
        BINDING_EIKONAL_FIELD = 13;
        BINDING_EIKONAL_EXTINCTION = 20;
        BINDING_EIKONAL_ALBEDO = 21;
        BINDING_EIKONAL_EMISSION = 22;
        BINDING_EIKONAL_TRIANGLES = 25;
        // The march map: per voxel (x fastest) the boundary band's reflectance factor (f32,
        // -1 outside the band) whose eight lowest mantissa bits hold the weak-gradient reach
        // of the merged steps (src/technique/eikonal/volume.rs, `march_map`).
        BINDING_EIKONAL_MARCH = 27;
    }
    // Set 1 of refraction_water, besides the tracer's REF_BINDINGS and BINDING_GBUF_ALBEDO /
    // _DEPTH: the environment's SH coefficients as seen from under the water
    // (src/frame/gpu_scene.rs, environment_sh_below), and the G-buffer's normals, whose own
    // binding is the tracer's uniforms' there.
    WATER_BINDINGS {
        BINDING_WATER_SKY = 15;
        BINDING_WATER_GBUF_NORMAL = 16;
    }
    // The light simulation's irradiance and direction volumes, sampled by eikonal_view, its
    // receiver pass and the nearby impostors around the volume.
    EIKONAL_LIGHT_VOLUME_BINDINGS {
        BINDING_EIKONAL_IRRADIANCE = 23;
        BINDING_EIKONAL_LIGHT_DIR = 24;
    }
    // Eikonal light simulator (Ihrke et al. 2007 section 5.2; src/technique/eikonal/eikonal_light.rs,
    // src/technique/eikonal/histopyramid.rs): set 0 of every HistoPyramid kernel (STATE to
    // HISTORY) and set 1 of the light kernels; the accumulator is the additive irradiance
    // accumulator (r32ui 3D image, six slabs along y); BAND and REFLECTANCE the view renderer's
    // boundary band and reflectance factor, for the Fresnel loss.
    LIGHT_BINDINGS {
        LIGHT_BINDING_STATE = 0;
        LIGHT_BINDING_CLASSES = 1;
        LIGHT_BINDING_LEVELS = 2;
        LIGHT_BINDING_PAIRS = 3;
        LIGHT_BINDING_HISTORY = 4;
        LIGHT_BINDING_SRC = 5;
        LIGHT_BINDING_DST = 6;
        LIGHT_BINDING_FIELD = 7;
        LIGHT_BINDING_ACCUM = 8;
        LIGHT_BINDING_IRRADIANCE = 10;
        LIGHT_BINDING_DIRECTION = 11;
        LIGHT_BINDING_EXTINCTION = 12;
        LIGHT_BINDING_SPILL = 13;
        LIGHT_BINDING_AIR_FACES = 14;
        LIGHT_BINDING_AIR_SKIP = 15;
        LIGHT_BINDING_BAND = 16;
        LIGHT_BINDING_REFLECTANCE = 17;
        // The view renderer's uniform-region map (u32 per brick; src/technique/eikonal/volume.rs),
        // for the straight steps of glsl/eikonal/light_step.glsl.
        LIGHT_BINDING_BRICKS = 18;
        // Where the volumes are read: one bit per voxel of the irradiance volume
        // (src/technique/eikonal/read_mask.rs).
        LIGHT_BINDING_READ_MASK = 19;
        // The source list again as RGBA32UI texels (eight per patch), which the step, commit
        // and expansion kernels read their patch through: one gather per texel on a CPU
        // device, where a storage-buffer load is a loop over the lanes.
        LIGHT_BINDING_SRC_TEXELS = 20;
    }
    // The window's water animation (glsl/common/heightfield.comp; src/frame/heightfield.rs):
    // one set 0.
    HEIGHTFIELD_BINDINGS {
        HEIGHTFIELD_BINDING_FIELDS = 0;
        HEIGHTFIELD_BINDING_WAVES = 1;
        HEIGHTFIELD_BINDING_VERTICES = 2;
    }
    // The raytrace technique's running mean (glsl/raytrace/accumulate.comp;
    // src/technique/raytrace.rs): one set 0.
    ACCUMULATE_BINDINGS {
        ACCUMULATE_BINDING_HDR = 0;
        ACCUMULATE_BINDING_MEAN = 1;
    }
}

// The descriptor sets made of several groups.
descriptor_sets! {
    // Set 1 of tonemap/adaptive.frag.
    TONEMAP_APPLY_SET = [GBUFFER_BINDINGS, TONEMAP_APPLY_BINDINGS];
    // Set 1 of the refractor layer passes and of refraction_wyman / refraction_hu_qin.
    REFRACTION_SET = [GBUFFER_BINDINGS, REFRACTION_BINDINGS, NEARBY_BINDINGS];
    // Set 1 of the distance impostor shading passes.
    IMPOSTOR_SET = [GBUFFER_BINDINGS, IMPOSTOR_BINDINGS];
    // Set 1 of the light-map apply pass.
    LIGHTMAP_APPLY_SET = [GBUFFER_BINDINGS, LIGHTMAP_APPLY_BINDINGS];
    // Set 0 of the photon-buffer passes.
    PHOTON_SET = [CAUSTIC_BINDINGS, PHOTON_BINDINGS];
    // Set 1 of eikonal_view and of its light receiver pass.
    EIKONAL_VIEW_SET = [GBUFFER_BINDINGS, EIKONAL_VIEW_BINDINGS, NEARBY_BINDINGS, EIKONAL_LIGHT_VOLUME_BINDINGS];
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
    // The caustic lookup's depth test against the caustic map's receivers (deferred.frag):
    // the point is pushed towards the light by this many texel footprints, the shadow maps'
    // bias (src/frame/gpu_scene.rs), so that a lit receiver does not hide itself.
    CAUSTIC_DEPTH_BIAS_TEXELS: f32 = 1.5;
    // The procedural `grid` environment (../shared/SCENES.md; src/scene/environment.rs
    // `grid_radiance`, glsl/include/common.glsl): lines of radiance GRID_LINE_RADIANCE within
    // GRID_LINE_HALF_WIDTH_DEG of every multiple of GRID_SPACING_DEG of longitude and latitude.
    GRID_SPACING_DEG: f32 = 15.0;
    GRID_LINE_HALF_WIDTH_DEG: f32 = 0.5;
    GRID_LINE_RADIANCE: f32 = 2.0;
    // The environment texture's alpha that stands for the grid: its 1x1 stand-in carries it
    // (src/frame/gpu_scene.rs), and the lookup evaluates the formula instead of sampling. Every
    // other environment texel has alpha 1.
    ENVIRONMENT_GRID_ALPHA: f32 = -1.0;
}

// Colours, written into the GLSL header as vec3 literals.
shared_rgb! {
    // The grid's sky at the horizon and at the zenith (mixed by d.y), and its ground.
    GRID_SKY_HORIZON = [0.8, 0.85, 0.9];
    GRID_SKY_ZENITH = [0.25, 0.45, 0.9];
    GRID_GROUND = [0.3, 0.25, 0.2];
}
