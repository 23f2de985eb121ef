// Shared by the eikonal light simulator's kernels (Ihrke et al. 2007, section 5.2;
// src/technique/eikonal/eikonal_light.rs): the wavefront patch list, the smoothed index field, the
// irradiance and direction volumes. Set 0 is the HistoPyramid (histopyramid.glsl).
#include "histopyramid.glsl"


layout(std430, set = 1, binding = LIGHT_BINDING_SRC) buffer Src { Patch src[]; };
layout(std430, set = 1, binding = LIGHT_BINDING_DST) buffer Dst { Patch dst[]; };
// Outputs past the list's capacity (histopyramid_total.comp), continued by a later run.
layout(std430, set = 1, binding = LIGHT_BINDING_SPILL) buffer Spill { Patch spill[]; };
// The source list again as RGBA32UI texels, eight per patch (x[0..3], then v[0..3]; floats by
// their bits). The kernels read their patch through it: a CPU device (lavapipe) loads a
// storage buffer at a per-invocation index lane by lane and component by component, a texel
// in one gather (the step kernel 0.72-0.85x at 128^3, docs/BENCHMARKS.md). Writes stay
// storage-buffer stores.
layout(set = 1, binding = LIGHT_BINDING_SRC_TEXELS) uniform usamplerBuffer src_texels;

// src[i], read through src_texels.
Patch src_patch(uint i) {
    Patch p;
    for (int k = 0; k < 4; ++k) {
        p.x[k] = uintBitsToFloat(texelFetch(src_texels, 8 * int(i) + k));
        p.v[k] = uintBitsToFloat(texelFetch(src_texels, 8 * int(i) + 4 + k));
    }
    return p;
}

// xyz: grad n per metre, w: n - 1 (glsl/eikonal/gradient.comp), over the VOLUME's box.
layout(set = 1, binding = LIGHT_BINDING_FIELD) uniform sampler3D field;
// (sigma_a + sigma_s RGB per metre, HG g) of src/scene/volume_sources.rs, over the VOLUME's box.
layout(set = 1, binding = LIGHT_BINDING_EXTINCTION) uniform sampler3D extinction_map;
// The view renderer's boundary band (alpha of its emission volume) and the reflectance
// factor (alpha of its albedo volume), over the VOLUME's box: the Fresnel loss (light_step.glsl).
layout(set = 1, binding = LIGHT_BINDING_BAND) uniform sampler3D band_map;
layout(set = 1, binding = LIGHT_BINDING_REFLECTANCE) uniform sampler3D reflectance_map;
// The additive accumulator of the track-length irradiance estimate (light_step.glsl): per
// voxel of the irradiance volume six f32 sums, in six slabs along y: 0..2 the scalar
// irradiance R, G, B (W/m^2), 3..5 the vector irradiance sum_j (E_r + E_g + E_b)_j l_j;
// with DIRECTION_NEAREST the vector sum of the deposits centred in the voxel, and a seventh
// slab, 6, their weight sum_j (E_r + E_g + E_b)_j. light_resolve.glsl turns it into the two
// volumes below. With ACCUM_FLOAT_ATOMICS an
// R32_SFLOAT image added to by float atomics; without, the f32 bits in an R32_UINT image
// added to by a compare-and-swap loop (`accum_add`). With HIGHEST_ENERGY (always R32_UINT)
// the slabs hold one ray per voxel instead: 0..2 its dE R, G, B, 3..5 its unit direction,
// and a seventh slab, 6, its energy dE_r + dE_g + dE_b as f32 bits, which order like the
// values for positive floats, so that imageAtomicMax keeps the highest (`voxel_sample`).
#ifdef ACCUM_FLOAT_ATOMICS
layout(set = 1, binding = LIGHT_BINDING_ACCUM, r32f) uniform image3D accum;
#else
layout(set = 1, binding = LIGHT_BINDING_ACCUM, r32ui) uniform uimage3D accum;
#endif
// rgb: irradiance sum_j dE_omega,j (W/m^2) of every ray through the voxel (Eqs. 6-7 sum
// over j); a: 1 where lit.
layout(set = 1, binding = LIGHT_BINDING_IRRADIANCE, rgba32f) uniform image3D irradiance;
// xyz: the vector irradiance sum_j (E_r + E_g + E_b)_j l_j (l_j the unit direction of
// travel); w: sum_j (E_r + E_g + E_b)_j. xyz / w is the mean direction of the light (its
// length the mean cosine between the rays), and for a Lambertian receiver with normal n,
// -dot(n, xyz) / w * E is Eq. 7's sum_j cos(theta_j) dE_omega,j exactly (per channel where
// the rays at the voxel share one colour ratio). With DIRECTION_NEAREST both sums are of the
// deposits centred in the voxel, so xyz / w is their mean direction and the product above
// weighs it by the trilinear irradiance: the same in the limit, 4 atomics a deposit instead
// of 24, and no longer linear in the lights (docs/BENCHMARKS.md).
layout(set = 1, binding = LIGHT_BINDING_DIRECTION, rgba32f) uniform image3D direction;

