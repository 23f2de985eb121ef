//! `prism reference`, `prism compare` and `prism sweep` run and produce their files; the
//! baseline's error is clearly above the reference's own noise floor.
mod common;

use std::process::Command;

struct Dir(common::ScratchDir);
impl Dir {
    fn new(name: &str) -> Dir {
        Dir(common::ScratchDir::new(&format!("prism-measure-{name}")))
    }
    fn path(&self) -> &std::path::Path {
        self.0.path()
    }
    fn prism(&self, args: &[&str]) -> (bool, String, String) {
        let out = Command::new(env!("CARGO_BIN_EXE_prism"))
            .args(args)
            .current_dir(self.path())
            .env("PRISM_CACHE_DIR", self.path().join("cache"))
            .output()
            .unwrap();
        (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
    }
}
const SMALL: &[&str] = &["--width", "32", "--height", "32", "--spp", "2", "--photons", "2000"];

#[test]
fn reference_writes_exr_and_png() {
    if !common::in_own_process() {
        return;
    }
    let d = Dir::new("reference");
    let mut args = vec!["reference", "sphere_env", "-o", "ref.exr", "--png", "ref.png", "--validation"];
    args.extend_from_slice(SMALL);
    let (ok, _, err) = d.prism(&args);
    assert!(ok, "{err}");
    let exr = image::open(d.path().join("ref.exr")).unwrap().to_rgb32f();
    assert_eq!((exr.width(), exr.height()), (32, 32));
    // The corner sees the grid environment's sky, never black.
    assert!(exr.get_pixel(0, 0).0.iter().all(|&v| v > 0.1));
    assert!(d.path().join("ref.png").exists());
}

#[test]
fn compare_reports_errors_writes_a_heat_map_and_caches_the_reference() {
    if !common::in_own_process() {
        return;
    }
    let d = Dir::new("compare");
    let mut args = vec![
        "compare",
        "sphere_env",
        "--set",
        "render.refraction=single",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--json",
        "c.json",
        "--heatmap",
        "heat.png",
        "--validation",
        "--no-exact",
    ];
    args.extend_from_slice(SMALL);
    let (ok, out, err) = d.prism(&args);
    assert!(ok, "{err}");
    assert!(
        out.contains("RMSE")
            && out.contains("FLIP mean")
            && out.contains("HDR-FLIP mean")
            && out.contains("refraction_single"),
        "{out}"
    );
    assert!(!out.contains("from the cache"));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(d.path().join("c.json")).unwrap()).unwrap();
    for k in ["rmse", "psnr_db", "rel_mse", "flip_mean", "flip_p95", "hdr_flip_mean", "hdr_flip_p95"] {
        assert!(json["errors"][k].as_f64().is_some_and(|v| v.is_finite() && v >= 0.0), "{k}: {}", json["errors"]);
    }
    assert!(json["passes"].as_array().unwrap().iter().any(|p| p["name"] == "refraction_single"));
    // The errors over the object mask: the ball's pixels (about pi 11.4^2 = 408 of 1024 at 32^2).
    let mask_line = out.lines().find(|l| l.trim_start().starts_with("over the object mask (")).expect(&out);
    assert!(mask_line.contains("ball (dielectric)") && mask_line.contains("RMSE"), "{mask_line}");
    let mask_pixels = json["mask_pixels"].as_u64().unwrap();
    assert!(mask_pixels > 0 && mask_pixels < 32 * 32, "{mask_pixels}");
    assert!(json["mask_surfaces"][0].as_str().is_some_and(|s| s.starts_with("ball (dielectric)")), "{json}");
    for k in ["rmse", "psnr_db", "rel_mse", "flip_mean", "flip_p95", "hdr_flip_mean", "hdr_flip_p95"] {
        let v = &json["errors_mask"][k];
        assert!(v.as_f64().is_some_and(|v| v.is_finite() && v >= 0.0), "{k}: {}", json["errors_mask"]);
    }
    assert_eq!(image::open(d.path().join("heat.png")).unwrap().width(), 32);
    // Second run: the reference comes from the cache and the numbers are the same.
    let (ok, out2, _) = d.prism(&args);
    assert!(ok && out2.contains("from the cache"), "{out2}");
    let json2: serde_json::Value = serde_json::from_slice(&std::fs::read(d.path().join("c.json")).unwrap()).unwrap();
    assert_eq!(json["errors"]["rmse"], json2["errors"]["rmse"]);
    // A different ior is a different reference.
    // With the exact curve (raytrace at two depths), compare prints the equal-time verdicts.
    let mut args3: Vec<&str> = args.iter().copied().filter(|a| *a != "--no-exact").collect();
    args3.extend_from_slice(&["--set", "materials.glass.ior=1.33", "--exact-depths", "1,2", "--exact-frames", "1"]);
    let (ok, out3, err3) = d.prism(&args3);
    assert!(ok && !out3.contains("from the cache"), "{out3}{err3}");
    assert!(out3.contains("exact tracer: raytrace") && out3.contains("max_depth=2"), "{out3}");
    for metric in ["rmse", "flip_mean"] {
        let line =
            out3.lines().find(|l| l.starts_with(&format!("equal time, {metric}:"))).unwrap_or_else(|| panic!("{out3}"));
        assert!(
            ["dominated", "beats exact", "within noise", "faster than exact"].iter().any(|v| line.ends_with(v)),
            "{line}"
        );
    }
}

