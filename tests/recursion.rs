//! Hu & Qin 2007 §2.2.1: recursive refraction through the impostors of *other dielectrics*
//! (src/technique/refraction/nearby_impostors.rs, glsl/nearby/impostor_body.glsl). Every dielectric is its
//! own OBJ_R with its own rectangle set, and a dielectric OBJ_k's TEX_k shows it refracting:
//! the environment at level 0, the level n - 1 impostors of its own set at level n. Measured
//! on assets/scenes/two_glass_balls.toml (glass ball B behind glass ball A) against prism's
//! exact reference; the pass list, the finiteness at the extremes, and (in the last test) the
//! single-refractor scenes staying as they were.
mod common;

use common::{assert_finite, context, render_on, scene};
use prism::reference::{Reference, ReferenceSettings};

const SIZE: u32 = 96;

/// The pixels whose centre ray (SCENES.md's pinhole) hits ball A (`objects.3`, centre
/// (-0.35, -0.2, 0.6), radius 0.6): A is the nearest object wherever its sphere is hit, since
/// nothing stands between it and the camera.
fn ball_a_mask(s: &prism::scene::Scene) -> Vec<bool> {
    ball_mask(s, 3)
}

/// The pixels whose centre ray hits the sphere of object `object`.
fn ball_mask(s: &prism::scene::Scene, object: usize) -> Vec<bool> {
    let Some(prism::scene::Analytic::Sphere { center: c, radius: r }) = s.objects[object].analytic else {
        panic!("object {object} is not a sphere")
    };
    let (w, h) = (s.camera.width, s.camera.height);
    let eye = s.camera.position;
    let forward = (s.camera.target - eye).normalize();
    let right = forward.cross(s.camera.up).normalize();
    let up = right.cross(forward);
    let tan = (s.camera.vfov_deg.to_radians() * 0.5).tan();
    let aspect = w as f32 / h as f32;
    let mut mask = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let x = (2.0 * (i as f32 + 0.5) / w as f32 - 1.0) * tan * aspect;
            let y = (1.0 - 2.0 * (j as f32 + 0.5) / h as f32) * tan;
            let d = (forward + x * right + y * up).normalize();
            let o = eye - c;
            let b = o.dot(d);
            mask.push(b * b - (o.length_squared() - r * r) > 0.0 && b < 0.0);
        }
    }
    mask
}

/// RMSE of linear radiance over the pixels where `mask` is set.
fn masked_rmse(a: &[f32], b: &[f32], mask: &[bool]) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (k, &m) in mask.iter().enumerate() {
        if m {
            for c in 0..3 {
                let d = (a[4 * k + c] - b[4 * k + c]) as f64;
                sum += d * d;
            }
            n += 3;
        }
    }
    (sum / n.max(1) as f64).sqrt()
}

/// The lookup these tests' bounds were derived with, in the refraction pass and inside the
/// recursive levels' textures: Fig. 13's closest rectangle (render.hu_qin.nearby_lookup and
/// recursive_lookup = "paper"). They measure §2.2.1's recursion and the dielectric's exit
/// inside the impostor textures, not the choice of rectangle, which tests/nearby.rs measures;
/// pinned so that those keys' defaults leave them as derived.
const PAPER_LOOKUP: [&str; 2] = ["render.hu_qin.nearby_lookup=paper", "render.hu_qin.recursive_lookup=paper"];

/// two_glass_balls with Hu & Qin's refraction (the technique its file selects), then `extra`.
fn two_balls(size: u32, extra: &[&str]) -> prism::scene::Scene {
    let mut o = vec!["render.refraction=hu_qin"];
    o.extend(PAPER_LOOKUP);
    o.extend_from_slice(extra);
    scene("two_glass_balls", size, &o)
}

/// The pass list: one recursion pass per level, and none where no rectangle stands for a
/// specular object (one refractor among diffuse objects), whatever `recursion_depth` says.
/// Loads two_glass_balls at `size`^2 with ball B replaced by the object `b` (scene-file text),
/// lit by the environment only (radiance 1, the light off): what B shows at level 0 (the
/// environment) and at level 1 (the floor, wall and box) then differ the most. `tag` names
/// the temporary scene file (one per test: tests run in parallel).
fn b_replaced(tag: &str, b: &str, size: u32) -> impl Fn(&[&str]) -> prism::scene::Scene {
    let path = prism::scene::benchmark_scene_path("two_glass_balls");
    let text = std::fs::read_to_string(&path).unwrap();
    let ball_b =
        "name = \"ball_b\"\nmaterial = \"glass\"\nshape = \"sphere\"\ncenter = [0.5, -0.2, -1.2]\nradius = 0.8";
    assert!(text.contains(ball_b), "two_glass_balls.toml changed: update this test");
    let dir = common::ScratchDir::new(&format!("prism-recursion-{tag}"));
    let name = format!("glass_{tag}.toml");
    std::fs::write(dir.path().join(&name), text.replace(ball_b, b)).unwrap();
    // The closure owns the directory: the file lives as long as scenes are loaded from it.
    move |extra: &[&str]| {
        let mut o = vec![format!("camera.width={size}"), format!("camera.height={size}")];
        o.extend(["environment.radiance=1", "lights.0.intensity=0"].map(String::from));
        o.extend(PAPER_LOOKUP.map(String::from));
        o.extend(extra.iter().map(|s| s.to_string()));
        prism::scene::load(&dir.path().join(&name), &o).unwrap()
    }
}

