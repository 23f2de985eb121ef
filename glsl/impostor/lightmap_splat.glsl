// What the light-map splat's two vertex programs share (lightmap_splat.vert, one sprite per
// photon; lightmap_splat_block.vert, one sprite per 2 x 2 block of caustic-map texels): a
// photon's centre on the light map and its Gaussian's normalisation, and which blocks are drawn
// as one sprite. See lightmap_splat.vert for the splat itself.
#include "common.glsl"
layout(set = 0, binding = LIGHTMAP_BINDING_PHOTON_HIT) uniform sampler2D photon_hit;
layout(set = 0, binding = LIGHTMAP_BINDING_PHOTON_POWER) uniform sampler2D photon_power;
layout(push_constant) uniform LightmapSplatPushBlock { LightmapSplatPush pc; };

// The photon of caustic-map texel `texel` lands on this light map: its (u, v) there.
bool photon_at(ivec2 texel, out vec2 uv) {
    uv = vec2(0.0);
    uint size = pc.info.y;
    if (any(greaterThanEqual(uvec2(texel), uvec2(size)))) return false;
    vec4 hit = texelFetch(photon_hit, texel, 0);
    if (!(hit.a > 0.0) || uint(hit.b + 0.5) != pc.info.x) return false;
    uv = hit.rg;
    return true;
}

// The photon's irradiance per unit Gaussian weight: its power over the texel area and over
// the sum of the weights of exactly the texels the fragment shader keeps (centres within
// `radius`), so that it deposits all of its power (src/technique/impostor/impostor_lightmap.rs,
// `splat_weights`, checks the same sum on the CPU). The Gaussian is separable,
// exp(-(dx^2 + dy^2) / 2 sigma^2) = e(dx) e(dy): one exp per column and per row of the splat's
// square (2 (2r + 1), r = ceil(radius)) instead of one per texel ((2r + 1)^2, 25 at the
// default radius); the disc decides which texels count. False: no texel centre in reach.
// `center`: the photon's (u, v) in light-map pixels.
bool splat_irradiance(ivec2 texel, vec2 center, out vec3 irradiance) {
    irradiance = vec3(0.0);
    float radius = pc.params.x;
    float sigma = radius * 0.5;
    float sum = 0.0;
    int r = int(ceil(radius));
    // The texels k whose centres k + 0.5 are within `radius` of the centre along an axis
    // start at `lo`; there are at most 2 ceil(radius) + 1 of them.
    ivec2 lo = ivec2(ceil(center - radius - 0.5));
    // filter_radius <= 16 (src/scene/techniques.rs): at most 2 * 16 + 1 columns and rows.
    float ex[33];
    float ey[33];
    int span = 2 * r + 1;
    for (int k = 0; k < span; ++k) {
        vec2 d = vec2(lo + ivec2(k)) + 0.5 - center;
        ex[k] = exp(-d.x * d.x / (2.0 * sigma * sigma));
        ey[k] = exp(-d.y * d.y / (2.0 * sigma * sigma));
    }
    for (int y = 0; y < span; ++y) {
        for (int x = 0; x < span; ++x) {
            vec2 d = vec2(lo + ivec2(x, y)) + 0.5 - center;
            if (dot(d, d) <= radius * radius) sum += ex[x] * ey[y];
        }
    }
    if (!(sum > 0.0)) return false;
    irradiance = texelFetch(photon_power, texel, 0).rgb * pc.params.z / sum;
    return true;
}

// The block of caustic-map texels 2 b .. 2 b + 1 is drawn as one sprite (with
// render.impostor_lightmap.block_splats) when its photons' centres span at most 2 ceil(radius)
// light-map pixels along each axis (31 at the largest radius): neighbours on the caustic map
// land next to each other on the receiver except across a fold of the caustic. lo, hi: the
// centres' bounds; false also for a block without a photon here. Both vertex programs
// evaluate exactly this, so every photon is drawn once.
bool block_fits(ivec2 b, out vec2 lo, out vec2 hi) {
    lo = vec2(1e30);
    hi = vec2(-1e30);
    bool any_photon = false;
    for (int i = 0; i < 4; ++i) {
        vec2 uv;
        if (photon_at(2 * b + ivec2(i & 1, i >> 1), uv)) {
            vec2 c = uv * pc.params.y;
            lo = min(lo, c);
            hi = max(hi, c);
            any_photon = true;
        }
    }
    // The sprite is then at most reach + 2 ceil(radius) + 1 texels wide: at most 64, the
    // point size every device supports, up to the largest filter_radius (16).
    float r = ceil(pc.params.x);
    float reach = min(2.0 * r, 63.0 - 2.0 * r);
    return any_photon && all(lessThanEqual(hi - lo, vec2(reach)));
}
