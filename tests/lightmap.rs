//! Light-map caustics with distance impostors (Szirmay-Kalos et al. 2005 §5;
//! src/technique/impostor/impostor_lightmap.rs), `render.caustics = "impostor_lightmap"`: the caustic
//! scenes render without validation errors or NaN, the light maps conserve the photons' power
//! (total flux on caustic_sphere's floor against the analytic flux through the ball, stable
//! in the caustic-map size), and the degenerate lights stay finite.
mod common;

use prism::metrics::image::{non_finite_count, rmse_rgba};
use prism::reference::{Reference, ReferenceSettings};
use prism::renderer::Renderer;

fn lightmap(extra: &[&str]) -> Vec<String> {
    let mut o = vec!["render.caustics=impostor_lightmap".to_string()];
    o.extend(extra.iter().map(|s| s.to_string()));
    o
}

/// Total flux (W, green channel) in the light maps: irradiance x texel area, over every
/// receiver; and the peak irradiance with its (u, v).
fn lightmap_flux(ctx: &std::sync::Arc<prism::gpu::GpuContext>, name: &str, extra: &[&str]) -> (f64, f32, [f32; 2]) {
    let s = common::scene(name, 64, &common::refs(&lightmap(extra)));
    let mut r = Renderer::new(ctx, &s).expect("renderer");
    r.render_frame().expect("frame");
    let (texels, charts) = r.read_lightmaps().expect("readback").expect("light maps");
    drop(r);
    common::assert_no_validation_errors(ctx);
    let per_layer = texels.len() / charts.len();
    let n = (per_layer as f64).sqrt() as usize;
    let mut flux = 0.0;
    let (mut peak, mut at) = (0f32, [0f32; 2]);
    for (layer, (_, area)) in charts.iter().enumerate() {
        let texel_area = *area as f64 / per_layer as f64;
        for (i, t) in texels[layer * per_layer..(layer + 1) * per_layer].iter().enumerate() {
            assert!(t.iter().all(|v| v.is_finite()), "{name}: non-finite light-map texel");
            flux += t[1] as f64 * texel_area;
            if t[1] > peak {
                peak = t[1];
                at = [((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32];
            }
        }
    }
    (flux, peak, at)
}

/// `block_splats`: the photons of a 2 x 2 block of caustic-map texels whose centres lie within
/// 2 ceil(radius) light-map texels of each other are drawn as one sprite, the others one by
/// one. The splat pass's points that survive clipping (the others are placed outside the clip
/// volume) are exactly that count, taken on the CPU from the caustic map's hits with the
/// shaders' rule (glsl/impostor/lightmap_splat.glsl, `block_fits`), and without the blocks
/// exactly the photons; the light maps agree within 1e-5 of their largest value (f32 sums in
/// another order). On caustic_sphere most blocks fit: fewer than half the sprites remain.
#[test]
fn block_splats_draw_one_sprite_per_close_block() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let splat = |blocks: bool| {
        let o = [format!("render.impostor_lightmap.block_splats={blocks}")];
        let s = common::scene("caustic_sphere", 64, &common::refs(&lightmap(&common::refs(&o))));
        let (mut r, counts) = common::render_counting(&ctx, &s, 1, "impostor_lightmap_splat");
        let points = counts.clipping_primitives;
        let image = r.frame_images().into_iter().find(|i| i.name == "impostor_lightmap_hit_0").expect("hit map");
        let hits = r.read_frame_image(&image).expect("readback").expect("a readable hit map");
        let (maps, charts) = r.read_lightmaps().expect("readback").expect("light maps");
        drop(r);
        (points, hits, image.width as usize, maps, charts.len())
    };
    let (blocked, hits, size, blocked_maps, charts) = splat(true);
    let (single, _, _, single_maps, _) = splat(false);
    assert_eq!(charts, 1, "caustic_sphere's floor is the one receiver");
    let defaults = prism::scene::techniques::ImpostorLightmapParams::default();
    let n = defaults.lightmap_size as f32;
    let r = defaults.filter_radius.ceil();
    let reach = (2.0 * r).min(63.0 - 2.0 * r);
    // The photon of caustic-map texel (x, y) on light map 0: its centre in light-map texels.
    let photon = |x: usize, y: usize| -> Option<[f32; 2]> {
        if x >= size || y >= size {
            return None;
        }
        let h = &hits[4 * (y * size + x)..4 * (y * size + x) + 4];
        (h[3] > 0.0 && (h[2] + 0.5) as u32 == 0).then(|| [h[0] * n, h[1] * n])
    };
    let photons = (0..size * size).filter(|i| photon(i % size, i / size).is_some()).count() as u64;
    let mut expected = 0u64;
    for by in 0..size.div_ceil(2) {
        for bx in 0..size.div_ceil(2) {
            let block: Vec<[f32; 2]> = (0..4).filter_map(|i| photon(2 * bx + (i & 1), 2 * by + (i >> 1))).collect();
            let extent = |a: usize| {
                let (lo, hi) = block.iter().fold((f32::MAX, f32::MIN), |(lo, hi), c| (lo.min(c[a]), hi.max(c[a])));
                hi - lo
            };
            if block.is_empty() {
                continue;
            }
            expected += if extent(0) <= reach && extent(1) <= reach { 1 } else { block.len() as u64 };
        }
    }
    eprintln!("{photons} photons: {blocked} sprites with blocks (expected {expected}), {single} without");
    assert_eq!(single, photons, "one sprite per photon without blocks");
    assert_eq!(blocked, expected, "one sprite per close block, one per photon elsewhere");
    assert!(2 * blocked < single, "caustic_sphere's blocks should mostly fit: {blocked} of {single}");
    let scale = single_maps.iter().flat_map(|t| t.iter()).fold(0f32, |m, v| m.max(v.abs()));
    for (a, b) in blocked_maps.iter().zip(&single_maps) {
        for c in 0..4 {
            assert!((a[c] - b[c]).abs() <= 1e-5 * scale, "light maps differ: {a:?} against {b:?} (largest {scale})");
        }
    }
    common::assert_no_validation_errors(&ctx);
}

/// The apply pass draws only the part of each receiver's chart that its light map's photons
/// can reach (src/technique/impostor/impostor_lightmap.rs, `reach`), since the light map is
/// exactly 0 elsewhere. It must draw every pixel whose bilinear lookup touches a non-zero
/// texel k: those with u n in (k - 1/2, k + 3/2), so the drawn texels must run from k - 1 to
/// k + 1 (clamped to the map, whose edges the drawn rectangle then overhangs). On
/// caustic_sphere the caustic is a small part of the floor (the pass draws 0.138 of its light
/// map, metal_ring 0.302), which is what makes the pass cheaper; a quarter bounds it there.
#[test]
fn the_apply_pass_draws_every_texel_the_light_map_lights() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    for (name, extra) in [
        ("caustic_sphere", &[][..]),
        ("metal_ring", &[][..]),
        ("caustic_sphere", &["render.impostor_lightmap.filter_radius=5.5"][..]),
    ] {
        let s = common::scene(name, 64, &common::refs(&lightmap(extra)));
        let mut r = Renderer::new(&ctx, &s).expect("renderer");
        r.render_frame().expect("frame");
        let (texels, charts) = r.read_lightmaps().expect("readback").expect("light maps");
        let reach = r.read_lightmap_reach().expect("readback").expect("light maps");
        drop(r);
        let per_layer = texels.len() / charts.len();
        let n = (per_layer as f64).sqrt() as u32;
        for (layer, [x0, y0, x1, y1]) in reach.iter().copied().enumerate() {
            let lit: Vec<(u32, u32)> = (0..per_layer as u32)
                .filter(|i| texels[layer * per_layer + *i as usize][..3].iter().any(|&v| v != 0.0))
                .map(|i| (i % n, i / n))
                .collect();
            for &(x, y) in &lit {
                let inside = x0 <= x.saturating_sub(1)
                    && y0 <= y.saturating_sub(1)
                    && x1 >= (x + 1).min(n - 1)
                    && y1 >= (y + 1).min(n - 1);
                assert!(
                    inside,
                    "{name} {extra:?} layer {layer}: lit texel ({x}, {y}) beyond the drawn [{x0}, {x1}] x [{y0}, {y1}]"
                );
            }
            let drawn = if x0 > x1 || y0 > y1 { 0 } else { (x1 - x0 + 1) * (y1 - y0 + 1) };
            let share = f64::from(drawn) / f64::from(n * n);
            eprintln!(
                "{name} {extra:?} layer {layer}: {} lit texels, the apply pass draws {share:.3} of the light map",
                lit.len()
            );
            assert!(!lit.is_empty(), "{name}: no caustic on layer {layer}");
            if name == "caustic_sphere" && extra.is_empty() {
                assert!(share < 0.25, "caustic_sphere: the apply pass draws {share:.3} of the floor's light map");
            }
        }
    }
    common::assert_no_validation_errors(&ctx);
}