#[test]
fn sweep_writes_csv_and_plots() {
    if !common::in_own_process() {
        return;
    }
    let d = Dir::new("sweep");
    let mut args = vec![
        "sweep",
        "sphere_env",
        "--set",
        "render.refraction=single",
        "--param",
        "render.sphere_segments=16,64",
        "--param",
        "materials.glass.ior=1.3,1.5",
        "-o",
        "s",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--exact-depths",
        "1,2",
        "--exact-frames",
        "1",
    ];
    args.extend_from_slice(SMALL);
    let (ok, _, err) = d.prism(&args);
    assert!(ok, "{err}");
    let csv = std::fs::read_to_string(d.path().join("s.csv")).unwrap();
    let lines: Vec<_> = csv.lines().collect();
    // Four settings, then the exact curve's two points.
    assert_eq!(lines.len(), 1 + 4 + 2, "{csv}");
    assert!(
        lines[0].starts_with("n,kind,setting,render.sphere_segments,materials.glass.ior,")
            && lines[0].ends_with(
                "flip_mean,flip_p95,mask_pixels,mask_rmse,mask_psnr_db,mask_rel_mse,mask_flip_mean,mask_flip_p95,\
                 mask_surfaces,pareto,technique,flip_mean_low,exact_flip_mean,verdict,hdr_flip_mean,hdr_flip_p95,\
                 mask_hdr_flip_mean,mask_hdr_flip_p95"
            ),
        "{}",
        lines[0]
    );
    assert!(lines[0].contains(",frame_ms,per_change_ms,"), "{}", lines[0]);
    let column = lines[0].split(',').position(|c| c == "mask_pixels").unwrap();
    for l in &lines[1..5] {
        let pixels: u32 = l.split(',').nth(column).unwrap().parse().unwrap();
        assert!(pixels > 0 && pixels < 32 * 32, "{l}");
        assert!(l.contains("ball (dielectric)"), "{l}");
    }
    // The verdict is the column before the appended HDR-FLIP columns, which hold values in [0, 1].
    let verdicts = ["dominated", "beats exact", "within noise", "faster than exact"];
    for (i, l) in lines[1..5].iter().enumerate() {
        assert!(l.starts_with(&format!("{},technique,", i + 1)), "{l}");
        let tail: Vec<&str> = l.rsplitn(5, ',').collect();
        assert!(verdicts.iter().any(|v| tail[4].ends_with(&format!(",{v}"))), "{l}");
        for v in &tail[..4] {
            assert!(v.parse::<f64>().is_ok_and(|v| (0.0..=1.0).contains(&v)), "{l}");
        }
    }
    assert!(lines[1..5].iter().any(|l| l.contains(",true,")), "some setting is on the Pareto front");
    assert!(
        lines[5].starts_with(",exact,raytrace max_depth=1,") && lines[6].starts_with(",exact,raytrace max_depth=2,")
    );
    let svg = std::fs::read_to_string(d.path().join("s.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("Pareto front") && svg.contains("exact: raytrace"));
    assert_eq!(image::open(d.path().join("s.png")).unwrap().width(), 900);
    // Bad parameters fail before any work, leaving nothing behind.
    let (ok, _, err) = d.prism(&["sweep", "sphere_env", "--param", "render.sphere_segments", "-o", "bad"]);
    assert!(!ok && err.contains("KEY=V1,V2"), "{err}");
    let (ok, _, err) = d.prism(&["sweep", "sphere_env", "--param", "render.nonsense=1,2", "-o", "bad"]);
    assert!(!ok && err.contains("nonsense"), "{err}");
    assert!(!d.path().join("bad.csv").exists());
}

/// A sweep over caustic techniques is weighed against `raytrace` with its caustics
/// (src/app/equaltime.rs, `ExactSource::RaytracePhotons`): one exact point per photon
/// budget, named in the CSV, on the plot and in the printed verdicts, the largest budget
/// (4 photons a pixel a frame at most) the mean of 4 frames, and the error falls as the
/// budget grows.
#[test]
fn sweep_with_caustics_measures_raytrace_with_photons_whose_error_falls_with_the_budget() {
    if !common::in_own_process() {
        return;
    }
    let d = Dir::new("sweep-photons");
    let args = [
        "sweep",
        "caustic_sphere",
        "--width",
        "64",
        "--height",
        "64",
        "--spp",
        "64",
        "--photons",
        "4000000",
        "--param",
        "render.caustics=caustics_map,photon_buffer",
        "--frames",
        "1",
        "--warmup",
        "1",
        "--exact-photons",
        "1024,4096,16384,65536",
        "--exact-frames",
        "1",
        "-o",
        "s",
        "--validation",
    ];
    let (ok, out, err) = d.prism(&args);
    assert!(ok, "{err}");
    assert!(out.contains("exact tracer: raytrace with its caustics") && out.contains("65536 photons"), "{out}");
    let csv = std::fs::read_to_string(d.path().join("s.csv")).unwrap();
    let lines: Vec<_> = csv.lines().collect();
    assert_eq!(lines.len(), 1 + 2 + 4, "{csv}");
    let head: Vec<&str> = lines[0].split(',').collect();
    let column = |name: &str| head.iter().position(|c| *c == name).unwrap();
    let labels = ["1024 photons", "4096 photons", "16384 photons", "65536 photons (4 frames of 16384)"];
    let mut flip = Vec::new();
    for (l, label) in lines[3..].iter().zip(labels) {
        assert!(l.starts_with(&format!(",exact,raytrace_photons {label},")), "{l}");
        // No comma inside the labels: the columns are the header's.
        let cells: Vec<&str> = l.split(',').collect();
        for k in ["frame_ms", "rmse", "flip_mean", "hdr_flip_mean", "mask_rmse", "mask_flip_mean"] {
            let v: f64 = cells[column(k)].parse().unwrap_or(f64::NAN);
            assert!(v.is_finite() && v >= 0.0, "{k} = {v}: {l}");
        }
        flip.push(cells[column("flip_mean")].parse::<f64>().unwrap());
    }
    eprintln!("exact FLIP mean over the budgets: {flip:?}");
    // Each budget is 4 times the one before, so the caustic's photon noise halves (relative
    // noise 1/sqrt(photons in the disk)): no point may be worse than the one before it. Over
    // the 64-fold budget the noise falls 8-fold; the reference's own noise and the disk's
    // blur, which no budget lowers, hold the fall of the whole image's FLIP to 0.65 (measured
    // 0.0497, 0.0463, 0.0391, 0.0324; the photons and seeds are fixed, so the run repeats):
    // the last point must be below 0.8 of the first. With one budget for every point the
    // ratio is 1.
    for w in flip.windows(2) {
        assert!(w[1] <= w[0], "the error grows with the photon budget: {flip:?}");
    }
    assert!(flip[3] < 0.8 * flip[0], "the error does not fall with the photon budget: {flip:?}");
    for l in &lines[1..3] {
        let verdict = l.split(',').nth(column("verdict")).unwrap();
        assert!(["dominated", "beats exact", "within noise", "faster than exact"].contains(&verdict), "{l}");
    }
    let svg = std::fs::read_to_string(d.path().join("s.svg")).unwrap();
    assert!(svg.contains("exact: raytrace_photons, 1024 to 65536 photons"), "the plot names the curve");
}

/// "per change ms" (src/app/compare.rs, `PerChange`): the distance impostor's two maps do
/// work in the first frame and none after, so they are timed in frame 0 and are in no steady
/// frame; Wyman's d_N and the exact tracer's geometry are host costs of creation; the
/// single-interface baseline caches nothing and pays nothing per change. A pass that draws takes a positive time on any clock
/// with sub-millisecond resolution; the sum is checked to the last bits.
#[test]
fn per_change_cost_is_the_first_frames_cached_passes_and_the_setup() {
    if !common::in_own_process() {
        return;
    }
    let d = Dir::new("per-change");
    let run = |refraction: &str, json: &str| {
        let mut args = vec![
            "compare",
            "sphere_env",
            "--set",
            refraction,
            "--frames",
            "2",
            "--warmup",
            "1",
            "--json",
            json,
            "--heatmap",
            "heat.png",
            "--validation",
            "--no-exact",
        ];
        args.extend_from_slice(SMALL);
        let (ok, out, err) = d.prism(&args);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(d.path().join(json)).unwrap()).unwrap();
        (out, v)
    };
    let names = |v: &serde_json::Value| -> Vec<String> {
        v.as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_string()).collect()
    };
    let maps = ["refraction_impostor_map", "refraction_impostor_refractor_map"];

    let (out, json) = run("render.refraction=impostor", "impostor.json");
    let costs = json["per_change_costs"].as_array().unwrap();
    assert_eq!(names(&json["per_change_costs"]), maps, "{json}");
    for c in costs {
        assert!(c["ms"].as_f64().unwrap() > 0.0 && c["clock"] == "gpu", "{c}");
        assert_eq!(c["rerun_on"], "light or object change", "{c}");
    }
    let sum: f64 = costs.iter().map(|c| c["ms"].as_f64().unwrap()).sum();
    // serde_json parses without `float_roundtrip`: a value may come back one ulp off.
    let total = json["per_change_ms"].as_f64().unwrap();
    assert!((total - sum).abs() <= 1e-12 * sum, "{total} vs {sum}");
    // The steady frames hold the impostor's per-frame pass, and neither map.
    let steady = names(&json["passes"]);
    assert!(steady.iter().any(|p| p == "refraction_impostor"), "{steady:?}");
    assert!(maps.iter().all(|m| !steady.iter().any(|p| p == m)), "{steady:?}");
    let line = out.lines().find(|l| l.starts_with("per change ms ")).expect(&out);
    assert!(line.contains("refraction_impostor_map") && line.contains("light or object change"), "{line}");

    let (_, json) = run("render.refraction=wyman", "wyman.json");
    assert_eq!(names(&json["per_change_costs"]), ["wyman_d_n"], "{json}");
    let c = &json["per_change_costs"][0];
    assert!(c["ms"].as_f64().unwrap() > 0.0 && c["clock"] == "cpu" && c["rerun_on"] == "mesh change", "{c}");

    // The exact tracer's BVH and buffers, built on the host once per object change.
    let (_, json) = run("render.refraction=raytrace", "raytrace.json");
    assert_eq!(names(&json["per_change_costs"]), ["trace_geometry"], "{json}");
    let c = &json["per_change_costs"][0];
    assert!(c["ms"].as_f64().unwrap() > 0.0 && c["clock"] == "cpu" && c["rerun_on"] == "object change", "{c}");

    let (out, json) = run("render.refraction=single", "single.json");
    assert_eq!(json["per_change_ms"].as_f64(), Some(0.0), "{json}");
    assert!(json["per_change_costs"].as_array().unwrap().is_empty(), "{json}");
    assert!(out.contains("per change ms 0.000, paid once per light or object change: none"), "{out}");
}

