//! The driver's loop limit, measured through the reference's probe kernel
//! (glsl/reference/probe.comp, mode 3: a loop of N iterations, then a loop of M).
//!
//! Mesa's llvmpipe (lavapipe) keeps one counter per shader invocation, set to
//! LP_MAX_TGSI_LOOP_ITERATIONS = 65535 (gallivm/lp_bld_limits.h) and decremented at the end
//! of every iteration of every loop (lp_exec_endloop in gallivm/lp_bld_ir_common.c); a loop
//! goes on only while some lane is active and the counter is still positive. The compiled
//! shader runs a vector of invocations in lockstep, so the counter is the vector's. Vulkan
//! allows no such limit: on other drivers both loops must run in full.
mod common;

use prism::reference::{Probe, Reference, ReferenceSettings};

const LP_MAX_TGSI_LOOP_ITERATIONS: u32 = 65_535;

/// (iterations of the first loop, of the second) for each (N, M) run in one dispatch, the
/// records' invocations side by side (in lockstep where the driver runs them so).
fn run(r: &mut Reference, records: &[(u32, u32)]) -> Vec<(u32, u32)> {
    let input: Vec<_> = records.iter().map(|&(n, m)| [[n as f32, m as f32, 0.0, 0.0], [0.0; 4], [0.0; 4]]).collect();
    r.probe(Probe::LoopLimit, &input).unwrap().iter().map(|o| (o[0][0] as u32, o[0][1] as u32)).collect()
}

/// What lavapipe's counter lets the two loops run, read from lp_exec_endloop: `budget`
/// decrements are left when the first loop starts; a loop of n takes n + 1 of them (the
/// last iteration is the one whose condition fails and breaks), and each iteration runs
/// its body before the counter is checked, so after the counter runs out a later loop still
/// runs its body once.
fn lavapipe_model(n: u32, m: u32, budget: u32) -> (u32, u32) {
    let first = n.min(budget);
    let left = budget - (n + 1).min(budget);
    let second = if left == 0 { m.min(1) } else { m.min(left) };
    (first, second)
}

#[test]
fn loop_limit_is_measured_and_matches_the_driver() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("caustic_sphere", 8, &[]);
    let mut r = Reference::new(&ctx, &s, &ReferenceSettings { spp: 1, photons: 0, ..Default::default() }).unwrap();
    let lavapipe = ctx.info.driver_name.to_lowercase().contains("llvmpipe");
    println!("driver: {} ({})", ctx.info.driver_name, ctx.info.driver_info);

    // A long loop alone tells how many decrements the kernel spends before mode 3's first
    // loop: probe.comp's other modes hold loops too.
    let (long, _) = run(&mut r, &[(200_000, 2)])[0];
    let spent = LP_MAX_TGSI_LOOP_ITERATIONS.saturating_sub(long);
    println!("a loop of 200000 ran {long} iterations: {spent} decrements spent before it");
    let budget = LP_MAX_TGSI_LOOP_ITERATIONS - spent;
    let cases = [
        (1000, 2),
        (budget - 4, 2),
        (budget - 3, 2),
        (budget - 2, 2),
        (65_534, 2),
        (70_000, 2),
        (200_000, 2),
        (40_000, 40_000),
        (0, 70_000),
    ];
    for (n, m) in cases {
        let got = run(&mut r, &[(n, m)])[0];
        println!("N = {n}, M = {m}: the loops ran {got:?}");
        if lavapipe {
            // spent: the other modes' loops, each one decrement (test: fewer than 64).
            assert!(spent < 64, "{spent} decrements before the probe's loop");
            assert_eq!(got, lavapipe_model(n, m, budget), "N = {n}, M = {m}");
        } else {
            assert_eq!(got, (n, m), "N = {n}, M = {m}: Vulkan runs every loop in full");
        }
    }

    // Invocations side by side: one long loop among 64 short ones.
    let records: Vec<_> = (0..64).map(|i| if i == 40 { (70_000, 2) } else { (0, 2) }).collect();
    let got = run(&mut r, &records);
    let cut: Vec<usize> = (0..64).filter(|&i| i != 40 && got[i].1 != 2).collect();
    println!("64 invocations, number 40 loops 70000 times: the second loop was cut in invocations {cut:?}");
    if lavapipe {
        // The long loop's own vector, and only it, lost its budget: an aligned block of
        // lanes around invocation 40 (8 with AVX2's 256-bit vectors).
        let width = cut.len() + 1;
        assert!(width.is_power_of_two() && width <= 16, "cut lanes {cut:?}");
        let start = 40 / width * width;
        assert_eq!(cut, (start..start + width).filter(|&i| i != 40).collect::<Vec<_>>());
        assert_eq!(got[40], lavapipe_model(70_000, 2, budget));
    } else {
        assert!(cut.is_empty() && got[40] == (70_000, 2), "{got:?}");
    }
}

