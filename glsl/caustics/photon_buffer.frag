#version 450
// The photon buffer of Hu & Qin 2007 §3.1 (Fig. 19b): the reflector/refractor rendered from
// the light, one pixel per photon. Each pixel follows the light through the specular surface
// it sees (the refracted ray through both interfaces, or the reflected ray:
// caustics/light_path.glsl), intersects it with the receiver rectangles RECT_i (§2.2.1,
// Fig. 13's ray tracing pass) and keeps the nearest, writing
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
    if (!light_path(f, layer, ij, grid, 1, 3u, origin, dir, weight, absorb, cos_in)) return;
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
    vec3 flux = f.intensity.rgb * texel_measure(f, ij, grid) * weight * exp(-absorb * best);
    if (any(isnan(flux)) || any(isinf(flux))) return;
    out_photon = vec4(uv, float(k), 0.0);
    out_flux = vec4(flux, 0.0);
}
