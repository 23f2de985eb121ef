#version 450
// Reference camera paths: every light path with exactly one diffuse vertex (SCENES.md,
// "Light transport measured"). The camera ray follows mirror, conductor and dielectric
// interactions (exact Fresnel, chosen stochastically) until it escapes (environment) or
// reaches a diffuse surface, where it takes (1) direct light from point and directional
// lights with exact shadow rays, (2) environment light arriving through any specular chain
// (one cosine-weighted sample), and (3) leaves a visible point for the photon gathering that
// adds caustics (gather.comp).
#define REF_STAT_STEP_CAP_SLOT REF_STAT_STEP_CAP_CAMERA
#include "sppm.glsl"
#include "paths.glsl"

// One camera path of pixel px through the image point `offset` inside the pixel. Returns the
// radiance it gathers; with `record` it leaves its diffuse vertex as the pixel's visible point
// of this iteration (or marks that it has none).
vec3 camera_path(uint px, vec2 offset, bool record, inout uint rng) {
    uint W = ref.dims.x, H = ref.dims.y;
    vec2 ndc = (vec2(px % W, px / W) + offset) / vec2(W, H) * 2.0 - 1.0;
    vec3 d = normalize(mat3(ref.inv_view) * vec3(ndc.x * ref.proj.x, -ndc.y * ref.proj.y, -1.0));
    vec3 o = ref.camera_pos.xyz;

    // Dispersion: trace one wavelength channel per path, chosen uniformly, weighted by 3.
    int channel = -1;
    vec3 beta = vec3(1.0);
    if ((ref.photon.w & REF_FLAG_DISPERSION) != 0u) {
        channel = min(int(rand(rng) * 3.0), 2);
        beta = vec3(0.0);
        beta[channel] = 3.0;
    }

    vec3 L = vec3(0.0);
    bool visible_point = false;
    float travelled = 0.0;   // along the surfaces' chain (curved paths in volumes not counted)
    for (uint bounce = 0u; bounce <= ref.counts.w; ++bounce) {
        Hit h = trace(o, d, 3.4e38);
        // A graded-index volume in front of the surface (or the environment): cross it.
        float tv;
        if (region_entry(o, d, h.kind == 0u ? 3.4e38 : h.t, tv)) {
            if (!volume_cross(o, d, tv, beta, L, channel, rng)) break;
            continue;
        }
        if (h.kind == 0u) {
            L += beta * environment(d);
            break;
        }
        Surface s = surface_at(o, d, h);
        GpuMaterial m = materials[s.material];
        travelled += h.t;
        if (kind_of(m) != MATERIAL_DIFFUSE) {
            if (!specular_step(s, o, d, beta, h.t, channel, rand(rng), true)) break;
            continue;
        }
        // The diffuse vertex.
        vec3 n = gather_diffuse(s, d, beta, channel, rng, L);
        if (!record) break;
        pixels[px].vp_pos.xyz = s.p;
        pixels[px].vp_normal = vec4(n, 1.0);
        pixels[px].vp_weight = vec4(beta * (albedo_at(m, s.st) / PI), 0.0);
        // The initial radius: ref.grid.w pixel footprints, the spacing of neighbouring
        // camera rays on the receiver (the pixel's angle times the distance travelled, over
        // sqrt(cos) so that the disk has the footprint's area), at most ref.grid.y. A pixel
        // that has collected no photon yet (N = 0, so tau = 0) takes the footprint of this
        // iteration's visible point; from its first photon on its radius only shrinks
        // (Hachisuka et al. 2008, Eq. 7).
        if (ref.grid.w > 0.0 && pixels[px].tau_n.w == 0.0) {
            float pixel_angle = 2.0 * ref.proj.y / float(H);
            float cosine = max(abs(dot(d, n)), 0.05);
            pixels[px].vp_pos.w = min(ref.grid.y, ref.grid.w * pixel_angle * travelled / sqrt(cosine));
        }
        visible_point = true;
        break;
    }
    if (record && !visible_point) pixels[px].vp_normal.w = 0.0;
    return L;
}

// Pixel px's sample of this iteration.
void camera_sample(uint px) {
    uint rng = rng_init(px, push.iteration, push.seed);
    // Pixel (i, j) samples the ray through its centre ((i+0.5)/W, (j+0.5)/H), j = 0 the top
    // row (SCENES.md), unless supersampling was asked for.
    bool jitter = (ref.photon.w & REF_FLAG_JITTER) != 0u;
    vec2 offset = jitter ? vec2(rand(rng), rand(rng)) : vec2(0.5);
    // With radii of a pixel's footprint (ref.grid.w > 0) the caustic's visible points sample
    // the pixel's area even for centre rays: a second path through a uniform point of the
    // pixel leaves them. SPPM then estimates the caustic averaged over the pixel (Hachisuka &
    // Jensen 2009, Sec. 4: the shared statistics of stochastic visible points), whose sum
    // over pixels is the caustic's flux. The visible point of the centre ray converges to
    // the irradiance at one point instead, and the sum over pixels then misses a focus
    // narrower than a pixel that falls between the centres, or multiplies one that falls on
    // a centre (tests/reference.rs, the flux checks: 0.96 to 2.2 times the photons' flux).
    bool area_caustics = ref.grid.w > 0.0 && !jitter;
    vec3 L = camera_path(px, offset, !area_caustics, rng);
    if (area_caustics) {
        uint rng_vp = rng_init(px, push.iteration, push.seed ^ 0x2545f491u);
        vec2 area = vec2(rand(rng_vp), rand(rng_vp));
        camera_path(px, area, true, rng_vp);
    }
    accum[px] += vec4(finite_or_zero(L), 1.0);
}

void main() {
    uint px = invocation_index();
    if (px >= ref.dims.x * ref.dims.y) return;
    camera_sample(px);
    // After the whole sample, whatever returns it takes (sppm.glsl).
    loop_canary(REF_STAT_CUT_CAMERA);
}
