//! The adaptive tone map (`render.tonemap = "adaptive"`, Ihrke et al. 2007 §5.3 after
//! Krawczyk et al. 2005; src/technique/baseline/tonemap.rs): the GPU reduction and operator against the
//! CPU version in src/app/output.rs, the extremes, and the temporal adaptation.
mod common;

use std::path::Path;

use prism::app::output;
use prism::renderer::Renderer;
use prism::scene::techniques::TonemapAdaptiveParams;
use prism::scene::{self, Scene};
use prism::technique::baseline::tonemap::AdaptiveStats;

/// Render one converged frame; return HDR, LDR and the GPU's tone-map state.
fn render(ctx: &std::sync::Arc<prism::gpu::GpuContext>, s: &Scene) -> (Vec<f32>, Vec<u8>, AdaptiveStats) {
    let mut r = Renderer::new(ctx, s).expect("renderer");
    r.render_frame().expect("frame");
    let hdr = r.read_hdr().unwrap();
    let ldr = r.read_ldr().unwrap();
    let stats = r.tonemap_stats().expect("the adaptive tone map reports its state");
    (hdr, ldr, stats)
}

fn rel(a: f32, b: f32) -> f32 {
    (a - b).abs() / b.abs().max(1e-30)
}

/// GPU and CPU agree: the state to float tolerance, every pixel to one 8-bit level.
fn assert_matches_cpu(name: &str, s: &Scene, hdr: &[f32], ldr: &[u8], gpu: AdaptiveStats) -> Vec<u8> {
    let p = TonemapAdaptiveParams::from_settings(&s.render).unwrap();
    let (cpu_ldr, cpu) = output::tonemap_adaptive(hdr, &p, s.render.exposure);
    for v in [gpu.l_avg, gpu.l_adapted, gpu.key, gpu.white] {
        assert!(v.is_finite() && v > 0.0, "{name}: {gpu:?}");
    }
    // The GPU sums log(delta + L_w) in f32 (a tree of 256 per tile, then over the tiles), the
    // CPU in f64: over 64^2 pixels the f32 sum's relative error is ~1e-6, so L_avg =
    // exp(mean) differs by ~1e-6 * |mean log|; 1e-4 leaves a wide margin yet catches a
    // missed tile (1/16 of the image) or a wrong mean by orders of magnitude.
    assert!(rel(gpu.l_avg, cpu.l_avg) < 1e-4, "{name}: L_avg GPU {} CPU {}", gpu.l_avg, cpu.l_avg);
    assert_eq!(gpu.l_adapted, gpu.l_avg, "{name}: headless renders are converged");
    assert!(rel(gpu.key, cpu.key) < 1e-4, "{name}: key GPU {} CPU {}", gpu.key, cpu.key);
    assert!(rel(gpu.white, cpu.white) < 1e-4, "{name}: L_white GPU {} CPU {}", gpu.white, cpu.white);
    // Per pixel within 1/255: the operator is the same float arithmetic on both sides; only
    // L_avg's last bits and pow/log rounding differ, which moves a code by at most one.
    let worst = ldr.iter().zip(&cpu_ldr).map(|(&a, &b)| (a as i32 - b as i32).abs()).max().unwrap();
    assert!(worst <= 1, "{name}: GPU and CPU tone maps differ by {worst}/255");
    cpu_ldr
}

fn luminances(hdr: &[f32]) -> Vec<f32> {
    hdr.chunks_exact(4).map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]).collect()
}