#[test]
fn caustic_scenes_render_with_impostor_lightmap() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    for name in ["caustic_sphere", "metal_ring"] {
        let with = common::render_on(&ctx, &common::scene(name, 96, &common::refs(&lightmap(&[]))));
        assert_eq!(non_finite_count(&with.hdr), 0, "{name}");
        for p in ["impostor_lightmap_uv_map", "impostor_lightmap_caustic_map", "impostor_lightmap_splat"] {
            assert!(with.passes.iter().any(|n| n == p), "{name}: {p} missing from {:?}", with.passes);
        }
        let without = common::render_on(&ctx, &common::scene(name, 96, &[]));
        let (a, b) = (common::total(&with.hdr), common::total(&without.hdr));
        eprintln!("{name}: radiance sum with light-map caustics {a:.2}, without {b:.2}");
        assert!(a > b * 1.01, "{name}: the caustic adds no light ({a} vs {b})");
    }
}

/// Every photon deposits its power on the floor (the splat weights sum to 1 and the light
/// map holds irradiance), so the light maps' total flux is the light's flux through the ball
/// times the two Fresnel transmittances: 50 W/sr at 3.8 m from a unit ball of ior 1.5,
/// 9.2395 W. Measured: 9.2340 / 9.2333 / 9.2336 W at caustic maps of 64^2 / 128^2 / 256^2
/// (0.06% low: the caustic map's texels sample the ball's disc with a staircase edge); the
/// 2% tolerance leaves room for that edge and the refractor map's approximate exit points
/// (§4) on other drivers. Peak irradiance 47.9 / 49.4 / 49.6 W/m^2 at the floor's centre.
#[test]
fn lightmap_flux_matches_the_analytic_flux_and_is_stable_in_the_map_size() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let expected = common::sphere_transmitted_flux(50.0, 3.8, 1.0, 1.5);
    let mut fluxes = Vec::new();
    for size in [64, 128, 256] {
        let (f, peak, at) =
            lightmap_flux(&ctx, "caustic_sphere", &[&format!("render.impostor_lightmap.caustic_map_size={size}")]);
        eprintln!("caustic map {size}^2: flux {f:.4} W (expected {expected:.4}), peak {peak:.2} W/m^2 at uv {at:?}");
        fluxes.push(f);
        assert!((f / expected - 1.0).abs() < 0.02, "{size}: flux {f} W, expected {expected} W");
        // The ball is above the floor's centre: so is the focus.
        assert!((at[0] - 0.5).abs() < 0.05 && (at[1] - 0.5).abs() < 0.05, "{size}: peak at {at:?}");
    }
    assert!((fluxes[0] / fluxes[2] - 1.0).abs() < 0.05, "64^2 vs 256^2: {fluxes:?}");
}