/// The exact points are timed interleaved with the setting (src/app/equaltime.rs): on the
/// device's clock, an exact point's timed frames fall between the setting's first and last
/// timed frames, where timing them after the setting would put them all after its last.
/// With 1 + 8 frames for the setting and 1 + 2 per exact point, the exact points' timed frames
/// are in rounds 5 and 8 of 9 (src/app/bench_versus.rs, `Interleave`): round 5 is inside.
#[test]
fn exact_points_are_timed_between_the_settings_frames() {
    if !common::in_own_process() {
        return;
    }
    let d = Dir::new("interleave");
    let mut args = vec![
        "compare",
        "sphere_env",
        "--set",
        "render.refraction=single",
        "--frames",
        "8",
        "--warmup",
        "1",
        "--exact-depths",
        "1,2",
        "--exact-frames",
        "2",
        "--json",
        "c.json",
        "--heatmap",
        "heat.png",
        "--validation",
    ];
    args.extend_from_slice(SMALL);
    let (ok, _, err) = d.prism(&args);
    assert!(ok, "{err}");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(d.path().join("c.json")).unwrap()).unwrap();
    let starts = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array().unwrap_or_else(|| panic!("{json}")).iter().map(|t| t.as_f64().unwrap()).collect()
    };
    let setting = starts(&json["frame_starts_ms"]);
    assert_eq!(setting.len(), 8, "{json}");
    let (first, last) = (setting[0], setting[7]);
    let points = json["exact"]["points"].as_array().unwrap();
    assert_eq!(points.len(), 2, "{json}");
    for p in points {
        let s = starts(&p["frame_starts_ms"]);
        assert_eq!(s.len(), 2, "{p}");
        assert!(s.iter().any(|&t| first < t && t < last), "{s:?} not within the setting's frames {setting:?}");
    }
}