#[test]
fn gpu_reduction_and_operator_match_the_cpu_on_wide_dynamic_range() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    // caustic_sphere with its caustic (the ball lens's focus on the floor), and the volume
    // scene eikonal_sphere with its light simulation (coarsened to 32^3, 64^2 patches: 10 s
    // on lavapipe instead of minutes).
    let cases: [(&str, &[&str]); 2] = [
        ("caustic_sphere", &["render.caustics=caustics_map"]),
        ("eikonal_sphere", &["volume.resolution=[32,32,32]", "render.eikonal.light_patches=64"]),
    ];
    for (name, extra) in cases {
        let mut o = vec!["render.tonemap=adaptive"];
        o.extend(extra);
        let s = common::scene(name, 64, &o);
        let (hdr, ldr, stats) = render(&ctx, &s);
        // The scene must exercise a wide range, else the test would prove little.
        let y = luminances(&hdr);
        let lit: Vec<f32> = y.iter().copied().filter(|&v| v > 0.0).collect();
        let range = lit.iter().copied().fold(0f32, f32::max) / lit.iter().copied().fold(f32::INFINITY, f32::min);
        eprintln!("{name}: dynamic range {range}, {stats:?}");
        assert!(range > 100.0, "{name}: dynamic range only {range}");
        assert_matches_cpu(name, &s, &hdr, &ldr, stats);
        // And the adaptive map is not the clamp rule in disguise.
        let clamp = output::tonemap(&hdr, s.render.exposure);
        let differing = ldr.iter().zip(&clamp).filter(|(a, b)| (**a as i32 - **b as i32).abs() > 2).count();
        assert!(differing > ldr.len() / 10, "{name}: only {differing} codes differ from the clamp rule");
    }
    // 257 x 225 pixels (fewer than 256^2): 9 x 8 = 72 tiles of 32^2, more than adapt.comp's
    // 64 invocations, so its strided loop over the tiles and the partial tiles at the right
    // and bottom edges are both exercised.
    let s = common::scene("sphere_env", 64, &["render.tonemap=adaptive", "camera.width=257", "camera.height=225"]);
    let (hdr, ldr, stats) = render(&ctx, &s);
    assert_matches_cpu("sphere_env 257x225", &s, &hdr, &ldr, stats);
    // A fixed key and L_white go through the same path.
    let fixed = ["render.tonemap_adaptive.key=0.18", "render.tonemap_adaptive.white=2.5"];
    let s = common::scene("caustic_sphere", 64, &["render.tonemap=adaptive", fixed[0], fixed[1]]);
    let (hdr, ldr, stats) = render(&ctx, &s);
    assert_eq!((stats.key, stats.white), (0.18, 2.5));
    assert_matches_cpu("caustic_sphere, fixed key", &s, &hdr, &ldr, stats);
    common::assert_no_validation_errors(&ctx);
}

#[test]
fn the_clamp_tone_map_stays_scenes_md_rule_bit_for_bit() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    for exposure in ["1", "2.5"] {
        let s = common::scene("caustic_sphere", 64, &[&format!("render.exposure={exposure}")]);
        let mut r = Renderer::new(&ctx, &s).unwrap();
        r.render_frame().unwrap();
        let (hdr, ldr) = (r.read_hdr().unwrap(), r.read_ldr().unwrap());
        assert!(r.tonemap_stats().is_none());
        assert_eq!(ldr, output::tonemap(&hdr, s.render.exposure));
        assert_eq!(output::tonemap_scene(&hdr, &s.render), ldr);
    }
    common::assert_no_validation_errors(&ctx);
}

const CAMERA: &str = r#"
[camera]
position = [0, 3, 5]
target = [0, 0, 0]
vfov_deg = 40
width = 48
height = 40
"#;

fn inline(body: &str) -> Scene {
    let text = format!("{CAMERA}\n{body}\n[render]\ntonemap = \"adaptive\"\n");
    scene::load_str(&text, Path::new("tonemap_extreme.toml"), &[]).unwrap()
}