#[test]
fn recursion_levels_follow_the_scene() {
    if !common::in_own_process() {
        return;
    }
    let names = |s: &prism::scene::Scene| -> Vec<&'static str> {
        prism::renderer::plan::plan(s).iter().map(|p| p.name).filter(|n| n.contains("nearby")).collect()
    };
    let back = "refraction_hu_qin_nearby_back";
    // With recursion, the diffuse textures (floor, wall, box) are rendered at level 0 only and
    // copied into the other array of the ping-pong (`_copy`); without it nothing is copied.
    let copy = "refraction_hu_qin_nearby_copy";
    assert_eq!(names(&two_balls(32, &["render.hu_qin.recursion_depth=0"])), [back, "refraction_hu_qin_nearby"]);
    assert_eq!(
        names(&two_balls(32, &["render.hu_qin.recursion_depth=3"])),
        [
            back,
            "refraction_hu_qin_nearby",
            copy,
            "refraction_hu_qin_nearby_r1",
            "refraction_hu_qin_nearby_r2",
            "refraction_hu_qin_nearby_r3"
        ]
    );
    // The full exit search renders the front faces in the same pass as the back faces.
    assert_eq!(
        names(&two_balls(32, &["render.hu_qin.recursion_depth=0", "render.hu_qin.recursive_exit=\"full\""])),
        [back, "refraction_hu_qin_nearby"]
    );
    // The bounding-sphere exit needs no back faces.
    assert_eq!(
        names(&two_balls(32, &["render.hu_qin.recursion_depth=1", "render.hu_qin.recursive_exit=\"bounding_sphere\""])),
        ["refraction_hu_qin_nearby", copy, "refraction_hu_qin_nearby_r1"]
    );
    // Ball B made diffuse: A is the only specular object, nothing to recurse into and no
    // dielectric impostor.
    assert_eq!(
        names(&two_balls(32, &["render.hu_qin.recursion_depth=3", "objects.4.material=\"box\""])),
        ["refraction_hu_qin_nearby"]
    );
    // Each ball is its own OBJ_R and a rectangle in the other's set.
    let s = two_balls(32, &[]);
    let layout = prism::technique::refraction::nearby_impostors::nearby_layout(&s, 1);
    assert_eq!(layout.sets.iter().map(|s| s.object).collect::<Vec<_>>(), [3, 4]);
    for set in &layout.sets {
        let objects: Vec<usize> =
            layout.rects[set.first as usize..(set.first + set.count) as usize].iter().map(|r| r.object).collect();
        assert!(!objects.contains(&set.object), "set of {} holds itself: {objects:?}", set.object);
        assert_eq!(objects.len(), 4, "{objects:?}");
        assert!(objects.contains(&(7 - set.object)), "set of {} lacks the other ball: {objects:?}", set.object);
    }
    assert_eq!(layout.levels, 1);
}