// Per run of the simulator (one light, one index channel, one tile of the initial
// wavefront; src/technique/eikonal/eikonal_light.rs `LightRun`).
layout(push_constant) uniform RunPushBlock { RunPush run; };

layout(constant_id = 2) const float DT = 0.01;             // time step of Eqs. 14-15
layout(constant_id = 3) const float VOL_MIN_X = -1.0;      // the index field's box
layout(constant_id = 4) const float VOL_MIN_Y = -1.0;
layout(constant_id = 5) const float VOL_MIN_Z = -1.0;
layout(constant_id = 6) const float VOL_MAX_X = 1.0;
layout(constant_id = 7) const float VOL_MAX_Y = 1.0;
layout(constant_id = 8) const float VOL_MAX_Z = 1.0;
layout(constant_id = 9) const float LIGHT_MIN_X = -1.0;    // the irradiance volume's box
layout(constant_id = 10) const float LIGHT_MIN_Y = -1.0;
layout(constant_id = 11) const float LIGHT_MIN_Z = -1.0;
layout(constant_id = 12) const float LIGHT_MAX_X = 1.0;
layout(constant_id = 13) const float LIGHT_MAX_Y = 1.0;
layout(constant_id = 14) const float LIGHT_MAX_Z = 1.0;
layout(constant_id = 15) const uint CHANNELS = 1u;         // index slabs in `field` (3: dispersion)
layout(constant_id = 16) const uint MATERIALS = 0u;        // 0: no extinction anywhere (stand-in)
layout(constant_id = 17) const uint KEEP_CROSSED = 0u;     // 1: keep patches past a singularity
layout(constant_id = 18) const uint INTEGRATOR = EIKONAL_EULER;
layout(constant_id = 20) const uint AIR_FACES = 0u;        // wavefront faces with skipped patches
layout(constant_id = 21) const uint HIGHEST_ENERGY = 0u;   // 1: the paper's voxelization (below)
layout(constant_id = 22) const uint FRESNEL = 0u;          // 1: Fresnel loss at boundary bands
layout(constant_id = 23) const uint HARDWARE_FILTER = 0u;  // 1: the device's trilinear field lookup
// 1: every light is grey (R = G = B) and nothing along the way colours it (one index slab,
// no extinction), so every deposit's three channel sums are equal: slab 0 holds them and
// slabs 1 and 2 are never added to (`deposit`, light_resolve.glsl).
layout(constant_id = 24) const uint GRAY = 0u;
// Steps per track-length deposit of a retained patch: 1, every step; 2, every other step
// (render.eikonal.light_deposit_every).
layout(constant_id = 25) const uint DEPOSIT_EVERY = 1u;
// 1: a track-length deposit adds its direction to the voxel holding its centre and its
// weight to slab 6 (render.eikonal.direction_splat = "nearest"); 0: trilinearly, like its
// irradiance, whose sum is the weight.
layout(constant_id = 26) const uint DIRECTION_NEAREST = 0u;
// At most this many straight steps after a patch's integrated step in one dispatch, while
// every corner stays in a uniform region (light_step.glsl; render.eikonal.light_leaps); 0: none.
layout(constant_id = 27) const uint LEAP_STEPS = 0u;
layout(constant_id = 28) const uint BRICK = 4u;
// Texel buffers, read at each patch's own index: one gather where lavapipe loads a storage
// buffer lane by lane.
layout(set = 1, binding = LIGHT_BINDING_BRICKS) uniform usamplerBuffer brick_texels;
uint brick_reach(int i) { return texelFetch(brick_texels, i).x; }
// 1: deposit only where `read_bits` says the volumes are read (render.eikonal.light_deposits,
// src/technique/eikonal/read_mask.rs): one bit per voxel of the irradiance volume, x fastest,
// set where a point that is looked up lies within two voxels of the voxel's centre.
layout(constant_id = 29) const uint READ_MASK = 0u;
layout(set = 1, binding = LIGHT_BINDING_READ_MASK) uniform usamplerBuffer read_bits;
// Whether voxel w of the irradiance volume (of `size` voxels) is within two voxels of a
// point that is read; always without READ_MASK.
bool marked_read(ivec3 w, ivec3 size) {
    if (READ_MASK == 0u) return true;
    uint k = uint(w.x + size.x * (w.y + size.y * w.z));
    return (texelFetch(read_bits, int(k >> 5u)).x & (1u << (k & 31u))) != 0u;
}
#include "bricks.glsl"

