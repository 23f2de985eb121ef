//! `prism bench` prints per-pass timings, writes JSON with the run's metadata, and writes a
//! Chrome trace whose structure Perfetto accepts. Structure only: lavapipe timings are CPU
//! time and are never compared against magnitudes (../shared/DESIGN.md, rule 6).
mod common;

use std::process::Command;

#[test]
fn bench_writes_table_json_and_a_valid_chrome_trace() {
    let scratch = common::ScratchDir::new("prism-bench");
    let dir = scratch.path();
    let (json, trace) = (dir.join("bench.json"), dir.join("trace.json"));
    let out = Command::new(env!("CARGO_BIN_EXE_prism"))
        .args(["bench", "sphere_nearby"])
        .args(common::baseline_args())
        .args(["--width", "48", "--height", "48", "--frames", "5", "--warmup", "2", "--validation"])
        .arg("--json")
        .arg(&json)
        .arg("--trace")
        .arg(&trace)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    let passes = ["shadow_map", "gbuffer", "deferred_shading", "refraction_single", "tonemap"];
    for p in passes.iter().chain(&["frame"]) {
        assert!(stdout.lines().any(|l| l.starts_with(p)), "table lacks {p}:\n{stdout}");
    }

    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(report["frames"], 5);
    assert_eq!(report["width"], 48);
    assert!(report["device"]["name"].as_str().is_some_and(|s| !s.is_empty()));
    assert!(report["device"]["driver_info"].is_string());
    assert!(report["git_revision"].is_string());
    let names: Vec<_> = report["passes"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, passes);
    for p in report["passes"].as_array().unwrap() {
        let (min, med, max) =
            (p["min_ms"].as_f64().unwrap(), p["median_ms"].as_f64().unwrap(), p["max_ms"].as_f64().unwrap());
        assert!(0.0 <= min && min <= med && med <= max, "{p}");
    }

    let trace: serde_json::Value = serde_json::from_slice(&std::fs::read(&trace).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().expect("traceEvents array");
    let complete: Vec<_> = events.iter().filter(|e| e["ph"] == "X").collect();
    let frames: Vec<_> = complete.iter().filter(|e| e["cat"] == "frame").collect();
    assert_eq!(frames.len(), 5);
    for f in &frames {
        let (fs, fd) = (f["ts"].as_f64().unwrap(), f["dur"].as_f64().unwrap());
        assert!(fd >= 0.0);
        let frame_no = f["name"].as_str().unwrap().trim_start_matches("frame ").parse::<u64>().unwrap();
        let inside: Vec<_> = complete.iter().filter(|e| e["cat"] == "pass" && e["args"]["frame"] == frame_no).collect();
        let mut seen: Vec<_> = inside.iter().map(|e| e["name"].as_str().unwrap()).collect();
        seen.dedup();
        assert_eq!(seen, passes, "every pass of frame {frame_no} is in the trace, in order");
        for e in inside {
            let (ts, dur) = (e["ts"].as_f64().unwrap(), e["dur"].as_f64().unwrap());
            assert!(dur >= 0.0, "{e}");
            // Microsecond values: allow rounding of 1 ns.
            assert!(ts >= fs - 1e-3 && ts + dur <= fs + fd + 1e-3, "pass {e} outside its frame {f}");
        }
    }
    for e in complete {
        assert!(e["pid"].is_number() && e["tid"].is_number() && e["name"].is_string());
    }
}

/// Runs `prism bench ARGS` and returns its stdout; fails the test with both streams on error.
fn bench(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_prism")).arg("bench").args(args).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    stdout
}

/// `--versus`: one renderer per setting, frames interleaved round by round, each setting's
/// own passes, and each per-frame ratio taken against the first setting's frame of the same
/// round.
#[test]
fn bench_versus_interleaves_settings_and_divides_frame_by_frame() {
    let scratch = common::ScratchDir::new("prism-bench-versus");
    let dir = scratch.path();
    let (json, trace) = (dir.join("versus.json"), dir.join("trace.json"));
    let frames = 4;
    let stdout = bench(&[
        "sphere_env",
        "--width",
        "48",
        "--height",
        "48",
        "--frames",
        "4",
        "--warmup",
        "1",
        "--validation",
        "--versus",
        "render.refraction=single",
        "--versus",
        "render.refraction=wyman",
        "--json",
        json.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
    ]);
    assert!(stdout.contains("#2 render.refraction=wyman"), "{stdout}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let versus = report["versus"].as_array().unwrap();
    assert_eq!(versus.len(), 2);
    let own = |i: usize| -> Vec<String> {
        versus[i]["technique_passes"].as_array().unwrap().iter().map(|p| p.as_str().unwrap().to_string()).collect()
    };
    // The passes both settings share are not the technique's, nor is the G-buffer, though it
    // carries Wyman's d_N in the second setting.
    assert_eq!(own(0), ["refraction_single"]);
    assert!(own(1).iter().any(|p| p == "refraction_wyman"), "{:?}", own(1));
    for shared in ["gbuffer", "deferred_shading", "tonemap"] {
        assert!(!own(1).iter().any(|p| p == shared), "{shared} is in {:?}", own(1));
    }
    assert!(versus[0].get("frame_ratio").is_none(), "the first setting is the one divided by");
    let samples = |i: usize, what: &str| -> Vec<f64> {
        versus[i][what]["samples_ms"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect()
    };
    for what in ["technique", "frame"] {
        let (a, b) = (samples(0, what), samples(1, what));
        assert_eq!((a.len(), b.len()), (frames, frames));
        let ratio = &versus[1][format!("{what}_ratio")];
        let per_frame: Vec<f64> = ratio["per_frame"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert_eq!(per_frame.len(), frames);
        for k in 0..frames {
            // Same round, divided: samples are in frame order in both settings.
            assert!((per_frame[k] - b[k] / a[k]).abs() <= 1e-9 * per_frame[k].abs(), "{what} frame {k}");
        }
        let (min, med, max) =
            (ratio["min"].as_f64().unwrap(), ratio["median"].as_f64().unwrap(), ratio["max"].as_f64().unwrap());
        assert!(min <= med && med <= max, "{ratio}");
    }
    // The technique's time is the sum of its passes'.
    for (i, setting) in versus.iter().enumerate() {
        let passes = setting["passes"].as_array().unwrap();
        let t = samples(i, "technique");
        for k in 0..frames {
            let sum: f64 = passes
                .iter()
                .filter(|p| own(i).contains(&p["name"].as_str().unwrap().to_string()))
                .map(|p| p["samples_ms"][k].as_f64().unwrap())
                .sum();
            assert!((sum - t[k]).abs() < 1e-9, "setting {i} frame {k}: {sum} vs {}", t[k]);
        }
    }

    // Interleaved: in GPU time order, every round of two frames holds one frame of each.
    let trace: serde_json::Value = serde_json::from_slice(&std::fs::read(&trace).unwrap()).unwrap();
    let mut frames_in_time: Vec<(f64, u64)> = trace["traceEvents"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["cat"] == "frame")
        .map(|e| (e["ts"].as_f64().unwrap(), e["pid"].as_u64().unwrap()))
        .collect();
    frames_in_time.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(frames_in_time.len(), 2 * frames);
    for round in frames_in_time.chunks(2) {
        assert_ne!(round[0].1, round[1].1, "a round ran one setting twice: {frames_in_time:?}");
    }
}

/// `--versus` also reports what each setting pays once per change (here the eikonal light
/// simulation, which the settings run with different integrators), with its work and its
/// ratio to the first setting's, beside the per-frame costs.
#[test]
fn bench_versus_reports_each_setting_s_cost_per_change() {
    let scratch = common::ScratchDir::new("prism-bench-versus-once");
    let dir = scratch.path();
    let json = dir.join("versus.json");
    let stdout = bench(&[
        "eikonal_sphere",
        "--width",
        "32",
        "--height",
        "32",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--set",
        "volume.resolution=[16,16,16]",
        "--versus",
        "render.eikonal.light_integrator=rk4",
        "--versus",
        "render.eikonal.light_integrator=midpoint",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(stdout.contains("Paid once per change"), "{stdout}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let versus = report["versus"].as_array().unwrap();
    for (i, v) in versus.iter().enumerate() {
        let costs = v["per_change_costs"].as_array().unwrap();
        let sim = costs.iter().find(|c| c["name"] == "eikonal_light_simulation").expect("the light simulation's cost");
        assert!(sim["ms"].as_f64().unwrap() > 0.0, "{sim}");
        let sum: f64 = costs.iter().map(|c| c["ms"].as_f64().unwrap()).sum();
        assert!((v["per_change_ms"].as_f64().unwrap() - sum).abs() < 1e-9, "setting {i}: the total is the costs' sum");
        assert!(v["light_simulation"]["patch_steps"].as_u64().unwrap() > 0, "setting {i}: {}", v["light_simulation"]);
    }
    assert!(versus[0].get("per_change_ratio").is_none(), "the first setting is the one divided by");
    let ratio = versus[1]["per_change_ratio"].as_f64().unwrap();
    let expected = versus[1]["per_change_ms"].as_f64().unwrap() / versus[0]["per_change_ms"].as_f64().unwrap();
    assert!((ratio - expected).abs() < 1e-9 * expected, "{ratio} vs {expected}");
}

/// `--diff` reads two bench JSON files and says which passes moved beyond the noise, from
/// the samples each file keeps.
#[test]
fn bench_diff_flags_only_differences_beyond_the_noise() {
    let scratch = common::ScratchDir::new("prism-bench-diff");
    let dir = scratch.path();
    // 20 samples alternating +-0.5 ms: stddev 0.51, standard error of the median 0.14 ms,
    // noise threshold 3 * sqrt(2) * 0.14 = 0.61 ms (src/app/bench_diff.rs).
    let series = |centre: f64| -> Vec<f64> { (0..20).map(|i| centre + if i % 2 == 0 { 0.5 } else { -0.5 }).collect() };
    let file = |name: &str, moved: f64, steady: f64| {
        let pass = |n: &str, c: f64| {
            let s = series(c);
            serde_json::json!({"name": n, "median_ms": c, "min_ms": c - 0.5, "max_ms": c + 0.5, "mean_ms": c,
                               "samples": 20, "samples_ms": s})
        };
        let v = serde_json::json!({
            "scene": "sphere_env", "width": 64, "height": 64, "frames": 20,
            "device": {"name": "test"}, "git_revision": "x",
            "passes": [pass("moved", moved), pass("steady", steady)],
            "frame": pass("frame", moved + steady),
        });
        let path = dir.join(name);
        std::fs::write(&path, serde_json::to_vec(&v).unwrap()).unwrap();
        path
    };
    let (a, b) = (file("a.json", 5.0, 3.0), file("b.json", 7.0, 3.2));
    let stdout = bench(&["--diff", a.to_str().unwrap(), b.to_str().unwrap()]);
    let line =
        |name: &str| stdout.lines().find(|l| l.starts_with(name)).unwrap_or_else(|| panic!("{stdout}")).to_string();
    assert!(line("moved").ends_with("B slower, beyond noise"), "{stdout}");
    assert!(line("steady").ends_with("within noise"), "{stdout}");
    assert!(line("frame").ends_with("B slower, beyond noise"), "{stdout}");
}

/// `--pipeline-stats`: every pass's counters and each technique's memory, in the table and
/// the JSON. On sphere_env the refraction shading pass shades the ball's pixels, not the
/// frame's.
#[test]
fn bench_pipeline_stats_count_each_pass_and_the_refraction_pass_shades_only_the_ball() {
    let scratch = common::ScratchDir::new("prism-bench-stats");
    let dir = scratch.path();
    let json = dir.join("stats.json");
    let size = 128u32;
    let s = size.to_string();
    let stdout = bench(&[
        "sphere_env",
        "--set",
        "render.refraction=single",
        "--width",
        &s,
        "--height",
        &s,
        "--frames",
        "2",
        "--warmup",
        "1",
        "--validation",
        "--pipeline-stats",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(stdout.contains("fs inv") && stdout.contains("images MiB"), "{stdout}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let pass = |name: &str| -> serde_json::Value {
        report["passes"].as_array().unwrap().iter().find(|p| p["name"] == name).unwrap()["pipeline_statistics"].clone()
    };
    let count = |name: &str, what: &str| pass(name)[what].as_u64().unwrap_or_else(|| panic!("{name}.{what}"));
    let pixels = u64::from(size * size);
    // The tone map is one triangle over every pixel: 3 vertices, 1 primitive, and a fragment
    // per pixel, give or take the counting granularity at the image's edges: one ring of
    // 4x4 blocks (lavapipe counts 16 fragments for every block a primitive touches).
    assert_eq!((count("tonemap", "input_vertices"), count("tonemap", "input_primitives")), (3, 1));
    let tonemap = count("tonemap", "fragment_invocations");
    assert!((pixels..=pixels + 16 * 4 * (u64::from(size) / 4 + 1)).contains(&tonemap), "{tonemap}");
    assert!(pass("tonemap")["compute_invocations"].as_u64().is_none_or(|n| n == 0));
    assert!(count("gbuffer", "input_primitives") > 100, "the ball is a tessellated sphere");

    // The ball: a unit sphere 4 away, seen with a 40-degree vertical field of view, projects
    // to a disc of radius tan(asin(1/4)) / tan(20 deg) * size / 2 pixels (it is centred on
    // the axis, so its silhouette is a circle).
    let r = (0.25f64.asin().tan() / 20f64.to_radians().tan()) * f64::from(size) / 2.0;
    let disc = std::f64::consts::PI * r * r;
    // The pass shades the inside of an octagon circumscribing that disc
    // (src/technique/baseline/fullscreen.rs, `Cover`): corners PROXY_SCALE * r away, area
    // 8 tan(pi / 8) r^2, drawn as 6 triangles fanned from one corner. Counting granularity:
    // a device may count the fragments of every 2x2 quad or (lavapipe) of every 4x4 block that
    // a triangle touches, so at most 16 more per block along each triangle's edges: the 8
    // sides (2 r tan(pi / 8) each) and the 5 inner diagonals (under 2 PROXY_SCALE r each),
    // where a segment of length L touches at most 2 (L / 4 + 1) blocks.
    let outer = r * f64::from(prism::technique::baseline::fullscreen::PROXY_SCALE);
    let octagon = 8.0 * (std::f64::consts::PI / 8.0).tan() * r * r;
    let blocks = |length: f64| 2.0 * (length / 4.0 + 1.0);
    let edges = 8.0 * blocks(2.0 * r * (std::f64::consts::PI / 8.0).tan()) + 5.0 * blocks(2.0 * outer);
    let fs = count("refraction_single", "fragment_invocations") as f64;
    assert!(
        fs >= disc * 0.99 && fs <= octagon + 16.0 * edges,
        "refraction_single shaded {fs} fragments; the ball covers {disc:.0} of {pixels} pixels"
    );

    // Memory: the shared resources and each technique, in bytes by kind.
    let memory = report["memory"].as_array().unwrap();
    assert_eq!(memory[0]["technique"], "frame");
    let frame_images = memory[0]["image_bytes"].as_u64().unwrap();
    // At least the HDR target alone (RGBA32F).
    assert!(frame_images >= 16 * pixels, "{}", memory[0]);
    for m in memory {
        for k in ["buffer_bytes", "image_bytes", "volume_bytes"] {
            assert!(m[k].is_u64(), "{m}");
        }
    }
    assert!(memory.iter().any(|m| m["technique"] == "tonemap"), "{memory:?}");
}