/// Against the exact reference (SPPM caustics) on caustic_sphere at 64^2: the light-map
/// caustic lowers the error compared with no caustics, and its focus (the brightest spot of
/// the caustic alone) lies where the reference's is. Measured: see the test output.
#[test]
fn impostor_lightmap_approaches_the_reference_on_caustic_sphere() {
    if !common::in_own_process() {
        return;
    }
    approaches_the_reference("caustic_sphere", 0.7);
}

/// The same on metal_ring: the reflective caustic of a mirror ring under a directional light
/// (a mirror needs no refractor map). Measured: RMSE none 0.3021, caustic map 32^2 0.3264
/// (the thin ring covers few texels: few, strong photons), 128^2 0.1741; focus (20, 31) in
/// both at 128^2, one pixel apart at 32^2.
#[test]
fn impostor_lightmap_approaches_the_reference_on_metal_ring() {
    if !common::in_own_process() {
        return;
    }
    approaches_the_reference("metal_ring", 0.7);
}

fn approaches_the_reference(scene: &str, ratio: f64) {
    let ctx = common::context(false);
    let size = 64;
    let s = common::scene(scene, size, &[]);
    let settings = ReferenceSettings { spp: 16, photons: 1 << 21, ..Default::default() };
    let mut r = Reference::new(&ctx, &s, &settings).unwrap();
    r.run_all(|_, _| {}).unwrap();
    let reference = r.image();
    let reference_caustic = r.caustic_image();
    drop(r);
    let none = common::render_on(&ctx, &s);
    let e_none = rmse_rgba(&none.hdr, &reference);
    let mut errors = Vec::new();
    for map in [32, 128] {
        let c = common::scene(
            scene,
            size,
            &common::refs(&lightmap(&[&format!("render.impostor_lightmap.caustic_map_size={map}")])),
        );
        let img = common::render_on(&ctx, &c);
        let e = rmse_rgba(&img.hdr, &reference);
        errors.push(e);
        let caustic: Vec<f32> = img.hdr.iter().zip(&none.hdr).map(|(a, b)| a - b).collect();
        let (w, h) = (size as usize, size as usize);
        let (ours, theirs) = (common::brightest(&caustic, w, h), common::brightest(&reference_caustic, w, h));
        eprintln!("{scene}, caustic map {map}^2: RMSE {e:.4} (none {e_none:.4}); focus {ours:?}, reference {theirs:?}");
        let dist = ((ours.0 as f32 - theirs.0 as f32).powi(2) + (ours.1 as f32 - theirs.1 as f32).powi(2)).sqrt();
        assert!(dist <= 3.0, "focus {ours:?} vs reference {theirs:?}");
    }
    assert!(errors[1] < ratio * e_none, "{scene}: impostor_lightmap must beat no caustics: {errors:?} vs {e_none}");
}

