#version 450
// The caustic map of light-map caustics (Szirmay-Kalos et al. 2005, §5, Fig. 9): rendered
// "from the point of view of the light source, the view plane is placed between the light
// and the refractor". Per pixel where a specular object is visible, the paper's pixel shader
// (R = refract(L, N, 1/n) or reflect; l = Hit(x, R, envmap); hituv = texCUBE(uvmap, l)):
// the light's ray is refracted (through both surfaces, the exit from the refractor map of
// §4) or reflected, Hit() finds the photon hit in the uv map (§3), and the pixel stores the
// hit's light-map (u, v), the texture id and the photon's power, "computed from the power of
// the light source and the solid angle subtended by the caustic map pixel" (a point light:
// intensity x solid angle; a directional light: irradiance x texel area), times the Fresnel
// factors. The paper stores the power's luminance; here RGB power goes to a second target.
// Texels without a hit get alpha -1 ("we initialize the caustic map with -1 alpha values";
// the splat pass drops them).
//
// A full-screen pass over the caustic map: the surfaces the light sees were rasterized first
// (lightmap_surface.frag), so each texel runs the two Hit() searches once. Shaded while
// rasterizing, they ran for every fragment of every small triangle that a CPU device shades
// in blocks of pixels, several times per texel on a tessellated ball.
#include "frame.glsl"
#include "fresnel.glsl"
#include "impostor.glsl"
#include "lightmap_push.glsl"
// 0: Hit() iterations (`render.impostor_lightmap.iterations`); 1, 2: the light maps' size
// and the splats' radius in their texels (`lightmap_size`, `filter_radius`).
layout(constant_id = 0) const uint ITERATIONS = 4;
layout(constant_id = 1) const uint LIGHTMAP_SIZE = 256;
layout(constant_id = 2) const float FILTER_RADIUS = 2.0;
layout(set = 1, binding = LIGHTMAP_BINDING_UV_LINEAR) uniform samplerCube uv_linear;
layout(set = 1, binding = LIGHTMAP_BINDING_UV_NEAREST) uniform samplerCube uv_nearest;
layout(set = 1, binding = LIGHTMAP_BINDING_REFRACTOR) uniform samplerCube refractor_map;
// xyz world position, w material index + 1 (0: no specular surface); xyz normal.
layout(set = 1, binding = LIGHTMAP_BINDING_SURFACE_POSITION) uniform sampler2D surface_position;
layout(set = 1, binding = LIGHTMAP_BINDING_SURFACE_NORMAL) uniform sampler2D surface_normal;
// Per light map, the texels the photons can reach (see `reach`); reset to u32::MAX each time
// the caustic maps are rendered.
layout(set = 1, binding = LIGHTMAP_BINDING_REACH, std430) buffer Reach { uint reach[]; };

// The texels of light map `slot` that this photon's splat (texels within FILTER_RADIUS of
// its centre, lightmap_splat.vert) and the apply pass's bilinear lookup next to them can
// reach, with a texel to spare: outside every photon's reach a light map holds exactly 0,
// and lightmap_apply.vert leaves those pixels out.
void extend_reach(uint slot, vec2 uv) {
    vec2 c = uv * float(LIGHTMAP_SIZE);
    int last = int(LIGHTMAP_SIZE) - 1;
    ivec2 lo = clamp(ivec2(floor(c - FILTER_RADIUS)) - 2, ivec2(0), ivec2(last));
    ivec2 hi = clamp(ivec2(ceil(c + FILTER_RADIUS)) + 2, ivec2(0), ivec2(last));
    atomicMin(reach[4u * slot], uint(lo.x));
    atomicMin(reach[4u * slot + 1u], uint(lo.y));
    atomicMin(reach[4u * slot + 2u], 0xFFFFFFFFu - uint(hi.x));
    atomicMin(reach[4u * slot + 3u], 0xFFFFFFFFu - uint(hi.y));
}
// RT0: (u, v, light-map slot, 1) or alpha -1 (no hit); RT1: rgb photon power (W).
layout(location = 0) out vec4 out_hit;
layout(location = 1) out vec4 out_power;

void no_hit() {
    out_hit = vec4(0.0, 0.0, 0.0, -1.0);
    out_power = vec4(0.0);
}