/// A's pixels against the exact reference (64 spp, no photons: the same noisy image for every
/// setting, so differences between settings are not noise) for recursion_depth 0, 1, 2, and
/// B's visibility through A. Measured at 96^2 on lavapipe (default: the back-layer exit):
/// - A's RMSE: depth 0 0.04971, depth 1 0.04970, depth 2 0.04970 (with the bounding-sphere
///   exit, depth 1: 0.04955); with B moved out of the scene (what A showed before each
///   dielectric had its own rectangle set: B was never drawn into a texture) 0.05917. Seeing B
///   through A is the gain (16%). The recursion itself changes only the 7 pixels of A where
///   B's texture differs from the environment it showed at level 0 (radiance 0.05 here, close
///   to the shadowed floor that B shows there). Over those pixels the mean radiance moves
///   from 0.047 (depth 0) to 0.108 (depth 1) against the reference's 0.096, but the RMSE there
///   does not fall (0.0710 -> 0.0717; 0.0581 with the bounding-sphere exit): B's texture holds
///   the right brightness in slightly wrong places.
/// - With B moved to (0.3, 0.2, -1.0), behind A's centre, depth 1 is *worse* over A (0.0421 ->
///   0.0471; 54 pixels change, mean 0.048 -> 0.156 against the reference's 0.067): TEX_B holds
///   B as seen along the one direction O_A -> O_B, but A is a lens and the rays it sends to B
///   arrive from widely varying directions, for which B refracts other parts of the scene
///   (Hu & Qin's assumption that an object looks the same from everywhere on OBJ_R, §2.2.1,
///   breaks worst for a refractive OBJ_k). Reported in docs/scene-format.md.
#[test]
fn recursion_against_the_reference_over_ball_a() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let s = two_balls(SIZE, &[]);
    let mask = ball_a_mask(&s);
    let pixels = mask.iter().filter(|&&m| m).count();
    assert!(pixels > 500, "ball A covers only {pixels} pixels");
    let mut r = Reference::new(&ctx, &s, &ReferenceSettings { spp: 64, photons: 0, ..Default::default() }).unwrap();
    r.run_all(|_, _| {}).unwrap();
    let reference = r.image();
    drop(r);
    let images: Vec<Vec<f32>> = (0..=2)
        .map(|d| {
            let r = render_on(&ctx, &two_balls(SIZE, &[&format!("render.hu_qin.recursion_depth={d}")]));
            assert_finite(&format!("recursion_depth {d}"), &r.hdr);
            r.hdr
        })
        .collect();
    let errors: Vec<f64> = images.iter().map(|h| masked_rmse(h, &reference, &mask)).collect();
    // Ball B moved out of the scene: what A shows without B.
    let without_b = render_on(&ctx, &two_balls(SIZE, &["objects.4.center=[0.5, -0.2, -40]"])).hdr;
    let e_without = masked_rmse(&without_b, &reference, &mask);
    let b_effect: Vec<f64> = images.iter().map(|h| masked_rmse(h, &without_b, &mask)).collect();
    let changed: Vec<bool> = images[0]
        .chunks(4)
        .zip(images[1].chunks(4))
        .zip(&mask)
        .map(|((a, b), &m)| m && (0..3).any(|c| (a[c] - b[c]).abs() > 0.01))
        .collect();
    let n_changed = changed.iter().filter(|&&m| m).count();
    let mean = |h: &[f32]| {
        let s: f64 = changed
            .iter()
            .enumerate()
            .filter(|(_, &m)| m)
            .map(|(k, _)| (h[4 * k] + h[4 * k + 1] + h[4 * k + 2]) as f64)
            .sum();
        s / (3 * n_changed.max(1)) as f64
    };
    let ch: Vec<f64> = images.iter().map(|h| masked_rmse(h, &reference, &changed)).collect();
    eprintln!(
        "changed 0->1: {n_changed} px, RMSE there {:.4} {:.4} {:.4}, mean d0 {:.4} d1 {:.4} ref {:.4}",
        ch[0],
        ch[1],
        ch[2],
        mean(&images[0]),
        mean(&images[1]),
        mean(&reference)
    );
    // B where A does not cover it: B's own refraction in the main pass.
    let bmask: Vec<bool> = ball_mask(&s, 4).iter().zip(&mask).map(|(&b, &a)| b && !a).collect();
    let eb: Vec<f64> = images.iter().map(|h| masked_rmse(h, &reference, &bmask)).collect();
    eprintln!("B's own {} pixels: RMSE {:.5} {:.5} {:.5}", bmask.iter().filter(|&&m| m).count(), eb[0], eb[1], eb[2]);
    eprintln!(
        "two_glass_balls {SIZE}^2, {pixels} pixels of A, RMSE vs reference: depth 0 {:.5}, 1 {:.5}, 2 {:.5}; \
         B moved away {e_without:.5}; RMSE(image, image without B) over A: {:.5} {:.5} {:.5}",
        errors[0], errors[1], errors[2], b_effect[0], b_effect[1], b_effect[2]
    );
    // The documented simplification: the bounding sphere as the glass textures' exit.
    let sphere = render_on(&ctx, &two_balls(SIZE, &["render.hu_qin.recursive_exit=\"bounding_sphere\""])).hdr;
    eprintln!(
        "depth 1 with the bounding-sphere exit: RMSE over A {:.5}, over the changed pixels {:.4}",
        masked_rmse(&sphere, &reference, &mask),
        masked_rmse(&sphere, &reference, &changed)
    );
    // B is visible through A: A's pixels differ from the image without B (measured 0.0418 at
    // every depth; a texture set without B, as before, gives 0).
    assert!(b_effect[1] > 0.02, "B is not visible through A: {b_effect:?}");
    // ... and showing it lowers A's error (measured 16%; 10% margin).
    assert!(errors[1] < 0.9 * e_without, "B through A should lower A's error: {e_without} -> {}", errors[1]);
    // The recursion (depth 1 against 0) changes the pixels of A where B's texture is seen
    // (measured 7) and brings their mean radiance to the reference's (measured |0.108 - 0.096|
    // against |0.047 - 0.096|: a quarter of the gap; asserted: less than half), without
    // making A worse overall (measured 0.04970 against 0.04971; 1% allowed for another
    // rasteriser's placement of those few pixels). It does not lower A's RMSE measurably:
    // see the comment above.
    assert!(n_changed >= 3, "the recursion changed only {n_changed} pixels of A");
    // ... and only those: the diffuse textures that A shows elsewhere are kept from level 0
    // (rendered once, copied into the other array by refraction_hu_qin_nearby_copy). Measured
    // 7 pixels; a level that lost them (not copied, or cleared) changes most of A's pixels.
    assert!(n_changed <= 40, "the recursion changed {n_changed} pixels of A: diffuse textures lost at level 1?");
    let (m0, m1, mr) = (mean(&images[0]), mean(&images[1]), mean(&reference));
    assert!(
        (m1 - mr).abs() < 0.5 * (m0 - mr).abs(),
        "depth 1 should be closer to the reference's mean: {m0} {m1} {mr}"
    );
    assert!(errors[1] < 1.01 * errors[0], "depth 1 should not make A worse: {errors:?}");
}