/// No NaN or Inf: the light grazing the ball (level with its centre, beside it), the light
/// inside the ball's bounding sphere and at its centre, a light map smaller than a splat,
/// the widest filter, no Hit() iterations; photons without a hit are dropped, not NaN.
#[test]
fn stable_at_degenerate_lights_and_parameters() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let cases: &[&[&str]] = &[
        &["lights.0.position=[3, 1.2, 0]"],
        &["lights.0.position=[1.001, 1.2, 0]"],
        &["lights.0.position=[0.3, 1.5, 0]"],
        &["lights.0.position=[0, 1.2, 0]"],
        &["render.impostor_lightmap.lightmap_size=4", "render.impostor_lightmap.filter_radius=16"],
        &["render.impostor_lightmap.iterations=0", "render.impostor_lightmap.caustic_map_size=4"],
        &["render.impostor_lightmap.filter_radius=0.75", "render.impostor_lightmap.uv_map_size=4"],
    ];
    for extra in cases {
        let s = common::scene("caustic_sphere", 48, &common::refs(&lightmap(extra)));
        let mut r = Renderer::new(&ctx, &s).expect("renderer");
        r.render_frame().expect("frame");
        let hdr = r.read_hdr().unwrap();
        let (texels, _) = r.read_lightmaps().unwrap().unwrap();
        drop(r);
        assert_eq!(non_finite_count(&hdr), 0, "{extra:?}");
        assert!(texels.iter().flatten().all(|v| v.is_finite()), "{extra:?}: light map");
    }
    common::assert_no_validation_errors(&ctx);
}