void main() {
    ivec2 at = ivec2(gl_FragCoord.xy);
    vec4 surface = texelFetch(surface_position, at, 0);
    if (!(surface.w > 0.5)) { no_hit(); return; }
    GpuMaterial m = materials[uint(surface.w - 0.5)];
    uint kind = kind_of(m);
    vec3 p = surface.xyz;
    bool point_light = uint(pc.light.w + 0.5) == LIGHT_POINT;
    vec3 L = point_light ? p - pc.light.xyz : pc.light.xyz;
    if (!(dot(L, L) > 0.0)) { no_hit(); return; }
    L = normalize(L);
    vec3 N = texelFetch(surface_normal, at, 0).xyz;
    if (!(dot(N, N) > 1e-20)) { no_hit(); return; }
    N = normalize(N);
    if (dot(N, L) > 0.0) N = -N;   // the side the light sees
    float cos_i = clamp(-dot(L, N), 0.0, 1.0);

    // The texel's measure: solid angle r^-2 dA cos^3 of the perspective texel at the
    // frustum's unit plane (point light), or its area (directional light).
    float size = pc.refractor.w;
    vec2 ndc = gl_FragCoord.xy / size * 2.0 - 1.0;
    float t = pc.reference.w;
    float texel = 2.0 * t / size;
    float measure;
    if (point_light) {
        vec2 xy = ndc * t;
        float q = 1.0 + dot(xy, xy);
        measure = texel * texel / (q * sqrt(q));
    } else {
        measure = texel * texel;
    }
    vec3 power = pc.intensity.rgb * measure;

    vec3 q = p;
    vec3 dir;
    if (kind == MATERIAL_DIELECTRIC) {
        // One ior (green) per photon: the caustic map carries no dispersion.
        float n = max(m.spec_a.g, 1e-6);
        vec3 T = refract(L, N, 1.0 / n);
        if (!(dot(T, T) > 0.0)) { no_hit(); return; }
        float F1 = fresnel_dielectric(cos_i, 1.0 / n);
        // The exit point and normal from the refractor map (§4).
        vec3 c = pc.refractor.xyz;
        vec3 l = impostor_hit(refractor_map, 3u, p - c, T, ITERATIONS);
        vec3 N1 = textureLod(refractor_map, dot(l, l) > 0.0 ? l : T, 0.0).xyz;
        N1 = dot(N1, N1) > 0.0 ? normalize(N1) : T;
        if (dot(N1, T) < 0.0) N1 = -N1;
        q = l + c;
        float F2 = fresnel_dielectric(clamp(dot(T, N1), 0.0, 1.0), n);
        dir = refract(T, -N1, n);
        if (!(dot(dir, dir) > 0.0)) { no_hit(); return; }   // totally reflected inside: dropped
        power *= (1.0 - F1) * (1.0 - F2) * exp(-m.spec_b.rgb * length(q - p));
    } else if (kind == MATERIAL_MIRROR) {
        dir = reflect(L, N);
        power *= m.spec_a.rgb;
    } else if (kind == MATERIAL_CONDUCTOR) {
        dir = reflect(L, N);
        power *= fresnel_conductor(cos_i, m.spec_a.rgb, m.spec_b.rgb);
    } else {
        no_hit();
        return;
    }
    // Hit() in the uv map (§5: "float3 l = Hit(x, R, envmap); float3 hituv = texCUBE(uvmap, l).xyz;").
    vec3 x = q - pc.reference.xyz;
    vec3 h = impostor_hit(uv_linear, 3u, x, normalize(dir), ITERATIONS);
    if (!(dot(h, h) > 0.0) || impostor_missed(uv_linear, 3u, h)) { no_hit(); return; }
    vec4 uv = textureLod(uv_nearest, h, 0.0);
    if (!(uv.b > 0.5)) { no_hit(); return; }   // not a light-mapped receiver
    if (any(isnan(power)) || any(isinf(power)) || any(isnan(uv.rg))) { no_hit(); return; }
    out_hit = vec4(uv.rg, uv.b - 1.0, 1.0);
    out_power = vec4(power, 0.0);
    extend_reach(uint(uv.b - 0.5), uv.rg);
}