/// Fig. 18's experiment one level down: ball B of ior 1 (its own material) bends nothing, so
/// A must show through B what lies behind B, as if B were not there. Lit by the environment
/// only (radiance 1, the light off), so that B casts no shadow and the scene with B moved away
/// is the exact answer. At level 0 B's texture shows the environment (1) through B; at level 1
/// the floor, wall and box of B's own rectangle set. The floor and wall have one albedo (0.3)
/// here, not their checker: the checker's edges fall a texel differently in B's 256^2 texture
/// than in the camera's pixels, an error of the texture's resolution that grows with the
/// checker's contrast (0.148 RMSE over the changed pixels with the environment's irradiance
/// at 0.59 pi on the floor, 0.377 at its exact pi), and is not what this test asks about.
#[test]
fn ior_one_ball_b_shows_what_lies_behind_it_at_level_one() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let base = [
        "environment.radiance=1",
        "lights.0.intensity=0",
        "materials.clear={type=\"dielectric\", ior=1.0}",
        "objects.4.material=\"clear\"",
        "materials.checker.checker.a=0.3",
        "materials.checker.checker.b=0.3",
    ];
    let render = |extra: &str| {
        let mut o = base.to_vec();
        o.push(extra);
        let r = render_on(&ctx, &two_balls(SIZE, &o));
        assert_finite(extra, &r.hdr);
        r.hdr
    };
    let without_b = render("objects.4.center=[0.5, -0.2, -40]");
    let d0 = render("render.hu_qin.recursion_depth=0");
    let d1 = render("render.hu_qin.recursion_depth=1");
    let mask = ball_a_mask(&two_balls(SIZE, &[]));
    let (e0, e1) = (masked_rmse(&d0, &without_b, &mask), masked_rmse(&d1, &without_b, &mask));
    // Where B's texture is seen through A: the pixels the recursion changed.
    let changed: Vec<bool> = d0
        .chunks(4)
        .zip(d1.chunks(4))
        .zip(&mask)
        .map(|((a, b), &m)| m && (0..3).any(|c| (a[c] - b[c]).abs() > 0.05))
        .collect();
    let n = changed.iter().filter(|&&m| m).count();
    let (c0, c1) = (masked_rmse(&d0, &without_b, &changed), masked_rmse(&d1, &without_b, &changed));
    eprintln!("B of ior 1, A's pixels vs the scene without B: RMSE depth 0 {e0:.4}, depth 1 {e1:.4}; over the {n} pixels that changed: {c0:.4}, {c1:.4}");
    // A recursion that does not reach B's texture changes no pixel (n = 0) or leaves the
    // level-0 error (measured 0.63). With one albedo, what level 1 shows through B is what
    // lies behind it, to rounding (measured 0.0000 over 76 pixels at 96^2, lavapipe); half of
    // level 0's error would still pass a level that shows B's own texture half-way.
    assert!(n >= 20, "the recursion changed only {n} of A's pixels");
    assert!(c1 < 0.5 * c0, "level 1 should show what lies behind B: {c0} -> {c1}");
    assert!(e1 < e0, "{e0} -> {e1}");
}

