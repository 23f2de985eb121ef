// The light's path through the specular surface a light-space refractor texel sees, shared by
// caustics mapping (Shah et al. 2007, glsl/caustics/splat_hits.comp) and the photon buffer of
// Hu & Qin 2007 §3.1 (glsl/caustics/photon_buffer.frag): where the photon leaves the
// specular object, in which direction, and with which flux.
//
// The includer declares, before including this file: the `Face` buffer (struct below),
// `materials[]`, and the refractor layers `front_position`, `front_normal`, `back_position`,
// `back_normal` (sampler2DArray, one layer per source face, caustics/refractor.frag).
#ifndef PRISM_LIGHT_PATH_GLSL
#define PRISM_LIGHT_PATH_GLSL

// The 2D texel of `f` that x projects to, or (-1, -1) outside the face.
ivec2 source_texel(GpuCausticFace f, vec3 x, int grid) {
    vec4 clip = f.view_proj * vec4(x, 1.0);
    if (!(clip.w > 0.0)) return ivec2(-1);
    vec2 t = (clip.xy / clip.w * 0.5 + 0.5) * float(grid);
    if (any(lessThan(t, vec2(0.0))) || any(greaterThanEqual(t, vec2(grid)))) return ivec2(-1);
    return ivec2(t);
}

// Whether x is still inside the object: in front of the back face the light sees at x's
// texel of source face f (distances from the light, or along a directional light).
bool inside(GpuCausticFace f, vec3 x, int grid, int layer) {
    ivec2 t = source_texel(f, x, grid);
    if (t.x < 0) return false;
    vec4 b = texelFetch(back_position, ivec3(t, layer), 0);
    if (b.w <= 0.0) return false;
    if (uint(f.light.w + 0.5) == LIGHT_POINT) {
        return distance(x, f.light.xyz) < distance(b.xyz, f.light.xyz);
    }
    return dot(x - b.xyz, f.light.xyz) < 0.0;
}

// The flux through grid texel ij of face f, in W: the light's intensity times the texel's
// solid angle (perspective face), or its irradiance times the texel's area (orthographic).
// This is Shah et al.'s Eq. 6 in physical units: the paper's weight 1/V is the texel's share
// of the flux through the visible area of the object, here measured directly, so the total
// does not depend on the grid resolution. For the photon buffer it is each photon's power:
// the paper counts photons, which is this with every photon carrying the same power.
float texel_measure(GpuCausticFace f, ivec2 ij, int grid) {
    vec2 ndc = (vec2(ij) + 0.5) / float(grid) * 2.0 - 1.0;
    if (uint(f.measure.x + 0.5) == CAUSTIC_FACE_PERSPECTIVE) {
        float t = f.measure.y;
        float q = 1.0 + t * t * dot(ndc, ndc);
        return (2.0 * t / float(grid)) * (2.0 * t / float(grid)) / (q * sqrt(q));
    }
    return (2.0 * f.measure.y / float(grid)) * (2.0 * f.measure.y / float(grid));
}

// The mean of texel_measure over the face: its solid angle over G^2 (a square pyramid of
// half-angle tangent t subtends 4 asin(t^2 / (1 + t^2))), or its area over G^2.
float mean_texel_measure(GpuCausticFace f, int grid) {
    float t = f.measure.y;
    if (uint(f.measure.x + 0.5) == CAUSTIC_FACE_PERSPECTIVE) {
        return 4.0 * asin(t * t / (1.0 + t * t)) / float(grid * grid);
    }
    return (2.0 * t / float(grid)) * (2.0 * t / float(grid));
}