/// Moving the ball with `Renderer::move_object` re-centres the uv map (§6) and refits the
/// caustic map's frustum: the light maps then match a renderer made for the moved scene.
#[test]
fn moving_the_refractor_moves_the_caustic() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let peak = |texels: &[[f32; 4]]| -> (usize, f64) {
        let i = (0..texels.len()).max_by(|&a, &b| texels[a][1].total_cmp(&texels[b][1])).unwrap();
        (i, texels.iter().map(|t| t[1] as f64).sum())
    };
    let s = common::scene("caustic_sphere", 48, &common::refs(&lightmap(&[])));
    let mut r = Renderer::new(&ctx, &s).unwrap();
    r.render_frame().unwrap();
    let (before, _) = r.read_lightmaps().unwrap().unwrap();
    assert!(r.move_object("ball", glam::Vec3::new(0.8, 1.2, 0.3)).unwrap());
    r.render_frame().unwrap();
    let (moved, _) = r.read_lightmaps().unwrap().unwrap();
    drop(r);
    let s = common::scene("caustic_sphere", 48, &common::refs(&lightmap(&["objects.1.center=[0.8, 1.2, 0.3]"])));
    let mut r = Renderer::new(&ctx, &s).unwrap();
    r.render_frame().unwrap();
    let (fresh, _) = r.read_lightmaps().unwrap().unwrap();
    drop(r);
    common::assert_no_validation_errors(&ctx);
    let (p_before, p_moved, p_fresh) = (peak(&before), peak(&moved), peak(&fresh));
    eprintln!("peak texel / light-map sum: before {p_before:?}, moved {p_moved:?}, fresh {p_fresh:?}");
    assert_ne!(p_before.0, p_moved.0, "the caustic did not move");
    let n = (moved.len() as f64).sqrt() as i64;
    let (a, b) = (p_moved.0 as i64, p_fresh.0 as i64);
    assert!((a % n - b % n).abs() <= 1 && (a / n - b / n).abs() <= 1, "moved {a} vs fresh {b}");
    assert!((p_moved.1 / p_fresh.1 - 1.0).abs() < 1e-3, "{p_moved:?} vs {p_fresh:?}");
}

/// A box receiver gets one chart and light map per face: caustic_sphere with its floor made a
/// box whose top face is the floor catches the same flux (the analytic 9.2395 W, as above).
#[test]
fn box_receivers_catch_the_caustic_on_their_faces() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let base = std::fs::read_to_string(prism::scene::benchmark_scene_path("caustic_sphere")).unwrap();
    let text = base.replacen(
        "shape = \"quad\"\ncenter = [0, 0, 0]\nsize = [8, 8]\nnormal = [0, 1, 0]",
        "shape = \"box\"\ncenter = [0, -0.5, 0]\nsize = [8, 1, 8]",
        1,
    );
    assert_ne!(text, base, "caustic_sphere's floor is no longer the expected quad");
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("lightmap_box_floor.toml");
    std::fs::write(&path, text).unwrap();
    // The baseline first: `without` (o without the last entry) has no caustic.
    let mut o: Vec<String> = ["camera.width=64", "camera.height=64"].iter().map(|s| s.to_string()).collect();
    o.extend(prism::scene::BASELINE.iter().map(|s| s.to_string()));
    o.push("render.caustics=impostor_lightmap".into());
    let s = prism::scene::load(&path, &o).unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    r.render_frame().unwrap();
    let hdr = r.read_hdr().unwrap();
    let (texels, charts) = r.read_lightmaps().unwrap().unwrap();
    drop(r);
    common::assert_no_validation_errors(&ctx);
    assert_eq!(non_finite_count(&hdr), 0);
    assert_eq!(charts.len(), 6, "one light map per face");
    let per_layer = texels.len() / 6;
    let fluxes: Vec<f64> = (0..6)
        .map(|f| {
            let texel_area = charts[f].1 as f64 / per_layer as f64;
            texels[f * per_layer..(f + 1) * per_layer].iter().map(|t| t[1] as f64 * texel_area).sum()
        })
        .collect();
    eprintln!("box faces' flux: {fluxes:?} W");
    let total: f64 = fluxes.iter().sum();
    let expected = common::sphere_transmitted_flux(50.0, 3.8, 1.0, 1.5);
    assert!((total / expected - 1.0).abs() < 0.02, "flux {total} W, expected {expected} W");
    // All of it on the top face (the face whose normal is +Y).
    assert!(fluxes.iter().filter(|&&f| f > 0.0).count() == 1, "{fluxes:?}");
    let without = common::render_on(&ctx, &prism::scene::load(&path, &o[..o.len() - 1]).unwrap());
    assert!(total_radiance(&hdr) > 1.01 * total_radiance(&without.hdr), "the caustic is not applied");
}