/// The extremes of a dielectric OBJ_k's texture at every recursion depth: B's ior near 1,
/// below 1 (a bubble: total internal reflection inside), large, dispersive, and a grazing
/// camera in the floor's plane; both balls sharing one centre (O_R O_k of zero length).
#[test]
fn recursive_refraction_is_finite_at_the_extremes() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    // Each setting's renderer is built beside the previous one's, whose pipelines it shares.
    let mut last = None;
    // The default (back-facing) exit at every depth, and the full search (dividing pixel,
    // Fig. 5's test, front faces) at depth 1.
    for (depth, exit) in [(0, "back_facing"), (1, "back_facing"), (3, "back_facing"), (1, "full")] {
        for extra in [
            &["materials.glass.ior=1.0"][..],
            &["materials.glass.ior=1.0001"],
            &["materials.glass.ior=0.75"],
            &["materials.glass.ior=0.5"],
            &["materials.glass.ior=4.0"],
            &["materials.glass.ior=[1.45, 1.5, 1.55]"],
            &["materials.glass.absorption=[100, 0, 1]"],
            &["camera.position=[0, -0.999, 5]"],
            &["objects.4.center=[-0.35, -0.2, 0.6]", "objects.4.radius=0.3"],
        ] {
            let mut o = vec![
                format!("render.hu_qin.recursion_depth={depth}"),
                format!("render.hu_qin.recursive_exit=\"{exit}\""),
            ];
            o.extend(extra.iter().map(|s| s.to_string()));
            let r = common::render_after(&ctx, &two_balls(48, &common::refs(&o)), &mut last);
            assert_finite(&format!("{extra:?} depth {depth} {exit}"), &r.hdr);
        }
    }
    drop(last);
    common::assert_no_validation_errors(&ctx);
}

/// Synchronization validation over several frames with two recursion levels of dielectric
/// textures (both balls' sets in one array pair, ping-ponged every level, the diffuse layers
/// copied between them), with the full exit search's front faces.
#[test]
fn recursive_refraction_has_no_sync_hazard() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(true);
    let s = two_balls(32, &["render.hu_qin.recursion_depth=2", "render.hu_qin.recursive_exit=\"full\""]);
    let mut r = prism::renderer::Renderer::new(&ctx, &s).unwrap();
    for _ in 0..3 {
        r.render_frame().unwrap();
    }
    assert_finite("recursion_depth 2", &r.read_hdr().unwrap());
    drop(r);
    common::assert_no_validation_errors(&ctx);
}

/// The stated limits: with ten glass balls, at most MAX_NEARBY_SETS sets (the first eight
/// dielectrics in scene order) of at most MAX_NEARBY_RECTS rectangles, the nearest kept; the
/// other two balls are named as having no set and see the environment only. It renders
/// (tiny textures) with finite radiance and no validation error.
#[test]
fn many_dielectrics_keep_the_stated_limits() {
    if !common::in_own_process() {
        return;
    }
    // two_glass_balls' camera, light and materials; its objects replaced by a floor and ten
    // balls in two rows.
    let path = prism::scene::benchmark_scene_path("two_glass_balls");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut toml = text[..text.find("[[objects]]").unwrap()].to_string();
    toml += "[[objects]]\nname = \"floor\"\nmaterial = \"checker\"\nshape = \"quad\"\ncenter = [0, -1, 0]\n";
    toml += "size = [10, 10]\nnormal = [0, 1, 0]\n";
    for i in 0..10 {
        let (x, z) = ((i % 5) as f32 - 2.0, -((i / 5) as f32) * 1.2);
        toml += &format!(
            "[[objects]]\nname = \"ball{i}\"\nmaterial = \"glass\"\nshape = \"sphere\"\ncenter = [{x}, -0.6, {z}]\nradius = 0.4\n"
        );
    }
    toml += "[render]\nrefraction = \"hu_qin\"\n";
    let dir = common::ScratchDir::new("prism-recursion");
    let file = dir.path().join("ten_balls.toml");
    std::fs::write(&file, toml).unwrap();
    let o = ["camera.width=32", "camera.height=32", "render.hu_qin.impostor_resolution=16"].map(String::from);
    let s = prism::scene::load(&file, &o).unwrap();
    let layout = prism::technique::refraction::nearby_impostors::nearby_layout(&s, 1);
    let max_sets = prism::MAX_NEARBY_SETS as usize;
    assert_eq!(layout.sets.len(), max_sets);
    assert_eq!(layout.sets.iter().map(|s| s.object).collect::<Vec<_>>(), (1..=max_sets).collect::<Vec<_>>());
    assert_eq!(layout.without_set, [9, 10]);
    for set in &layout.sets {
        // 10 other objects (9 balls + the floor), the nearest 8 kept.
        assert_eq!(set.count, prism::MAX_NEARBY_RECTS);
        assert_eq!(set.dropped.len(), 2, "{set:?}");
    }
    let reason = prism::renderer::plan::plan(&s).into_iter().find(|p| p.name == "refraction_hu_qin_nearby").unwrap();
    assert!(reason.reason.contains("ball8, ball9 without a rectangle set"), "{}", reason.reason);
    let ctx = context(false);
    let r = render_on(&ctx, &s);
    assert_finite("ten balls", &r.hdr);
    // 64 textures of 2048^2 texels would need 4 GiB per array: refused with the key to lower.
    let o = ["camera.width=32", "camera.height=32", "render.hu_qin.impostor_resolution=2048"].map(String::from);
    let big = prism::scene::load(&file, &o).unwrap();
    let e = prism::renderer::Renderer::new(&ctx, &big).err().expect("4 GiB of impostor textures per array");
    assert!(e.to_string().contains("lower impostor_resolution"), "{e}");
}

