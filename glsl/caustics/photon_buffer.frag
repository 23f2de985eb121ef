#version 450
// The photon buffer of Hu & Qin 2007 §3.1 (Fig. 19b): the reflector/refractor rendered from
// the light, one pixel per photon. Each pixel follows the light through the specular surface
// it sees (the refracted ray through both interfaces, or the reflected ray:
// caustics/light_path.glsl), intersects it with the receiver rectangles RECT_i (§2.2.1,
// Fig. 13's ray tracing pass), keeps the nearest, moves that hit onto the receiver itself
// with §2.2.2's iterative depth correction (Fig. 16) against TEX_DEPTH_k, and writes
//   RT0 photon: (u, v, k, 0): texture coordinates on RECT_k, k = rectangle index + 1,
//               k = 0 where no photon leaves (no specular surface, total internal
//               reflection, or a ray that meets no rectangle: discarded, never NaN);
//   RT1 flux:   (rgb, 0): the photon's power in W. The paper counts photons ("one pixel
//               denotes one photon"); prism also carries each photon's share of the light's
//               flux (texel_measure) times its Fresnel transmittance/reflectance and
//               Beer-Lambert absorption, so that the caustic is in physical units.
#include "common.glsl"
#include "fresnel.glsl"
#include "photon_rect.glsl"

layout(set = 0, binding = CAUSTIC_BINDING_FACES, std430) readonly buffer Faces { GpuCausticFace faces[]; };
layout(set = 0, binding = CAUSTIC_BINDING_MATERIALS, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = CAUSTIC_BINDING_FRONT_POSITION) uniform sampler2DArray front_position;
layout(set = 0, binding = CAUSTIC_BINDING_FRONT_NORMAL) uniform sampler2DArray front_normal;
layout(set = 0, binding = CAUSTIC_BINDING_BACK_POSITION) uniform sampler2DArray back_position;
layout(set = 0, binding = CAUSTIC_BINDING_BACK_NORMAL) uniform sampler2DArray back_normal;
layout(set = 0, binding = PHOTON_BINDING_RECTS, std430) readonly buffer Rects { GpuPhotonRect rects[]; };
// TEX_DEPTH_i: the receiver's signed distance from RECT_i's plane along the rectangle's axis
// (photon_buffer_receivers), FAR_DISTANCE where the projection sees no receiver.
layout(set = 0, binding = PHOTON_BINDING_RECEIVER_DEPTH) uniform sampler2DArray receiver_depth;
#include "light_path.glsl"

layout(push_constant) uniform PhotonBufferPushBlock { PhotonBufferPush pc; };

layout(location = 0) out vec4 out_photon;
layout(location = 1) out vec4 out_flux;

void main() {
    out_photon = vec4(0.0);
    out_flux = vec4(0.0);
    int layer = int(pc.info.x);
    int grid = int(pc.info.y);
    ivec2 ij = ivec2(gl_FragCoord.xy);
    GpuCausticFace f = faces[layer];
    vec3 origin, dir, weight, absorb;
    float cos_in;
    // Dispersion is not modelled by the photon buffer: the paper's photons carry no
    // wavelength; a dispersive (RGB) ior is taken at green (channel 1).
    // The exit point by the march: Hu & Qin build the photon buffer with their own refraction
    // (§3: "using the method to implement reflection and refraction"), not Wyman's d_V/d_N,
    // whose precomputed d_N §2.1 names as the limitation it removes.
    if (!light_path(f, layer, ij, grid, 1, 3u, CAUSTIC_EXIT_MARCH, origin, dir, weight, absorb, cos_in)) return;
    // Fig. 13's ray tracing pass: the rectangle whose intersection is nearest to startP.
    float best = 1.0 / 0.0;
    int k = 0;
    vec2 uv = vec2(0.0);
    for (uint i = 0u; i < pc.info.z; ++i) {
        GpuPhotonRect r = rects[i];
        float denom = dot(dir, r.axis.xyz);
        if (abs(denom) < 1e-8) continue;   // parallel to the rectangle
        float t = dot(r.centre.xyz - origin, r.axis.xyz) / denom;
        if (!(t > 0.0) || !(t < best)) continue;
        vec2 q = rect_uv(r, origin + t * dir);
        if (any(lessThan(q, vec2(0.0))) || any(greaterThanEqual(q, vec2(1.0)))) continue;
        best = t;
        k = int(i) + 1;
        uv = q;
    }
    if (k == 0) return;
    // §2.2.2, Fig. 16: the rectangle hit P_rect is where the ray meets RECT_k, not OBJ_k.
    // Deferred shading finds a receiver point's caustic by projecting the point in parallel
    // onto RECT_k (§3.3, Fig. 23), so the photon must be counted at the projection of P_geom,
    // the ray's hit with OBJ_k: step along the ray by the depth difference over cos(theta)
    // until the point lies on the receiver's depth (relative tolerance as
    // render.hu_qin.correction_tolerance's default). A ray that reaches a texel where the
    // projection sees no receiver passes beside OBJ_k and is no photon of it; the paper makes
    // the same assumption the other way (a ray that misses RECT_k misses OBJ_k, §2.2.2).
    GpuPhotonRect r = rects[k - 1];
    float cos_theta = dot(dir, r.axis.xyz);
    float tolerance = 1e-3 * r.axis.w;
    float dist = best;
    for (uint it = 0u; it < pc.info.w; ++it) {
        vec3 p = origin + dist * dir;
        vec2 q = rect_uv(r, p);
        if (any(lessThan(q, vec2(0.0))) || any(greaterThanEqual(q, vec2(1.0)))) return;
        float depth = textureLod(receiver_depth, vec3(q, float(k - 1)), 0.0).r;
        if (!(depth < 1.0e30)) return;   // FAR_DISTANCE: no receiver along this line
        float dz = depth - dot(p - r.centre.xyz, r.axis.xyz);
        if (abs(dz) <= tolerance) break;
        dist += dz / cos_theta;
    }
    if (!(dist > 0.0)) return;
    uv = rect_uv(r, origin + dist * dir);
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) return;
    best = dist;
    vec3 flux = f.intensity.rgb * texel_measure(f, ij, grid) * weight * exp(-absorb * best);
    if (any(isnan(flux)) || any(isinf(flux))) return;
    out_photon = vec4(uv, float(k), 0.0);
    out_flux = vec4(flux, 0.0);
}
