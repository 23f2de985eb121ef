// The structs shared by Rust and GLSL: push constants and the records of uniform and storage
// buffers, declared once (../shared/DESIGN.md, rule 7).
//
// This file is `include!`d twice: by the library (src/lib.rs, module `shader_structs`, where
// the macro makes `#[repr(C)]` Pod structs checked at compile time against the GLSL layout
// of their kind) and by build.rs (where it emits the GLSL `struct`s, with these comments,
// into the generated header `prism_shared.glsl`). Member types are GLSL's: `float`, `uint`,
// `vec4`, `mat4` (column-major, four vec4 columns), another struct here, or `[T; N]` for an
// array; in Rust they are scalars and arrays of them (`vec4` is `[f32; 4]`). The kind is
// the block the struct is read through: `push` (push constants, std430, at most 128 bytes),
// `buffer` (storage blocks, std430) or `uniform` (std140 and std430 alike). A block wraps the
// struct in GLSL (`layout(push_constant) uniform MapPushBlock { MapPush pc; };`), so its
// members keep their names in both languages.
shared_structs! {
    // ---- The frame set (glsl/include/frame.glsl, src/frame) ----------------------------

    /// A mesh vertex: the raster passes read it as vertex attributes, the exact tracer as two
    /// RGBA32UI texels and the water animation as a storage buffer (scalar arrays keep it 32
    /// bytes in std430).
    #[derive(Default)]
    buffer struct Vertex {
        position: [float; 3],
        normal: [float; 3],
        checker_uv: [float; 2],
    }

    #[derive(Default)]
    uniform struct GpuLight {
        /// xyz: position (point) or unit direction light -> scene (directional); w: kind
        position: vec4,
        /// rgb: intensity W/sr (point) or irradiance W/m^2 (directional); w: first shadow layer
        intensity: vec4,
        /// x: near, y: far, z: normal-offset bias per metre of distance, w: 1/resolution
        shadow: vec4,
        /// directional: origin of the distance plane
        origin: vec4,
        /// directional: world -> orthographic light clip space
        view_proj: mat4,
    }

    /// The frame's uniform block (set 0, BINDING_FRAME).
    uniform struct FrameUniforms {
        view: mat4,
        proj: mat4,
        view_proj: mat4,
        inv_view_proj: mat4,
        inv_view: mat4,
        /// w: exposure
        camera_position: vec4,
        /// x: near plane distance of the reversed-Z infinite projection
        clip: vec4,
        /// w, h, 1/w, 1/h
        viewport: vec4,
        /// irradiance SH (Ramamoorthi & Hanrahan 2001), rgb
        env_sh: [vec4; 9],
        /// x: light count, y: frame index
        info: uvec4,
        lights: [GpuLight; MAX_LIGHTS],
    }

    #[derive(Default)]
    buffer struct GpuMaterial {
        /// diffuse: rgb albedo (or checker colour a); w: kind
        albedo_a: vec4,
        /// checker colour b; w: checker size in metres (0: constant albedo)
        albedo_b: vec4,
        /// dielectric: rgb ior | mirror: rgb reflectance | conductor: rgb eta
        spec_a: vec4,
        /// dielectric: rgb absorption per metre | conductor: rgb k
        spec_b: vec4,
    }

    /// Push constants of the shadow pass (glsl/shadow/shadow.{vert,frag}).
    push struct ShadowPush {
        /// world -> face clip space
        view_proj: mat4,
        /// xyz: position (point) or direction (directional); w: kind
        light: vec4,
        /// directional: origin of the distance plane
        origin: vec4,
    }

    /// One heightfield of the window's water animation (glsl/common/heightfield.comp).
    #[derive(Default)]
    buffer struct GpuHeightfield {
        transform: mat4,
        /// The inverse transpose of the transform's upper 3x3, for the normals.
        normal_matrix: mat4,
        /// xyz; w unused
        center: vec4,
        /// size x, size z, cells nx, cells nz
        size_cells: vec4,
        /// first vertex, first wave, wave count, unused
        ranges: uvec4,
    }

    push struct HeightfieldPush {
        field: uint,
        time: float,
    }

    /// Push constants of glsl/raytrace/accumulate.comp (src/technique/raytrace.rs).
    push struct AccumulatePush {
        /// The frames blended before this one since the last change (0: the frame itself).
        frames: uint,
        /// `render.raytrace.accumulate`: from this many frames on the mean is held.
        limit: uint,
        /// The image's width and height.
        width: uint,
        height: uint,
    }

    /// Push constants of glsl/common/cover.vert: the proxy sphere drawn over an object's
    /// pixels (src/technique/baseline/fullscreen.rs, `Cover`).
    push struct CoverPush {
        /// The octagon's centre (xyz), and its two half-axes u and v in its plane: corner k
        /// is centre + cos(k pi / 4) u + sin(k pi / 4) v.
        centre: vec4,
        u: vec4,
        v: vec4,
    }

    /// Push constants of the G-buffer pass (glsl/gbuffer/gbuffer.frag).
    push struct GbufferPush {
        material: uint,
        object: uint,
    }

    // ---- Tone map (src/technique/baseline/tonemap.rs) ------------------------------------

    /// Push constants of glsl/tonemap/log_average.comp and adapt.comp.
    #[derive(Default)]
    push struct AdaptPush {
        /// width, height, workgroups of log_average, frame slot (stats entry)
        size: uvec4,
        /// dt in s (< 0: converged, no temporal state), delta, key (<= 0: auto), white (<= 0: auto)
        params: vec4,
        /// tau_rod, tau_cone, luminance_scale (cd/m^2 per unit), exposure
        params2: vec4,
    }

    // ---- Distance impostors (src/technique/impostor) -------------------------------------

    /// Push constants of the impostor map passes (glsl/impostor/map_push.glsl).
    push struct MapPush {
        /// world -> clip space of one cube face
        view_proj: mat4,
        /// xyz: the map's reference point o
        reference: vec4,
        /// x: the draw's material index; y: uv map: light-map slot + 1 (0: no light map)
        material: uvec4,
        /// uv map: light-map u = dot(chart_u.xyz, p) + chart_u.w (p: world position)
        chart_u: vec4,
        /// uv map: light-map v = dot(chart_v.xyz, p) + chart_v.w
        chart_v: vec4,
    }

    /// Push constants of the impostor shading passes (glsl/impostor/shade_common.glsl).
    push struct ShadePush {
        /// xyz: reference point o of the environment impostor
        env_reference: vec4,
        /// xyz: centre of the refractor map (refraction only)
        refractor_center: vec4,
        /// x: the object whose map this draw uses, or ALL_OBJECTS (shared map)
        object: uvec4,
    }

    /// Push constants of glsl/impostor/probe.comp.
    push struct ImpostorProbePush {
        /// xyz: the map's reference point
        reference: vec4,
        /// x: record count, y: mode
        info: uvec4,
    }

    /// Push constants of the caustic-map pass of light-map caustics
    /// (glsl/impostor/lightmap_push.glsl).
    push struct CausticPush {
        /// world -> the light's clip space (fitted to the specular objects)
        view_proj: mat4,
        /// xyz: point light position or unit direction of travel; w: LIGHT_*
        light: vec4,
        /// rgb: I (W/sr, point) or E (W/m^2, directional); w: the material index of the object
        /// drawn (glsl/impostor/lightmap_surface.frag)
        intensity: vec4,
        /// xyz: reference point o of the uv map; w: tan(half angle) or half side (m)
        reference: vec4,
        /// xyz: centre of the refractor map; w: caustic map size (texels)
        refractor: vec4,
    }

    /// Push constants of glsl/impostor/lightmap_splat.{vert,frag}.
    push struct LightmapSplatPush {
        /// x: filter radius (light-map texels), y: light-map size, z: 1 / texel area (m^-2)
        params: vec4,
        /// x: this light map's slot, y: caustic map size
        info: uvec4,
    }

    /// Push constants of glsl/impostor/lightmap_apply.frag.
    push struct LightmapApplyPush {
        /// xyz: the chart's (u, v) = (0, 0) corner; w: light-map slot
        origin: vec4,
        /// xyz: edge to u = 1, w: object index
        edge_u: vec4,
        /// xyz: edge to v = 1
        edge_v: vec4,
    }

    // ---- Caustics mapping and the photon buffer (src/technique/caustics) -----------------

    /// One source face of the vertex grid (glsl/caustics/splat_hits.comp, photon_buffer.frag).
    buffer struct GpuCausticFace {
        /// world -> source face clip space (the refractor textures)
        view_proj: mat4,
        /// directional: world -> the light's orthographic map
        receiver_view_proj: mat4,
        /// xyz: position (point) or unit direction (directional); w: kind
        light: vec4,
        /// rgb: I in W/sr (point) or E in W/m^2 (directional); w: first atlas layer
        intensity: vec4,
        /// x: face kind, y: tan(half angle) or half extent (m), z: grid size,
        /// w: largest chord of the specular objects (m)
        measure: vec4,
        /// directional: origin of the receivers' distance plane
        origin: vec4,
    }

    /// Push constants of glsl/caustics/refractor.{vert,frag}.
    push struct RefractorPush {
        /// world -> source face clip space
        view_proj: mat4,
        /// xyz: position (point) or unit direction (directional); w: kind
        light: vec4,
        /// x: material index of the draw
        info: uvec4,
    }

    /// Push constants of glsl/caustics/splat_hits.comp.
    push struct CausticHitsPush {
        /// x: source faces (all lights'), y: channels, z: vertices per channel and face
        /// (grid^2), w: unused
        face: uvec4,
        /// x: splat sigma (texels), y: iterations, z: NEWTON_*, w: map size (texels)
        params: vec4,
    }

    /// One grid vertex's splat, computed once by glsl/caustics/splat_hits.comp and drawn by
    /// glsl/caustics/splat.vert into the caustic-atlas layer it lands in.
    buffer struct GpuCausticSplat {
        /// xyz: the hit in the destination layer's normalised device coordinates; w: that
        /// layer (-1: dropped)
        position: vec4,
        /// rgb: flux (W) divided by the splat's weight sum; w: sigma (texels)
        flux: vec4,
    }

    /// Push constants of glsl/caustics/splat.vert.
    push struct CausticDrawPush {
        /// x: the caustic-atlas layer drawn, y: unused, z: map size (texels), w: unused
        dest: uvec4,
    }

    /// A receiver rectangle RECT_i of Hu & Qin 2007 §2.2.1 (Fig. 12-13), as the photon-buffer
    /// caustics (§3) use it (glsl/include/photon_rect.glsl).
    buffer struct GpuPhotonRect {
        /// world -> RECT_i's parallel projection from O_R along O_R O_i (glOrtho(-d, d, -d, d)),
        /// clip xy in [-1, 1] on the rectangle
        view_proj: mat4,
        /// xyz: unit O_R -> O_i, the rectangle's normal and the projection's direction; w: d_i
        /// (half the side)
        axis: vec4,
        /// xyz: O_i; w: radius of the receiver object around O_i (m)
        centre: vec4,
        /// x: the receiver's object index (deferred shading picks the rectangle of the object
        /// the G-buffer names at each pixel); yzw unused
        object: uvec4,
    }

    /// Push constants of glsl/caustics/photon_buffer.frag.
    push struct PhotonBufferPush {
        /// x: source face, y: photon buffer size, z: rectangles, w: depth-correction
        /// iterations (§2.2.2, Fig. 16)
        info: uvec4,
    }

    /// Push constants of glsl/caustics/photon_scatter.vert.
    push struct PhotonScatterPush {
        /// x: photon buffer size, y: source faces, z: this layer's k (rectangle index + 1),
        /// w: the filter's k (§3.2)
        info: uvec4,
        /// x: PHOTON_PAPER: s; PHOTON_PHYSICAL: texel area on the rectangle (m^2); y: the
        /// kernel's weight sum W, z: caustic texture size (texels), w: PHOTON_PHYSICAL or
        /// PHOTON_PAPER
        params: vec4,
        /// x: with `merge_texels`, the power of one step of the texel sums' 64-bit fixed
        /// point (W; glsl/caustics/photon_bin.comp); yzw unused
        sum_unit: vec4,
    }

    // ---- Hu & Qin 2007 nearby impostors (src/technique/refraction/nearby_impostors.rs) ---

    /// One impostor rectangle (glsl/include/nearby.glsl).
    buffer struct GpuNearbyRect {
        /// world -> clip of glOrtho(-d_i, d_i, -d_i, d_i, near, far) from O_R to O_i
        view_proj: mat4,
        /// xyz: O_i; w: d_i (half the square's side)
        center: vec4,
        /// xyz: unit O_R -> O_i (rectangle normal, projection direction); w: near
        axis: vec4,
        /// xyz: world direction of growing u; w: far (TEX_DEPTH of empty texels)
        axis_u: vec4,
        /// xyz: world direction of growing v (the shared up vector); w: layer
        axis_v: vec4,
    }

    /// Header of the rectangle buffer, followed by the rectangles of every set.
    buffer struct GpuNearbyHeader {
        /// x: rectangles over all sets, y: sets (0: environment only)
        info: uvec4,
        /// x: first rectangle, y: count, z: OBJ_R's object index (the G-buffer's albedo.a),
        /// w: bit k set when the set's rectangle first + k is a dielectric whose texture
        /// refracts the environment only (ranked last by the nearest lookup)
        sets: [uvec4; MAX_NEARBY_SETS],
        /// xyz: O_R of the set
        origins: [vec4; MAX_NEARBY_SETS],
    }

    /// Push constants of the impostor-texture passes (glsl/nearby/push.glsl).
    push struct NearbyImpostorPush {
        /// world -> clip of glOrtho(-d_i, d_i, -d_i, d_i, near, far) from O_R to O_i
        view_proj: mat4,
        /// xyz: O_R, the centre of the refractor the rectangle's set belongs to
        origin: vec4,
        /// xyz: unit O_R -> O_i, the direction of projection
        axis: vec4,
        /// x: the object's material index, y: its layer, z: its own rectangle set (the
        /// recursive levels look it up; ~0u: none, the environment)
        material: uvec4,
        /// xyz: O_k, w: d_k: OBJ_k's bounding sphere (a dielectric's second interface)
        sphere: vec4,
    }

    // ---- Eikonal rendering (src/technique/eikonal) ---------------------------------------

    /// One triangle of an exactly intersected receiver (glsl/eikonal/nearby_exit.glsl).
    #[derive(Default, PartialEq)]
    buffer struct GpuTriangle {
        /// xyz: p0
        p0: vec4,
        /// xyz: p1 - p0
        e1: vec4,
        /// xyz: p2 - p0
        e2: vec4,
        /// checker uv of p0 (xy) and p1 (zw)
        uv01: vec4,
        /// checker uv of p2 (xy); z: material index (as a float, exact below 2^24)
        uv2: vec4,
    }

    /// One wavefront patch (Ihrke et al. 2007 section 5.2: "patches ... hold the four
    /// corners' positions, their propagation directions and a RGB energy value"), 128 bytes:
    /// every step reads and writes it, and the output generator copies it. Corners 0..3 go
    /// around the patch so that cross(x2 - x0, x3 - x1) points along the propagation
    /// direction at birth. The four w components carry the rest (accessors in
    /// src/technique/eikonal/eikonal_light.rs and glsl/eikonal/light_common.glsl):
    /// x[0..3].w the flux R, G, B, the energy dE * A of Eq. 17 (W), constant unless absorbed
    /// (Eq. 18); x[3].w the initial particles among the corners, for tests that follow them
    /// (P * 8 + code: code 4, corner c is particle 4P + c; code k < 4, corner k is particle
    /// 4P + k and the others were created by tessellation; 5, none); v[0].w the steps taken
    /// in its run (its parent's before it was tessellated) times 128 plus the substep mark of
    /// the paper's voxelization; v[1..3].w the Fresnel run in progress (light_step.glsl).
    /// All are integers below 2^24 where they are counts, so exact in f32.
    #[derive(Default, PartialEq)]
    buffer struct Patch {
        /// corner positions; w: see above
        x: [vec4; 4],
        /// corner optical directions v = n dx/ds, |v| = n; w: see above
        v: [vec4; 4],
    }

    /// One face of a light's initial wavefront whose patches that only cross air were not
    /// simulated (`render.eikonal.skip_air`): light_resolve.glsl adds their light in closed
    /// form (src/technique/eikonal/eikonal_light.rs `WavefrontFace`).
    #[derive(Default)]
    buffer struct AirFace {
        /// xyz: the point light's position, or the directional wavefront's centre; w: 0 point,
        /// 1 directional
        origin: vec4,
        /// xyz: the face's axis (the direction of travel of a directional light); w: tan of the
        /// half-angle (point) or the half-width in metres (directional)
        axis: vec4,
        /// xyz: the first tangent; w: patches per side k
        t1: vec4,
        /// xyz: the second tangent; w: index of the face's first k x k skip flag
        t2: vec4,
        /// rgb: intensity W/sr (point) or irradiance W/m^2 (directional); w: the radius the
        /// point light's patches start at
        power: vec4,
    }

    /// Per run of the light simulator (one light, one index channel, one tile of the initial
    /// wavefront; glsl/eikonal/light_common.glsl).
    #[derive(Default)]
    push struct RunPush {
        /// index slab of `field` the wavefront travels through (dispersion)
        slab: uint,
        /// +1: deposit; -1: take a run's deposits back (an overflowing tile)
        sign: float,
        /// energy threshold in W (section 5.2.3, patch termination)
        min_flux: float,
        /// steps a patch may take in the run (its step count is in `Patch::v[0].w`)
        max_steps: uint,
        /// which of the step kernel's dispatches between two compactions this is (0: the
        /// first, which steps every patch of the list)
        substep: uint,
    }

    /// The HistoPyramid's state (glsl/eikonal/histopyramid.glsl).
    #[derive(Default, PartialEq, Eq)]
    buffer struct HpState {
        /// vkCmdDispatchIndirect groups over `next` (x, 1, 1) and one unused word
        args: uvec4,
        /// entries of level 0 that are valid (the input list's length; set to `next` by
        /// histopyramid_total.comp for the next step)
        count: uint,
        /// outputs of the last step (min(total, CAPACITY))
        next: uint,
        /// outputs lost to the capacity clamp, summed over the steps
        dropped: uint,
        /// steps taken (the history index)
        step: uint,
        /// the largest `next` so far
        peak: uint,
        /// the last unclamped total
        requested: uint,
        /// patches in the spill list: outputs past the list's capacity, continued by a later
        /// run instead of dropped
        spilled: uint,
        /// of them, the last build's (they follow its `next` outputs)
        spill_new: uint,
        /// patches advanced by one step, summed over the run's dispatches (with several steps
        /// per dispatch the list lengths no longer count them)
        advanced: uint,
        /// keeps `out_args` on its 16-byte boundary (std430)
        pad: [uint; 3],
        /// vkCmdDispatchIndirect groups over `next + spill_new` (the traversal and the
        /// output generator) and one unused word
        out_args: uvec4,
        /// vkCmdDispatchIndirect groups of the reduction of level k + 1 over the entries that
        /// `count` makes live on it (ceil(count / 4^(k+1))), so that the build costs what
        /// the live list costs, not the capacity
        level_args: [uvec4; HP_MAX_LEVELS],
    }

    // ---- The reference path tracer (src/reference, glsl/reference) -----------------------

    buffer struct RefLight {
        /// xyz: position (point) or unit direction light -> scene (directional); w: kind
        position: vec4,
        /// rgb: W/sr (point) or W/m^2 (directional)
        intensity: vec4,
    }

    /// The tracer's parameters, read as a storage block (glsl/reference/trace.glsl `ref`).
    buffer struct RefUniforms {
        /// camera to world
        inv_view: mat4,
        camera_pos: vec4,
        /// x: tan(fov_x / 2), y: tan(fov_y / 2), z: ray epsilon, w: scene radius
        proj: vec4,
        /// x: width, y: height, z: light count, w: sphere count
        dims: uvec4,
        /// x: triangles, y: BVH nodes, z: photon targets, w: max specular bounces
        counts: uvec4,
        /// x: photons per iteration, y: photon capacity, z: grid table size, w: flags
        photon: uvec4,
        /// x: cell size, y: largest initial radius, z: SPPM alpha; w: initial radius in pixel
        /// footprints (reference), branch cutoff (raytrace technique)
        grid: vec4,
        lights: [RefLight; MAX_LIGHTS],
        /// specular objects' bounding spheres (centre, radius)
        targets: [vec4; REF_MAX_TARGETS],
        /// The scene's `[volume]`, see glsl/reference/volume.glsl (volume[0].w = 0: none).
        volume: [vec4; 6],
    }

    /// Push constants of the reference kernels (glsl/reference/scene.glsl).
    push struct RefPush {
        iteration: uint,
        seed: uint,
        /// test kernels: what to do
        mode: uint,
        /// test kernels: number of inputs
        count: uint,
    }

    /// Stochastic progressive photon mapping's per-pixel state (glsl/reference/sppm.glsl).
    #[derive(Default)]
    buffer struct PixelState {
        /// accumulated flux tau (rgb) and photon count N
        tau_n: vec4,
        /// this iteration's visible point; w: gathering radius R
        vp_pos: vec4,
        /// its normal, facing the camera path; w: 1 if there is one
        vp_normal: vec4,
        /// camera path throughput times the diffuse BRDF, beta * albedo / pi
        vp_weight: vec4,
    }

    /// An exactly intersected sphere (glsl/reference/trace.glsl).
    buffer struct GpuSphere {
        /// xyz: centre, w: radius
        center_radius: vec4,
        /// x: object index
        info: uvec4,
    }

    /// A node of the triangles' bounding volume hierarchy.
    #[derive(Default, PartialEq)]
    buffer struct BvhNode {
        lo: vec3,
        /// Leaf: first triangle. Interior: the node after its subtree (src/reference/bvh.rs).
        index: uint,
        hi: vec3,
        /// Triangle count; 0 for an interior node.
        count: uint,
    }
}