/// The exit of a dielectric OBJ_k that is not a ball: B replaced by a glass cube (edge 1.2,
/// centre (0.5, -0.4, -1.2)), where the bounding sphere (radius 1.04) lies far from the faces.
/// A's pixels against the reference (64 spp, no photons) for depth 0, and depth 1 with each
/// exit. Measured at 96^2 on lavapipe: RMSE over A 0.24519 (depth 0), 0.24363 (depth 1, back
/// layer), 0.24097 (depth 1, bounding sphere); the 15 pixels the recursion changes go from
/// 0.4508 to 0.3894. The exits differ on only 4 pixels (back layer 0.5821, bounding sphere
/// 0.1086 there): at this size the cube is seen through A in a handful of pixels, and there the
/// back-layer search (the default, `"back_facing"`, §4's shortcut) lands worse than the sphere.
/// `"full"` (Fig. 5's test with the dividing pixel) gave the same 0.24363: no front-facing
/// exit of the cube is seen through A. So the paper's exit search is not shown to
/// buy accuracy here; docs/scene-format.md reports it.
#[test]
fn exit_of_a_glass_cube_behind_ball_a() {
    if !common::in_own_process() {
        return;
    }
    let cube =
        "name = \"cube_b\"\nmaterial = \"glass\"\nshape = \"box\"\ncenter = [0.5, -0.4, -1.2]\nsize = [1.2, 1.2, 1.2]";
    let load = b_replaced("cube", cube, SIZE);
    let ctx = context(false);
    let s = load(&[]);
    let mask = ball_a_mask(&s);
    let mut r = Reference::new(&ctx, &s, &ReferenceSettings { spp: 64, photons: 0, ..Default::default() }).unwrap();
    r.run_all(|_, _| {}).unwrap();
    let reference = r.image();
    drop(r);
    let error = |extra: &[&str]| {
        let h = render_on(&ctx, &load(extra)).hdr;
        assert_finite(&format!("{extra:?}"), &h);
        (masked_rmse(&h, &reference, &mask), h)
    };
    let (e0, h0) = error(&["render.hu_qin.recursion_depth=0"]);
    let (e_back, h_back) = error(&["render.hu_qin.recursion_depth=1"]);
    let (e_sphere, h_sphere) =
        error(&["render.hu_qin.recursion_depth=1", "render.hu_qin.recursive_exit=\"bounding_sphere\""]);
    let changed = |a: &[f32], b: &[f32]| -> Vec<bool> {
        a.chunks(4)
            .zip(b.chunks(4))
            .zip(&mask)
            .map(|((p, q), &m)| m && (0..3).any(|c| (p[c] - q[c]).abs() > 0.01))
            .collect()
    };
    let c_back = changed(&h0, &h_back);
    let c_exit = changed(&h_back, &h_sphere);
    let count = |m: &[bool]| m.iter().filter(|&&x| x).count();
    eprintln!(
        "glass cube B, A's {} pixels: RMSE depth 0 {e0:.5}, depth 1 back layer {e_back:.5}, bounding sphere {e_sphere:.5}; \
         {} pixels changed 0 -> 1 (RMSE there {:.4} -> {:.4}); {} differ between the exits (back {:.4}, sphere {:.4})",
        count(&mask),
        count(&c_back),
        masked_rmse(&h0, &reference, &c_back),
        masked_rmse(&h_back, &reference, &c_back),
        count(&c_exit),
        masked_rmse(&h_back, &reference, &c_exit),
        masked_rmse(&h_sphere, &reference, &c_exit),
    );
    // Asserted with margin: the recursion helps over the changed pixels (measured 14%; 5%
    // asserted) and over A with either exit (measured 0.6% and 1.7%).
    assert!(count(&c_back) >= 5, "the recursion changed only {} pixels", count(&c_back));
    let (r0, r1) = (masked_rmse(&h0, &reference, &c_back), masked_rmse(&h_back, &reference, &c_back));
    assert!(r1 < 0.95 * r0, "depth 1 should be closer where it changes A: {r0} -> {r1}");
    assert!(e_back < e0 && e_sphere < e0, "{e0} {e_back} {e_sphere}");
    let (e_nearest, _) = error(&NEAREST_AT_DEPTH_0);
    assert_nearest_no_worse_at_depth_0("glass cube", e_nearest, e0);
}