fn total_radiance(hdr: &[f32]) -> f64 {
    common::total(hdr)
}

/// The apply pass reaches every pixel of its receiver: a floor lit, through a tall mirror, by
/// the reflection of a directional light that covers all of it (the caustic is the mirror's
/// reflected beam, E cos 45 deg), seen by a camera that the floor extends behind (so its
/// chart's rectangle crosses the camera's plane and is clipped). Every pixel whose centre ray
/// meets the floor, away from its edges, gains radiance from the caustic; a pass that drew
/// less than each chart (a rectangle short of the chart's edge, or one dropped where it
/// crosses the camera's plane) leaves such pixels without.
#[test]
fn the_apply_pass_covers_its_whole_receiver() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let text = r#"
name = "mirrored_floor"
[camera]
position = [0, 1.5, 2.5]
target = [0, 0, -1.5]
up = [0, 1, 0]
vfov_deg = 70
width = 96
height = 96
[environment]
type = "constant"
radiance = 0
[[lights]]
type = "directional"
direction = [1, -1, 0]
irradiance = 2
[materials.floor]
type = "diffuse"
albedo = 0.8
[materials.mirror]
type = "mirror"
reflectance = 1
[[objects]]
name = "floor"
material = "floor"
shape = "quad"
center = [0, 0, 0]
size = [8, 8]
normal = [0, 1, 0]
[[objects]]
name = "mirror"
material = "mirror"
shape = "quad"
center = [5, 5, 0]
size = [10, 12]
normal = [-1, 0, 0]
"#;
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("lightmap_mirrored_floor.toml");
    std::fs::write(&path, text).unwrap();
    let mut o: Vec<String> = prism::scene::BASELINE.iter().map(|s| s.to_string()).collect();
    let without = common::render_on(&ctx, &prism::scene::load(&path, &o).unwrap());
    // Photons dense enough for a smooth beam: 512^2 over the mirror, gathered into 64^2
    // light-map texels of 12.5 cm (the default 128^2 photons in 256^2 texels leave a dotted
    // pattern, one splat per photon).
    o.extend(
        [
            "render.caustics=impostor_lightmap",
            "render.impostor_lightmap.caustic_map_size=512",
            "render.impostor_lightmap.lightmap_size=64",
        ]
        .map(String::from),
    );
    let s = prism::scene::load(&path, &o).unwrap();
    let with = common::render_on(&ctx, &s);
    common::assert_no_validation_errors(&ctx);
    assert_eq!(non_finite_count(&with.hdr), 0);
    // The mirror's beam on the floor: irradiance 2 W/m^2 across the beam, arriving at 45 deg
    // (E = 2 cos 45 on the floor), times albedo / pi.
    let expected = 2.0 * std::f64::consts::FRAC_1_SQRT_2 * 0.8 / std::f64::consts::PI;
    let (w, h) = (s.camera.width as usize, s.camera.height as usize);
    let (mut floor, mut dark) = (0, Vec::new());
    let mut sum = 0.0;
    for y in 0..h {
        for x in 0..w {
            // The pixel's centre ray against the floor (y = 0), kept 0.2 m inside its edges.
            let (o, d) = s.camera.primary_ray(x as u32, y as u32);
            if d.y >= 0.0 {
                continue;
            }
            let p = o + d * (-o.y / d.y);
            if p.x.abs() > 3.8 || p.z.abs() > 3.8 {
                continue;
            }
            floor += 1;
            let i = 4 * (y * w + x) + 1;
            let added = f64::from(with.hdr[i] - without.hdr[i]);
            sum += added;
            if added < 0.5 * expected {
                dark.push((x, y, added));
            }
        }
    }
    eprintln!(
        "floor pixels {floor}, mean caustic radiance {:.4} (expected {expected:.4}), below half: {}",
        sum / floor as f64,
        dark.len()
    );
    assert!(floor > w * h / 3, "the camera sees too little of the floor ({floor} pixels)");
    assert!(dark.is_empty(), "{} floor pixels without the caustic, e.g. {:?}", dark.len(), &dark[..dark.len().min(5)]);
}