/// `prism report` on a one-entry spec: the summary table opens the report with the entry's
/// best technique, the exact tracer's FLIP at its time and a verdict; the section's table has
/// the equal-time columns and its plot the exact curve.
#[test]
fn report_on_a_tiny_spec_writes_the_summary_and_equal_time_columns() {
    if !common::in_own_process() {
        return;
    }
    let d = Dir::new("report");
    std::fs::write(
        d.path().join("spec.toml"),
        "set = [\"render.reflection=single\", \"render.caustics=none\"]\n\
         [[entry]]\nscene = \"sphere_env\"\ntitle = \"tiny\"\nparams = [\"render.refraction=single,hu_qin\"]\n",
    )
    .unwrap();
    std::fs::create_dir_all(d.path().join("docs")).unwrap();
    let mut args = vec![
        "report",
        "--spec",
        "spec.toml",
        "-o",
        "docs/ACCURACY.md",
        "--size",
        "32",
        "--frames",
        "1",
        "--warmup",
        "1",
        "--exact-depths",
        "1,2",
        "--exact-frames",
        "1",
    ];
    args.extend_from_slice(&SMALL[4..]);
    let (ok, _, err) = d.prism(&args);
    assert!(ok, "{err}");
    let md = std::fs::read_to_string(d.path().join("docs/ACCURACY.md")).unwrap();
    let summary = md.find("## Summary: the best approximation against exact ray tracing").expect(&md);
    assert!(summary < md.find("## sphere_env: tiny").unwrap(), "the summary comes first");
    let row = md.lines().find(|l| l.starts_with("| sphere_env | refraction | `")).expect(&md);
    assert!(
        ["dominated |", "beats exact |", "within noise |", "faster than exact |"].iter().any(|v| row.ends_with(v)),
        "{row}"
    );
    assert!(md.contains("| # | setting | frame ms |") && md.contains("exact FLIP at equal time | verdict |"), "{md}");
    // HDR-FLIP's columns after the verdict, and every row of the section's table as wide as its header.
    let head = md.lines().find(|l| l.starts_with("| # | setting | frame ms |")).expect(&md);
    assert!(head.ends_with("| verdict | HDR-FLIP mean | HDR-FLIP p95 | mask HDR-FLIP mean |"), "{head}");
    let cells = |l: &str| l.matches(" |").count();
    // The rows of the table under `head`: up to the first line that is not a row.
    let table = |head: &str| -> Vec<String> {
        md.lines().skip_while(|l| *l != head).skip(2).take_while(|l| l.starts_with("| ")).map(String::from).collect()
    };
    let rows = table(head);
    assert_eq!(rows.len(), 2, "{md}");
    assert!(rows.iter().all(|r| cells(r) == cells(head)), "{head}\n{rows:?}");
    // The ranking: the other setting against the best by FLIP mean, paired against the shared
    // reference (src/metrics/paired.rs), one row as wide as its header.
    assert!(md.contains("Ranking against the best by FLIP mean, #"), "{md}");
    let ranking = md.lines().find(|l| l.starts_with("| # | setting | FLIP mean − best |")).expect(&md);
    let ranked = table(ranking);
    assert_eq!(ranked.len(), 1, "{md}");
    assert!(cells(&ranked[0]) == cells(ranking), "{ranking}\n{ranked:?}");
    assert!(["by FLIP and RMSE |", "by FLIP |", "by RMSE |", "within noise |"].iter().any(|v| ranked[0].ends_with(v)));
    // The time columns and the caption that says what each includes.
    assert!(
        md.contains("| frame ms | per change ms |")
            && md.contains("*Per change ms* is paid once per light or object change"),
        "{md}"
    );
    assert!(md.contains("Exact tracer: raytrace"), "{md}");
    let svg = std::fs::read_dir(d.path().join("docs/accuracy"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "svg"))
        .unwrap();
    assert!(std::fs::read_to_string(svg).unwrap().contains("exact: raytrace"));
    // The image strips only with --images: a run's output, not the repository's.
    let pngs = std::fs::read_dir(d.path().join("docs/accuracy"))
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "png"));
    assert_eq!(pngs.count(), 0, "image strips written without --images");
    assert!(!md.contains("Left to right"), "{md}");
}