// The light leaving the specular surface seen at texel ij of face f (layer `layer`) for
// colour channel c of `channels` (3: dispersion, one ior per channel): its origin, unit
// direction, the surface's transmittance or reflectance `weight`, and the absorption
// coefficient still to apply over the distance to the receiver (single-surface refraction).
// cos_in: N . L at the entry point (Shah et al.'s Eq. 6). Returns false where no specular
// surface is seen or the light stays inside the object.
// exit: CAUSTIC_EXIT_WYMAN or CAUSTIC_EXIT_MARCH, how double-surface refraction finds P2.
bool light_path(GpuCausticFace f, int layer, ivec2 ij, int grid, int c, uint channels, uint exit, out vec3 origin,
                out vec3 dir, out vec3 weight, out vec3 absorb_to_receiver, out float cos_in) {
    cos_in = 0.0;
    origin = vec3(0.0);
    dir = vec3(0.0);
    weight = vec3(0.0);
    absorb_to_receiver = vec3(0.0);
    vec4 fp = texelFetch(front_position, ivec3(ij, layer), 0);
    if (fp.w <= 0.0) return false;
    vec4 fn = texelFetch(front_normal, ivec3(ij, layer), 0);
    vec3 p1 = fp.xyz;
    vec3 n1 = normalize(fn.xyz);
    bool point_light = uint(f.light.w + 0.5) == LIGHT_POINT;
    vec3 l = point_light ? normalize(p1 - f.light.xyz) : f.light.xyz;

    GpuMaterial m = materials[uint(fn.w + 0.5)];
    uint kind = kind_of(m);
    float cos1 = clamp(dot(-l, n1), 0.0, 1.0);
    cos_in = cos1;
    origin = p1;
    // Single-surface refraction (water): "attenuation is performed over the distance between
    // the surface and the receiver geometry" (Shah et al. 2007, §III.E).
    if (kind == MATERIAL_DIELECTRIC) {
        float ior = (channels == 3u) ? m.spec_a[c] : m.spec_a.x;
        dir = refract(l, n1, 1.0 / ior);
        weight = vec3(1.0 - fresnel_dielectric(cos1, 1.0 / ior));
        vec4 bp = texelFetch(back_position, ivec3(ij, layer), 0);
        if (bp.w > 0.0) {
            // Double-surface refraction (§IV): the exit point P2 = P1 + d T1 and its normal N2.
            float d;
            vec3 exit_p, n2;
            if (exit == CAUSTIC_EXIT_WYMAN) {
                // Shah et al.'s estimator, Wyman 2005 §3.1 from the light: d_V the distance
                // from the front to the back surface along the light ray at this texel
                // (Fig. 3c), d_N the per-vertex distance along -N1 (the front layer's w - 1),
                //   d~ = (theta_t / theta_i) d_V + (1 - theta_t / theta_i) d_N,
                // N2 from the back layer where P2~ projects (§3.2); outside the silhouette,
                // perpendicular to the light's direction at P1, which stands in for the
                // camera's look-at vector of §3.3 (N2 = T1 - (L . T1) L).
                float d_v = distance(bp.xyz, p1);
                float d_n = fp.w - 1.0;
                if (!(d_n > 0.0)) d_n = d_v;   // open mesh or non-dielectric: no far side along -N
                float theta_i = acos(cos1);
                float theta_t = acos(clamp(-dot(n1, dir), -1.0, 1.0));
                // theta_t / theta_i -> 1 / ior as theta_i -> 0 (Snell for small angles).
                float ratio = theta_i > 1e-4 ? theta_t / theta_i : 1.0 / ior;
                d = max(ratio * d_v + (1.0 - ratio) * d_n, 0.0);
                exit_p = p1 + d * dir;
                ivec2 exit_t = source_texel(f, exit_p, grid);
                if (exit_t.x >= 0 && texelFetch(back_position, ivec3(exit_t, layer), 0).w > 0.0) {
                    n2 = normalize(texelFetch(back_normal, ivec3(exit_t, layer), 0).xyz);
                } else {
                    n2 = dir - dot(l, dir) * l;
                    n2 = dot(n2, n2) > 1e-12 ? normalize(n2) : dir;
                }
            } else {
                // prism's departure: the back faces seen from the light are a depth map, so
                // the exit is the root of the same signed function as the receiver's (Eq. 3):
                // the back face's distance from the light at the point's texel minus the
                // point's own distance, positive inside. A linear search over the objects'
                // largest chord brackets the first exit and a binary search refines it (the
                // linear-then-binary search of relief mapping; Hu & Qin 2007 §2.1 search
                // differently: a binary search for the silhouette pixel p_e to decide front
                // or back, Fig. 7, then an iterative d_T, Fig. 8). Unlike one estimate of d,
                // it needs no precomputed d_N and follows concave back surfaces.
                float chord = f.measure.w;
                float lo = 0.0, hi = chord;
                const int MARCH = 16, BISECT = 10;
                bool found = false;
                for (int k = 1; k <= MARCH && !found; ++k) {
                    float t = chord * float(k) / float(MARCH);
                    if (!inside(f, p1 + t * dir, grid, layer)) {
                        hi = t;
                        found = true;
                    } else {
                        lo = t;
                    }
                }
                for (int k = 0; k < BISECT; ++k) {
                    float mid = 0.5 * (lo + hi);
                    if (inside(f, p1 + mid * dir, grid, layer)) lo = mid; else hi = mid;
                }
                d = 0.5 * (lo + hi);
                exit_p = p1 + d * dir;
                ivec2 exit_t = source_texel(f, exit_p, grid);
                if (exit_t.x < 0 || texelFetch(back_position, ivec3(exit_t, layer), 0).w <= 0.0) {
                    // Left through the silhouette: the back face at the last texel inside.
                    exit_t = source_texel(f, p1 + lo * dir, grid);
                    if (exit_t.x < 0) exit_t = ij;
                }
                n2 = normalize(texelFetch(back_normal, ivec3(exit_t, layer), 0).xyz);
            }
            vec3 t2 = refract(dir, -n2, ior);
            // Total internal reflection: the light stays inside the object.
            if (dot(t2, t2) == 0.0) return false;
            weight *= 1.0 - fresnel_dielectric(clamp(dot(dir, n2), 0.0, 1.0), ior);
            // Beer-Lambert along the path inside the object (Eq. 7).
            weight *= exp(-m.spec_b.rgb * d);
            origin = exit_p;
            dir = t2;
        } else {
            absorb_to_receiver = m.spec_b.rgb;
        }
    } else if (kind == MATERIAL_MIRROR) {
        dir = reflect(l, n1);
        weight = m.spec_a.rgb;
    } else if (kind == MATERIAL_CONDUCTOR) {
        dir = reflect(l, n1);
        weight = fresnel_conductor(cos1, m.spec_a.rgb, m.spec_b.rgb);
    } else {
        return false;
    }
    if (!(dot(dir, dir) > 0.0)) return false;
    dir = normalize(dir);
    return !(any(isnan(dir)) || any(isnan(origin)));
}
#endif