/// The nearest corrected surface (glsl/include/nearby.glsl) against Fig. 13's closest
/// rectangle at recursion depth 0, where B's TEX_k refracts the environment only: rays from A
/// towards B's lower part meet the floor's rectangle first (Fig. 13 shows the floor) and B's
/// surface first (the nearest lookup, taking B's environment-only texel: a white crescent on
/// A where the reference shows the floor through the glass). With the environment-only
/// dielectric ranked after the other rectangles the nearest lookup must be no worse than the
/// paper's over A, the bound being that comparison itself (docs/refraction.md: measured cube
/// 0.21364 against 0.24519, torus 0.19374 against 0.23299; 0.28241 and 0.25043 with B's texel
/// taken, which fails here).
const NEAREST_AT_DEPTH_0: [&str; 2] = ["render.hu_qin.recursion_depth=0", "render.hu_qin.nearby_lookup=nearest"];

/// See [`NEAREST_AT_DEPTH_0`]: `e_nearest` and `e_paper` are A's RMSE with each lookup at depth 0.
fn assert_nearest_no_worse_at_depth_0(what: &str, e_nearest: f64, e_paper: f64) {
    eprintln!("{what} B, A's RMSE at depth 0: paper {e_paper:.5}, nearest {e_nearest:.5}");
    assert!(
        e_nearest <= e_paper,
        "{what}: the nearest lookup is worse than the paper's over A: {e_nearest} > {e_paper}"
    );
}

