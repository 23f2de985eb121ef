// The photons' caustic at a diffuse point, shared by the raytrace technique's passes: at the
// diffuse vertices of its branches (raytrace.frag) and at the diffuse pixels seen directly
// (caustics.frag). The includer declares the tracer (REF_SET 1) and the frame first.
#ifndef PRISM_RAYTRACE_CAUSTIC_GLSL
#define PRISM_RAYTRACE_CAUSTIC_GLSL
#define PHOTON_GRID_ACCESS readonly
#include "../reference/photon_grid.glsl"

// The caustic radiance leaving the diffuse point s towards a branch that arrived along d after
// `travelled` from the camera, n the normal on its side: the photon map's radiance estimate
// (Jensen 1996; the reference's gather.comp with a fixed radius) over this frame's photons
// within r, each of flux Phi_p reflected by the Lambertian BRDF albedo / pi:
//   L = albedo / pi * sum Phi_p / (pi r^2).
// r is ref.grid.z pixel footprints on the surface (the pixel's angle times the distance
// travelled, over sqrt(cos) so that the disk has the footprint's area), at most ref.grid.y:
// the initial radius of the reference's visible points (camera.comp).
vec3 caustic_at(Surface s, vec3 d, vec3 n, float travelled) {
    float pixel_angle = 2.0 * ref.proj.y / float(frame.viewport.y);
    float cosine = max(abs(dot(d, n)), 0.05);
    float r = min(ref.grid.y, ref.grid.z * pixel_angle * travelled / sqrt(cosine));
    float M;
    vec3 phi;
    photons_within(s.p, n, r, M, phi);
    return albedo_at(materials[s.material], s.st) / PI * phi / (PI * r * r);
}
#endif