#[test]
fn extremes_give_finite_sensible_output() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let floor = r#"
[materials.white]
type = "diffuse"
albedo = 0.8
[[objects]]
material = "white"
shape = "quad"
center = [0, 0, 0]
size = [8, 8]
normal = [0, 1, 0]
"#;
    // All black: L_avg is delta exactly (log(delta + 0) averaged), and black stays black.
    let s = inline("[environment]\ntype = \"constant\"\nradiance = 0\n");
    let (hdr, ldr, st) = render(&ctx, &s);
    assert!(rel(st.l_avg, 1e-4) < 1e-5, "{st:?}");
    assert_eq!(st.white, 1.0, "auto L_white is at least 1");
    assert!(ldr.chunks_exact(4).all(|p| p[..3] == [0, 0, 0]));
    assert_matches_cpu("black", &s, &hdr, &ldr, st);

    // A huge light (1e30 W/sr): radiance ~1e29 on the floor, 0 in the sky. The lit floor is
    // white, the sky black, nothing NaN (L^2 / L_white^2 would overflow without the cap).
    let s = inline(&format!(
        "{floor}\n[environment]\ntype = \"constant\"\nradiance = 0\n[[lights]]\ntype = \"point\"\nposition = [0, 5, 0]\nintensity = 1e30\n"
    ));
    let (hdr, ldr, st) = render(&ctx, &s);
    let y = luminances(&hdr);
    assert!(y.iter().copied().fold(0f32, f32::max) > 1e27, "the floor should be lit by ~1e29");
    assert_matches_cpu("huge", &s, &hdr, &ldr, st);
    let (w, h) = (s.camera.width as usize, s.camera.height as usize);
    let centre = 4 * ((h * 3 / 4) * w + w / 2);
    assert!(ldr[centre..centre + 3].iter().all(|&c| c >= 250), "lit floor {:?}", &ldr[centre..centre + 3]);
    assert_eq!(&ldr[0..3], &[0, 0, 0], "the sky");
    // The same with a small fixed L_white: the capped L_d keeps the colour ratio finite.
    let mut s2 = s.clone();
    s2.render.params.insert("tonemap_adaptive".into(), "white = 0.001".parse().unwrap());
    let (hdr, ldr, st) = render(&ctx, &s2);
    assert_matches_cpu("huge, small white", &s2, &hdr, &ldr, st);

    // Tiny radiance (1e-30 everywhere): below delta, so the eye adapted to delta sees black;
    // the state stays finite.
    let s = inline("[environment]\ntype = \"constant\"\nradiance = 1e-30\n");
    let (hdr, ldr, st) = render(&ctx, &s);
    assert!(rel(st.l_avg, 1e-4) < 1e-5, "{st:?}");
    assert!(ldr.chunks_exact(4).all(|p| p[..3] == [0, 0, 0]));
    assert_matches_cpu("tiny", &s, &hdr, &ldr, st);
    // The smallest delta and a large luminance scale: still finite, still the CPU's answer.
    let mut s2 = s.clone();
    s2.render.params.insert("tonemap_adaptive".into(), "delta = 1e-12\nluminance_scale = 1e6".parse().unwrap());
    let (hdr, ldr, st) = render(&ctx, &s2);
    assert_matches_cpu("tiny, small delta", &s2, &hdr, &ldr, st);
    common::assert_no_validation_errors(&ctx);
}

#[test]
fn adapted_luminance_follows_the_log_average_with_the_rod_cone_time_constant() {
    if !common::in_own_process() {
        return;
    }
    // Synchronization validation on: the state image carries L_a from frame to frame (two
    // frames in flight) and the host reads each slot's statistics after its fence.
    let ctx = common::context(true);
    let s = common::scene("caustic_sphere", 48, &["render.tonemap=adaptive"]);
    let p = TonemapAdaptiveParams::from_settings(&s.render).unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    // Frame 0 is converged whatever the time step.
    r.set_tonemap_time_step(Some(0.05));
    r.render_frame().unwrap();
    r.finish().unwrap();
    let bright = r.tonemap_stats().unwrap();
    assert_eq!(bright.l_adapted, bright.l_avg);
    // Turn away from the lit floor (environment 0): L_avg drops to delta, and L_a follows
    // it frame by frame: L_a += (L_avg - L_a)(1 - exp(-T / tau)), tau = sigma tau_rod +
    // (1 - sigma) tau_cone, sigma = 0.04 / (0.04 + L_a) (Krawczyk et al. 2005).
    let mut cam = s.camera;
    cam.target = cam.position + glam::Vec3::new(0.0, 0.0, 10.0);
    r.set_camera(&cam);
    let dt = 0.05f64;
    let mut expected = bright.l_adapted as f64;
    let mut last = bright.l_adapted;
    for frame in 1..=6 {
        r.render_frame().unwrap();
        r.finish().unwrap();
        let st = r.tonemap_stats().unwrap();
        assert!(rel(st.l_avg, p.delta) < 1e-5, "frame {frame}: {st:?}");
        let sigma = 0.04 / (0.04 + expected);
        let tau = sigma * p.tau_rod as f64 + (1.0 - sigma) * p.tau_cone as f64;
        expected += (st.l_avg as f64 - expected) * (1.0 - (-dt / tau).exp());
        assert!(rel(st.l_adapted, expected as f32) < 1e-4, "frame {frame}: L_a {} expected {expected}", st.l_adapted);
        assert!(st.l_adapted < last && st.l_adapted > st.l_avg, "frame {frame}: {st:?}");
        // The key follows the adapted luminance, not the frame's average.
        let key = 1.03 - 2.0 / (2.0 + (st.l_adapted + 1.0).log10());
        assert!(rel(st.key, key) < 1e-4, "frame {frame}: key {} expected {key}", st.key);
        last = st.l_adapted;
    }
    // Without a time step (headless) the state is converged again at once.
    r.set_tonemap_time_step(None);
    r.render_frame().unwrap();
    r.finish().unwrap();
    let st = r.tonemap_stats().unwrap();
    assert_eq!(st.l_adapted, st.l_avg);
    common::assert_no_validation_errors(&ctx);
}