/// A sanity check of the measurement itself: the single-interface baseline's error
/// on sphere_env is far above the reference's own noise floor (two references with
/// different seeds).
#[test]
fn baseline_error_is_far_above_the_reference_noise_floor() {
    if !common::in_own_process() {
        return;
    }
    use prism::reference::{Reference, ReferenceSettings};
    let ctx = common::context(false);
    let s = common::scene("sphere_env", 32, &[]);
    // At 64 spp two references differ by about 0.03 RMSE (mostly the stochastic Fresnel
    // choice between reflected sky and refracted grid); the baseline is off by about 0.43.
    let reference = |seed| {
        let mut r =
            Reference::new(&ctx, &s, &ReferenceSettings { spp: 64, photons: 0, seed, ..Default::default() }).unwrap();
        r.run_all(|_, _| {}).unwrap();
        r.image()
    };
    let (a, b) = (reference(1), reference(2));
    let noise = prism::metrics::image::rmse_rgba(&a, &b);
    let baseline = common::render_on(&ctx, &s);
    let error = prism::metrics::image::rmse_rgba(&baseline.hdr, &a);
    assert!(error > 8.0 * noise.max(1e-6), "baseline RMSE {error} vs noise floor {noise}");
}

/// The object mask of sphere_env at 128^2 is the glass ball's projected disc, and the error
/// over it accounts for the whole image's error where the images differ only on the ball.
#[test]
fn object_mask_is_the_balls_projected_disc_and_holds_all_of_its_error() {
    if !common::in_own_process() {
        return;
    }
    use prism::metrics::image::ErrorMetrics;
    use prism::metrics::mask::ObjectMask;
    let size = 128u32;
    let s = common::scene("sphere_env", size, &[]);
    let mask = ObjectMask::of_scene(&s);
    // The ball (radius r = 1 at distance D = 4 on the optical axis) subtends the cone of
    // half-angle asin(r / D); its silhouette on the image plane is the circle of radius
    // tan(asin(r / D)) / tan(vfov / 2) half-heights, R = 45.40 px at 128^2.
    let (r, dist) = (1.0f64, s.camera.position.distance(s.camera.target) as f64);
    let tan_half = ((s.camera.vfov_deg as f64).to_radians() * 0.5).tan();
    let radius_px = (r / dist).asin().tan() / tan_half * size as f64 / 2.0;
    // Pixels whose centre lies in a disc of radius R: their unit squares cover the disc of
    // radius R - sqrt(2)/2 and lie inside the disc of radius R + sqrt(2)/2 (half a pixel's
    // diagonal), so pi (R -+ sqrt(2)/2)^2 bound the count: +-201 pixels about pi R^2 = 6476.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let (lo, hi) = (std::f64::consts::PI * (radius_px - h).powi(2), std::f64::consts::PI * (radius_px + h).powi(2));
    let n = mask.count();
    assert!(lo <= n as f64 && n as f64 <= hi, "mask {n} pixels, the disc allows {lo:.0}..{hi:.0}");
    assert_eq!(mask.surfaces, [format!("ball (dielectric): {n} px")]);
    // Pixel (i, j)'s centre is inside the disc when its angle to the axis is below asin(r / D);
    // shrunk by 0.01 px so that f32 rounding at the silhouette cannot put a pixel of the disc
    // outside the mask.
    let in_disc = |i: u32, j: u32| {
        let c = size as f64 / 2.0;
        let (x, y) = (i as f64 + 0.5 - c, j as f64 + 0.5 - c);
        (x * x + y * y).sqrt() < radius_px - 0.01
    };

    // Images that differ only on the ball: the reference everywhere, the single-interface
    // baseline's pixels inside the (closed-form) disc.
    let ctx = common::context(false);
    let reference = {
        use prism::reference::{Reference, ReferenceSettings};
        let settings = ReferenceSettings { spp: 2, photons: 0, ..Default::default() };
        let mut reference = Reference::new(&ctx, &s, &settings).unwrap();
        reference.run_all(|_, _| {}).unwrap();
        reference.image()
    };
    let baseline = common::render_on(&ctx, &s);
    let mut test = reference.clone();
    for (k, p) in test.chunks_exact_mut(4).enumerate() {
        let (i, j) = (k as u32 % size, k as u32 / size);
        if in_disc(i, j) {
            p.copy_from_slice(&baseline.hdr[4 * k..4 * k + 4]);
        }
    }
    let tonemap = |img: &[f32]| prism::app::output::tonemap_scene(img, &s.render);
    let (tl, rl) = (tonemap(&test), tonemap(&reference));
    let (all, over, _) = ErrorMetrics::between_with_mask(&test, &reference, &tl, &rl, size, size, Some(&mask.pixels));
    let over = over.expect("the mask holds pixels");
    // Every differing pixel is in the mask, so the sums of squared errors are equal:
    // RMSE_mask^2 N_mask = RMSE^2 N, up to f64 rounding of the division and square root.
    let (sum_all, sum_mask) = (all.rmse.powi(2) * (size * size) as f64, over.rmse.powi(2) * n as f64);
    assert!(sum_all > 0.0, "the baseline differs from the reference on the ball");
    assert!((sum_all - sum_mask).abs() <= 1e-12 * sum_all, "sum of squared errors: whole {sum_all}, mask {sum_mask}");
    let (rel_all, rel_mask) = (all.rel_mse * (size * size) as f64, over.rel_mse * n as f64);
    assert!((rel_all - rel_mask).abs() <= 1e-12 * rel_all, "relMSE sums: whole {rel_all}, mask {rel_mask}");
    // And so the mask's RMSE is the whole image's scaled by sqrt(N / N_mask) = 1.59.
    assert!(over.rmse > 1.5 * all.rmse, "mask RMSE {} vs whole {}", over.rmse, all.rmse);

    // With caustics, the diffuse receivers the caustics techniques light join the mask.
    let without = ObjectMask::of_scene(&common::scene("caustic_sphere", 64, &[]));
    let with = ObjectMask::of_scene(&common::scene("caustic_sphere", 64, &["render.caustics=caustics_map"]));
    assert_eq!(without.surfaces.len(), 1, "{:?}", without.surfaces);
    assert!(without.surfaces[0].starts_with("ball (dielectric)"), "{:?}", without.surfaces);
    assert!(with.surfaces.iter().any(|s| s.contains("(diffuse caustic receiver)")), "{:?}", with.surfaces);
    assert!(with.count() > without.count());
}