/// A glass slab 0.1 thick in y (256 voxels: RK4 steps of 0.1/256/8 = 4.9e-5,
/// volume_uniforms in src/reference/mod.rs) and 4 long in z, seen end-on: the centre pixel's
/// path runs along its length, 4 / 4.9e-5 = 82 000 steps, each at least one loop iteration,
/// beyond lavapipe's 65 535 and within the step cap (200 000). The other rows miss the slab
/// (a pixel is 2 tan(20 deg) 4 / 3 = 0.97 tall at its near face) and the centre row's other
/// pixels leave it through its sides within 0.2 of their way (x = +-0.97 at the near face,
/// slope 0.24).
pub const SLAB: &str = r#"name = "loop_limit_slab"

[camera]
position = [0, 0, 6]
target = [0, 0, 0]
up = [0, 1, 0]
vfov_deg = 40
width = 3
height = 3

[environment]
type = "grid"

[volume]
name = "slab"
bounds = { min = [-1, -0.05, -2], max = [1, 0.05, 2] }
resolution = [8, 256, 8]

[[volume.region]]
name = "glass"
shape = "box"
center = [0, 0, 0]
size = [2, 0.1, 4]
n = 1.3
"#;

fn slab() -> prism::scene::Scene {
    prism::scene::load_str(SLAB, std::path::Path::new("loop_limit_slab.toml"), &[]).unwrap()
}

fn reference_stats(
    ctx: &std::sync::Arc<prism::gpu::GpuContext>,
    scene: &prism::scene::Scene,
    spp: u32,
    photons: u64,
) -> prism::reference::ReferenceStats {
    let mut r = Reference::new(ctx, scene, &ReferenceSettings { spp, photons, ..Default::default() }).unwrap();
    r.run_all(|_, _| {}).unwrap();
    let stats = r.stats();
    println!("{}: {stats:?}", scene.name);
    stats
}

#[test]
fn a_path_past_the_loop_limit_is_counted() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let lavapipe = ctx.info.driver_name.to_lowercase().contains("llvmpipe");
    let stats = reference_stats(&ctx, &slab(), 1, 0);
    if lavapipe {
        // The centre pixel (invocation 4) is cut, and the canary fires in every lane of its
        // vector: llvmpipe's vectors are at most 256 bits (LP_NATIVE_VECTOR_WIDTH), 8 lanes
        // of 32 bits, so that is invocations 0 to 7 at most (8 measured), never invocation 8.
        assert!((1..=8).contains(&stats.cut_camera), "{stats:?}");
    } else {
        assert_eq!(stats.cut(), 0, "{stats:?}");
    }
    // A path cut by the driver is not one that took `steps` steps.
    assert_eq!(stats.step_capped(), 0, "{stats:?}");
}

/// The photon kernel's canary: the slab lit end-on by a directional light along its length,
/// with a wall behind it to receive the light (photons are traced only where a diffuse
/// surface can receive them). A photon through the end face crosses the 4 m of glass in about
/// 82 000 RK4 steps, past lavapipe's budget of 65 535, like the centre pixel's camera path
/// above. 4096 photons, of which the end face (0.2 m^2 of the light's disk around the
/// volume's bounding sphere, radius about 2.2 m) takes about 1%: a few dozen cut photons,
/// each with the other lanes of its 8-lane vector.
#[test]
fn a_photon_past_the_loop_limit_is_counted() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let lavapipe = ctx.info.driver_name.to_lowercase().contains("llvmpipe");
    let text = format!(
        r#"{SLAB}
[[lights]]
type = "directional"
direction = [0, 0, -1]
irradiance = 1

[materials.wall]
type = "diffuse"
albedo = 0.5

[[objects]]
name = "wall"
material = "wall"
shape = "quad"
center = [0, 0, -3]
size = [6, 6]
normal = [0, 0, 1]
"#
    );
    let scene = prism::scene::load_str(&text, std::path::Path::new("loop_limit_slab_lit.toml"), &[]).unwrap();
    let stats = reference_stats(&ctx, &scene, 1, 4096);
    if lavapipe {
        assert!(stats.cut_photons > 0, "{stats:?}");
    } else {
        assert_eq!(stats.cut(), 0, "{stats:?}");
    }
    assert_eq!(stats.step_capped(), 0, "{stats:?}");
}

