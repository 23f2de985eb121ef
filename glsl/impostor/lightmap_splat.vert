#version 450
// Light-map caustics (Szirmay-Kalos et al. 2005, §5): "we render as many small quadrilaterals
// ... or point sprites as texels the caustic map has"; the vertex shader reads the caustic map
// (vertex texture fetch), centres the sprite at the photon hit's (u, v) in the receiver's
// texture space and "moves the quadrilateral out of the clipping region if the alpha is
// negative". One point sprite per caustic-map texel; the Gaussian weights are normalized here
// over exactly the texels the fragment shader keeps (centres within `radius`), so each photon
// deposits all of its power (src/technique/impostor/impostor_lightmap.rs, `splat_weights`, checks the same
// sum on the CPU). The Gaussian is separable, exp(-(dx^2 + dy^2) / 2 sigma^2) = e(dx) e(dy):
// one exp per column and per row of the splat's square (2 (2r + 1), r = ceil(radius)) instead
// of one per texel ((2r + 1)^2, 25 at the default radius); the disc decides which texels count.
#include "common.glsl"
layout(set = 0, binding = LIGHTMAP_BINDING_PHOTON_HIT) uniform sampler2D photon_hit;
layout(set = 0, binding = LIGHTMAP_BINDING_PHOTON_POWER) uniform sampler2D photon_power;
layout(push_constant) uniform LightmapSplatPushBlock { LightmapSplatPush pc; };
layout(location = 0) flat out vec3 out_irradiance;   // power / texel area / weight sum
layout(location = 1) flat out vec2 out_center;       // splat centre in light-map pixels

void drop_vertex() {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // outside the clip volume: culled
    gl_PointSize = 1.0;
    out_irradiance = vec3(0.0);
    out_center = vec2(0.0);
}

void main() {
    uint size = pc.info.y;
    ivec2 texel = ivec2(uint(gl_VertexIndex) % size, uint(gl_VertexIndex) / size);
    vec4 hit = texelFetch(photon_hit, texel, 0);
    if (!(hit.a > 0.0) || uint(hit.b + 0.5) != pc.info.x) { drop_vertex(); return; }
    vec3 power = texelFetch(photon_power, texel, 0).rgb;
    float n = pc.params.y;
    vec2 center = hit.rg * n;   // light-map pixels
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
    if (!(sum > 0.0)) { drop_vertex(); return; }
    out_irradiance = power * pc.params.z / sum;
    out_center = center;
    gl_Position = vec4(hit.rg * 2.0 - 1.0, 0.0, 1.0);
    // Pixel centres up to r + 1/2 from the centre along each axis: the whole disc.
    gl_PointSize = 2.0 * float(r) + 1.0;
}