const vec3 VOL_MIN = vec3(VOL_MIN_X, VOL_MIN_Y, VOL_MIN_Z);
const vec3 VOL_MAX = vec3(VOL_MAX_X, VOL_MAX_Y, VOL_MAX_Z);
const vec3 LIGHT_MIN = vec3(LIGHT_MIN_X, LIGHT_MIN_Y, LIGHT_MIN_Z);
const vec3 LIGHT_MAX = vec3(LIGHT_MAX_X, LIGHT_MAX_Y, LIGHT_MAX_Z);

// With a per-channel index (CHANNELS = 3, dispersion) each channel's wavefront travels
// through its own slab (section 5.3: "a separate refractive index field for each RGB
// channel"): the simulator runs once per channel (`run.slab`).
vec4 field_voxel(ivec3 q, ivec3 size) {
    int slab = int(min(run.slab, CHANNELS - 1u));
    return all(greaterThanEqual(q, ivec3(0))) && all(lessThan(q, size)) ? texelFetch(field, q + ivec3(0, 0, slab * size.z), 0)
                                                                      : vec4(0.0);
}

// (grad n, n - 1) by trilinear interpolation in full precision, as eikonal_view samples it;
// n = 1 and no gradient beyond the volume's box. With HARDWARE_FILTER the device's filtering,
// as the view renderer's (render.eikonal.hardware_filtering: one slab, a linear sampler whose
// border is zero, as `field_voxel` beyond the box): one fetch instead of eight.
vec4 sample_field(vec3 x) {
    if (HARDWARE_FILTER != 0u) return textureLod(field, (x - VOL_MIN) / (VOL_MAX - VOL_MIN), 0.0);
    ivec3 size = textureSize(field, 0);
    size.z /= int(CHANNELS);
    vec3 u = (x - VOL_MIN) / (VOL_MAX - VOL_MIN) * vec3(size) - 0.5;
    u = clamp(u, vec3(-1.0), vec3(size));
    vec3 f = fract(u);
    ivec3 i = ivec3(floor(u));
    vec4 c00 = mix(field_voxel(i, size), field_voxel(i + ivec3(1, 0, 0), size), f.x);
    vec4 c10 = mix(field_voxel(i + ivec3(0, 1, 0), size), field_voxel(i + ivec3(1, 1, 0), size), f.x);
    vec4 c01 = mix(field_voxel(i + ivec3(0, 0, 1), size), field_voxel(i + ivec3(1, 0, 1), size), f.x);
    vec4 c11 = mix(field_voxel(i + ivec3(0, 1, 1), size), field_voxel(i + ivec3(1, 1, 1), size), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

// Extinction sigma_a + sigma_s at x (trilinear, clamped to the box's voxels; 0 outside the
// box and without materials), as eikonal_view samples it.
vec3 extinction_at(vec3 x) {
    if (MATERIALS == 0u || any(lessThan(x, VOL_MIN)) || any(greaterThan(x, VOL_MAX))) return vec3(0.0);
    ivec3 size = textureSize(extinction_map, 0);
    vec3 u = clamp((x - VOL_MIN) / (VOL_MAX - VOL_MIN) * vec3(size) - 0.5, vec3(0.0), vec3(size - 1));
    ivec3 i = ivec3(floor(u));
    ivec3 j = min(i + 1, size - 1);
    vec3 f = u - vec3(i);
    vec3 c00 = mix(texelFetch(extinction_map, i, 0).rgb, texelFetch(extinction_map, ivec3(j.x, i.y, i.z), 0).rgb, f.x);
    vec3 c10 = mix(texelFetch(extinction_map, ivec3(i.x, j.y, i.z), 0).rgb, texelFetch(extinction_map, ivec3(j.x, j.y, i.z), 0).rgb, f.x);
    vec3 c01 = mix(texelFetch(extinction_map, ivec3(i.x, i.y, j.z), 0).rgb, texelFetch(extinction_map, ivec3(j.x, i.y, j.z), 0).rgb, f.x);
    vec3 c11 = mix(texelFetch(extinction_map, ivec3(i.x, j.y, j.z), 0).rgb, texelFetch(extinction_map, j, 0).rgb, f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

float index_at(vec3 x) {
    return max(1.0 + sample_field(x).w, 1e-3);
}

// The fields a patch keeps in its corners' w (src/shader_structs.rs `Patch`).
vec3 patch_flux(Patch p) {
    return vec3(p.x[0].w, p.x[1].w, p.x[2].w);
}

void set_patch_flux(inout Patch p, vec3 flux) {
    p.x[0].w = flux.r;
    p.x[1].w = flux.g;
    p.x[2].w = flux.b;
}

// v[0].w: steps * MARK_SCALE + a mark: with HIGHEST_ENERGY the substep mark (at most 64
// substeps), with the track-length deposit 1 where the step's deposit waits for the next
// step's (light_step.glsl, DEPOSIT_EVERY).
const uint MARK_SCALE = 128u;

uint patch_steps(Patch p) {
    return uint(p.v[0].w) / MARK_SCALE;
}

uint patch_mark(Patch p) {
    return uint(p.v[0].w) % MARK_SCALE;
}

void set_patch_steps(inout Patch p, uint steps, uint mark) {
    p.v[0].w = float(steps * MARK_SCALE + mark);
}

// The vector area of the quad (half the cross product of its diagonals): its length is the
// area A of Eq. 17, its direction the patch orientation of section 5.2.3.
vec3 patch_normal(Patch p) {
    return 0.5 * cross(p.x[2].xyz - p.x[0].xyz, p.x[3].xyz - p.x[1].xyz);
}

vec3 patch_mid(Patch p) {
    return 0.25 * (p.x[0].xyz + p.x[1].xyz + p.x[2].xyz + p.x[3].xyz);
}

vec3 patch_dir(Patch p) {
    return p.v[0].xyz + p.v[1].xyz + p.v[2].xyz + p.v[3].xyz;
}

bool in_light_box(vec3 x) {
    return all(greaterThanEqual(x, LIGHT_MIN)) && all(lessThan(x, LIGHT_MAX));
}

// The paper's voxel sample of a patch (section 5.2.2: "we ... equate wavefront patches with
// their midpoints, storing the differential irradiance and directional information as a
// single voxel sample"): the voxel q holding its midpoint, its differential irradiance
// dE = flux / area (Eq. 17) and the key of its energy (slab 6, see `accum`). False outside
// the irradiance volume, and for a patch of no area (a focus: infinite dE) or no flux.
bool voxel_sample(Patch p, out ivec3 q, out vec3 dE, out uint key) {
    vec3 mid = patch_mid(p);
    dE = vec3(0.0);
    q = ivec3(0);
    key = 0u;
    if (!in_light_box(mid)) return false;
    dE = patch_flux(p) / length(patch_normal(p));
    float e = dE.r + dE.g + dE.b;
    if (!(e > 0.0) || isinf(e) || any(isnan(dE)) || any(isinf(dE))) return false;
    ivec3 size = imageSize(irradiance);
    q = clamp(ivec3((mid - LIGHT_MIN) / (LIGHT_MAX - LIGHT_MIN) * vec3(size)), ivec3(0), size - 1);
    key = floatBitsToUint(e);
    return true;
}

// Component `comp` (slab) of voxel q of the accumulator.
ivec3 accum_texel(ivec3 q, int comp) {
    return ivec3(q.x, q.y + comp * imageSize(irradiance).y, q.z);
}

float accum_value(ivec3 q, int comp) {
#ifdef ACCUM_FLOAT_ATOMICS
    return imageLoad(accum, accum_texel(q, comp)).x;
#else
    return uintBitsToFloat(imageLoad(accum, accum_texel(q, comp)).x);
#endif
}

// Add `value` to component `comp` of voxel q. The order of the additions is not fixed, so
// sums agree between runs to f32 rounding only (with either path).
void accum_add(ivec3 q, int comp, float value) {
    ivec3 c = accum_texel(q, comp);
#ifdef ACCUM_FLOAT_ATOMICS
    imageAtomicAdd(accum, c, value);
#else
    // Float atomics are an extension: this loop is core Vulkan.
    uint old = imageLoad(accum, c).x;
    for (int k = 0; k < 65536; ++k) {
        uint seen = imageAtomicCompSwap(accum, c, old, floatBitsToUint(uintBitsToFloat(old) + value));
        if (seen == old) break;
        old = seen;
    }
#endif
}