/// The shipped scenes' references are exact: no invocation is cut (camera, photon and gather
/// kernels all run) and no path reaches the step cap.
#[test]
fn default_scenes_report_no_cut() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    for (name, photons) in [("caustic_sphere", 1 << 14), ("eikonal_sphere", 1 << 12)] {
        let stats = reference_stats(&ctx, &common::shipped(name, 32, &[]), 2, photons);
        assert_eq!(stats, Default::default(), "{name}");
    }
}

/// A fresh directory for the CLI runs (DIR/work, the reference cache in DIR/cache), removed
/// at the end.
struct Dir(common::ScratchDir);
impl Dir {
    fn new(name: &str) -> Dir {
        let d = common::ScratchDir::new(&format!("prism-loop-limit-{name}"));
        std::fs::create_dir_all(d.path().join("work")).unwrap();
        Dir(d)
    }
    fn work(&self) -> std::path::PathBuf {
        self.0.path().join("work")
    }
    fn listing(&self) -> Vec<String> {
        let mut v: Vec<_> = std::fs::read_dir(self.work())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

/// Run prism in `dir` with its own reference cache; (exit code, stderr).
fn prism(dir: &Dir, args: &[&str]) -> (Option<i32>, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_prism"))
        .args(args)
        .current_dir(dir.work())
        .env("PRISM_CACHE_DIR", dir.0.path().join("cache"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "{stderr}");
    (out.status.code(), stderr)
}

#[test]
fn cli_warns_about_a_cut_reference_and_compare_refuses_it() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    if !ctx.info.driver_name.to_lowercase().contains("llvmpipe") {
        println!("{}: no loop limit to provoke", ctx.info.driver_name);
        return;
    }
    drop(ctx);
    let dir = Dir::new("cli");
    std::fs::write(dir.work().join("slab.toml"), SLAB).unwrap();
    let quick = ["--spp", "1", "--photons", "0"];

    // `reference` writes its image and warns: scene, count, cause, what to do.
    let (code, err) = prism(&dir, &[&["reference", "slab.toml", "-o", "ref.exr"][..], &quick].concat());
    assert_eq!(code, Some(0), "{err}");
    let warning = err.lines().find(|l| l.starts_with("warning: ")).unwrap_or_else(|| panic!("no warning:\n{err}"));
    for part in ["loop_limit_slab", "8 shader invocations", "loop budget", "65535", "volume.resolution", "--max-depth"]
    {
        assert!(warning.contains(part), "{part:?} missing from {warning}");
    }

    // `compare` refuses to rank against it: exit 1, no output, the flag named; also when
    // the reference comes from the cache the run above did not fill (compare's own).
    let compare = ["compare", "slab.toml", "--frames", "1", "--warmup", "0", "--no-exact", "--json", "c.json"];
    for attempt in ["rendered", "cached"] {
        let before = dir.listing();
        let (code, err) = prism(&dir, &[&compare[..], &quick].concat());
        assert_eq!(code, Some(1), "{attempt}: {err}");
        assert!(err.contains("error: the reference of scene loop_limit_slab is not exact"), "{attempt}: {err}");
        assert!(err.contains("--accept-cut-reference"), "{attempt}: {err}");
        assert_eq!(dir.listing(), before, "{attempt}: output left behind");
    }
    // With the flag it measures, warns, and the JSON carries the counts.
    let (code, err) = prism(&dir, &[&compare[..], &quick, &["--accept-cut-reference"]].concat());
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("warning: the reference of scene loop_limit_slab is not exact"), "{err}");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.work().join("c.json")).unwrap()).unwrap();
    assert_eq!(json["reference_stats"]["cut_camera"], 8, "{}", json["reference_stats"]);
}

#[test]
fn cli_is_silent_about_an_exact_reference() {
    if !common::in_own_process() {
        return;
    }
    let dir = Dir::new("exact");
    let (code, err) = prism(
        &dir,
        &[
            "reference",
            "caustic_sphere",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "2",
            "--photons",
            "16384",
            "-o",
            "r.exr",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("warning"), "{err}");
}

/// Paths that reach the volume's step cap are counted apart from cut ones. In
/// eikonal_dispersion_cube the middle glass (n 1.60 to 1.68) lies between the outer glass
/// (1.50 to 1.56) and the core (1.45 to 1.47): a light guide, in which a path beyond both
/// critical angles reflects totally at both of its faces until it has taken the cap's ten
/// diagonals of steps (17 741 of 1/8 voxel, fewer than lavapipe's 65 535, so no cut).
#[test]
fn a_path_trapped_in_a_light_guide_reaches_the_step_cap() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let stats = reference_stats(&ctx, &common::shipped("eikonal_dispersion_cube", 32, &[]), 2, 0);
    assert!(stats.step_cap_camera > 0, "{stats:?}");
    assert_eq!(stats.cut(), 0, "{stats:?}");
}
