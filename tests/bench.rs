//! `prism bench` prints per-pass timings, writes JSON with the run's metadata, and writes a
//! Chrome trace whose structure Perfetto accepts. Structure only: lavapipe timings are CPU
//! time and are never compared against magnitudes (../shared/DESIGN.md, rule 6).
mod common;

use std::process::Command;

#[test]
fn bench_writes_table_json_and_a_valid_chrome_trace() {
    let dir = std::env::temp_dir().join(format!("prism-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
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
    let _ = std::fs::remove_dir_all(&dir);
}