/// §2.2.1 with §2.1's whole exit search in the impostor texture (render.hu_qin.recursive_exit
/// = "full": Fig. 7's dividing pixel, Fig. 5's front/back test, Fig. 9 on the front or back
/// faces) against §4's back-facing assumption and the bounding sphere, on a NON-CONVEX glass
/// OBJ_k: B replaced by a glass torus (major radius 0.5, tube 0.2) tilted 70 degrees about X
/// and 20 about Z towards ball A, so that A's rectangle view of it looks through the ring and
/// into the tube from the side, where refracted rays can leave through front-facing surfaces.
/// A's pixels against the reference (64 spp, no photons), lit by the environment only.
#[test]
fn exit_modes_of_a_glass_torus_behind_ball_a() {
    if !common::in_own_process() {
        return;
    }
    let torus = "name = \"torus_b\"\nmaterial = \"glass\"\nshape = \"torus\"\nmajor_radius = 0.5\n\
                 minor_radius = 0.2\nsegments = 64\n\
                 transform = { rotation = [70, 0, 20], translation = [0.5, -0.2, -1.2] }";
    let load = b_replaced("torus", torus, SIZE);
    let ctx = context(false);
    let s = load(&[]);
    let mask = ball_a_mask(&s);
    let mut r = Reference::new(&ctx, &s, &ReferenceSettings { spp: 64, photons: 0, ..Default::default() }).unwrap();
    r.run_all(|_, _| {}).unwrap();
    let reference = r.image();
    drop(r);
    let render = |extra: &[&str]| {
        let h = render_on(&ctx, &load(extra)).hdr;
        assert_finite(&format!("{extra:?}"), &h);
        h
    };
    let h0 = render(&["render.hu_qin.recursion_depth=0"]);
    let modes = ["full", "back_facing", "bounding_sphere"];
    let h: Vec<Vec<f32>> = modes
        .iter()
        .map(|m| render(&["render.hu_qin.recursion_depth=1", &format!("render.hu_qin.recursive_exit=\"{m}\"")]))
        .collect();
    let changed = |a: &[f32], b: &[f32]| -> Vec<bool> {
        a.chunks(4)
            .zip(b.chunks(4))
            .zip(&mask)
            .map(|((p, q), &m)| m && (0..3).any(|c| (p[c] - q[c]).abs() > 0.01))
            .collect()
    };
    let count = |m: &[bool]| m.iter().filter(|&&x| x).count();
    let e0 = masked_rmse(&h0, &reference, &mask);
    let e: Vec<f64> = h.iter().map(|x| masked_rmse(x, &reference, &mask)).collect();
    // Where full and back-facing differ: the front-facing exits the Fig. 5 test found.
    let c_fb = changed(&h[0], &h[1]);
    let c_fs = changed(&h[0], &h[2]);
    eprintln!(
        "glass torus B, A's {} pixels: RMSE depth 0 {e0:.5}; depth 1 full {:.5}, back_facing {:.5}, bounding_sphere \
         {:.5}; {} pixels differ full/back_facing (RMSE there full {:.4}, back_facing {:.4}); {} differ \
         full/bounding_sphere (full {:.4}, sphere {:.4})",
        count(&mask),
        e[0],
        e[1],
        e[2],
        count(&c_fb),
        masked_rmse(&h[0], &reference, &c_fb),
        masked_rmse(&h[1], &reference, &c_fb),
        count(&c_fs),
        masked_rmse(&h[0], &reference, &c_fs),
        masked_rmse(&h[2], &reference, &c_fs),
    );
    // Measured at 96^2 on lavapipe: depth 0 0.23299; depth 1 full 0.22232, back_facing 0.22232
    // (the Fig. 5 test finds no front-facing exit that changes one of A's pixels: 0 differ),
    // bounding_sphere 0.23237; the 20 pixels where full and sphere differ: 0.2634 against
    // 0.5489. Asserted with margin: the layer searches beat the sphere there by a third (measured
    // half), and depth 1 with them beats depth 0 over A (measured 4.6%; 2% asserted).
    assert!(count(&c_fs) >= 5, "the exits differ on only {} pixels", count(&c_fs));
    assert!(
        masked_rmse(&h[0], &reference, &c_fs) < 0.67 * masked_rmse(&h[2], &reference, &c_fs),
        "the front/back-layer exit should beat the bounding sphere on the torus"
    );
    assert!(e[0] < 0.98 * e0 && e[1] < 0.98 * e0, "depth 1 should lower A's error: {e0} -> {e:?}");
    // Full and back-facing agree to a few pixels (measured 0; the cone test below has some).
    assert!(count(&c_fb) <= 10, "full and back_facing differ on {} pixels", count(&c_fb));
    let e_nearest = masked_rmse(&render(&NEAREST_AT_DEPTH_0), &reference, &mask);
    assert_nearest_no_worse_at_depth_0("glass torus", e_nearest, e0);
}

/// A case where the full search's front-facing exits matter: B replaced by a sharp glass cone
/// (base radius 0.35, height 1, half-angle 19 degrees) whose apex points at ball A's centre, so
/// that in A's rectangle view it is seen apex-on: a ray refracted into its side (ior 1.5,
/// incidence 71 degrees, T1 32 degrees from the view direction, more than the half-angle)
/// leaves through the opposite side, which faces the view. There Fig. 5's test must pick the
/// front faces; the back-facing assumption (§4) reaches the back faces (the base) instead.
#[test]
fn front_facing_exits_of_a_glass_cone_behind_ball_a() {
    if !common::in_own_process() {
        return;
    }
    const CONE_SIZE: u32 = 128;
    // Lathe axis +Y turned onto (-0.36, -0.22, 0.9), the base centre -> A's centre direction.
    let cone = "name = \"cone_b\"\nmaterial = \"glass\"\nshape = \"lathe\"\n\
                profile = [[0, 0], [0.35, 0], [0, 1.0]]\nsegments = 64\n\
                transform = { rotation = [102.7, -21.6, 0], translation = [0.3, 0.2, -1.0] }";
    let load = b_replaced("cone", cone, CONE_SIZE);
    let ctx = context(false);
    let render = |m: &str| {
        let h = render_on(&ctx, &load(&[&format!("render.hu_qin.recursive_exit=\"{m}\"")])).hdr;
        assert_finite(m, &h);
        h
    };
    let (full, back) = (render("full"), render("back_facing"));
    let differ = full.chunks(4).zip(back.chunks(4)).filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 0.01)).count();
    eprintln!("glass cone B at {CONE_SIZE}^2: {differ} pixels differ between the full and the back-facing exit");
    // Measured 2 pixels (lavapipe; the cone's texture is seen through A in few pixels). With a
    // front-face layer that is empty or never chosen, the two are bit-identical (0).
    assert!(differ >= 1, "the full exit search never picked a front-facing exit");
}
