//! `prism bench SCENE --versus KEY=VALUE --versus KEY=VALUE ...`: the cost of settings
//! against each other, measured in one process with the frames interleaved, so that the
//! load of a shared machine (and, on lavapipe, the CPU it runs on) weighs on every setting
//! alike. The papers' metric is a ratio of frame times (Wyman 2005, Table 1; Hu & Qin 2007,
//! §5), so each setting's technique passes and whole frame are divided by the first
//! setting's in the same round, frame by frame, and the spread of those ratios is reported.
use std::collections::BTreeMap;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::gpu::DeviceInfo;
use crate::metrics::timing::Stats;
use crate::renderer::{technique_passes, FrameTiming, Renderer, TechniqueMemory};
use crate::scene::Scene;

use super::bench::{
    git_revision, print_counts_table, print_memory_table, print_pass_table, summarize_detailed, BenchArgs, HostState,
    PassStats,
};
use super::check_validation;
use super::compare::PerChange;
use super::output::{self, Outputs};
use crate::technique::eikonal::eikonal_light::LightStats;

/// The order in which frames of several participants (renderers, or the reference's
/// iterations) are rendered when they are timed against each other in one process: in
/// rounds, each round one frame of every participant due in it, the first of them rotating
/// so that none always follows the same one (caches, the clock ramping after a pause). A
/// participant with fewer frames than the longest is spread evenly over the rounds, its last
/// frame in the last round: participant i with n_i frames in R rounds has rendered
/// floor((r + 1) n_i / R) by the end of round r. The rotation counts the rounds with as many
/// participants due (not all rounds: a participant due every sixth of three-participant rounds
/// would otherwise always take the same place). With equal counts every participant renders
/// every round, round r starting with participant r mod n.
#[derive(Clone, Debug)]
pub struct Interleave {
    frames: Vec<u64>,
    rounds: u64,
}

impl Interleave {
    /// Participant i renders `frames[i]` frames.
    pub fn new(frames: Vec<u64>) -> Interleave {
        let rounds = frames.iter().copied().max().unwrap_or(0);
        Interleave { frames, rounds }
    }

    /// Frames participant `i` has rendered by the end of round `r` (`r` = -1: none).
    fn done(&self, i: usize, r: i64) -> u64 {
        if r < 0 {
            return 0;
        }
        // u128: frames and rounds are each at most u64.
        ((r as u128 + 1) * self.frames[i] as u128 / self.rounds.max(1) as u128) as u64
    }

    /// Every round's participants, in the order they render their frames.
    pub fn order(&self) -> impl Iterator<Item = Vec<usize>> + '_ {
        // Rounds seen so far with k participants due, for k = 0..=n.
        let mut seen = vec![0u64; self.frames.len() + 1];
        (0..self.rounds).map(move |r| {
            let mut due: Vec<usize> =
                (0..self.frames.len()).filter(|&i| self.done(i, r as i64) > self.done(i, r as i64 - 1)).collect();
            let k = due.len();
            if k > 0 {
                due.rotate_left((seen[k] % k as u64) as usize);
            }
            seen[k] += 1;
            due
        })
    }
}

/// Min, median and max of one setting's per-frame ratios to the first setting.
#[derive(Serialize, Debug, Clone)]
pub struct RatioStats {
    pub min: f64,
    pub median: f64,
    pub max: f64,
    /// Every round's ratio, in frame order.
    pub per_frame: Vec<f64>,
}

impl RatioStats {
    fn of(per_frame: Vec<f64>) -> Option<RatioStats> {
        if per_frame.is_empty() {
            return None;
        }
        let s = Stats::of(&per_frame);
        Some(RatioStats { min: s.min_ms, median: s.median_ms, max: s.max_ms, per_frame })
    }
}

#[derive(Serialize, Debug)]
pub struct VersusSetting {
    /// The KEY=VALUE of this setting's `--versus`.
    pub setting: String,
    /// The effective scene (after --set and this setting), as TOML.
    pub scene_toml: String,
    /// The passes of the techniques that differ between the settings
    /// ([`crate::renderer::technique_passes`]), in the order they run.
    pub technique_passes: Vec<String>,
    /// Their summed time per frame.
    pub technique: PassStats,
    pub frame: PassStats,
    /// Per-frame ratios to the first setting's technique passes and frame (absent for the
    /// first setting, and for the technique where the first setting has no technique pass).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub technique_ratio: Option<RatioStats>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_ratio: Option<RatioStats>,
    pub passes: Vec<PassStats>,
    /// Device memory each technique created, and the shared resources' ("frame").
    pub memory: Vec<TechniqueMemory>,
    /// What the setting pays once per change instead of every frame (an eikonal light
    /// simulation, static impostor textures and caustic maps): measured while its renderer
    /// was set up and in its first frame, the settings one after another, not interleaved.
    #[serde(flatten)]
    pub per_change: PerChange,
    /// `per_change_ms` over the first setting's (absent for the first, or where it paid nothing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_change_ratio: Option<f64>,
    /// The eikonal light simulation's work (patch-steps, kernels), where the setting runs one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_simulation: Option<LightStats>,
}

#[derive(Serialize, Debug)]
pub struct VersusReport {
    pub scene: String,
    pub scene_file: String,
    pub device: DeviceInfo,
    pub width: u32,
    pub height: u32,
    /// Measured frames per setting, and warm-up frames per setting before them.
    pub frames: u32,
    pub warmup: u32,
    pub git_revision: String,
    /// The --set overrides every setting shares.
    pub settings: Vec<String>,
    /// How the frames were ordered: each round renders one frame of every setting, starting
    /// one setting later than the previous round, and waits for each frame before the next.
    pub interleaving: &'static str,
    pub versus: Vec<VersusSetting>,
    pub host: HostState,
    pub note: &'static str,
}

pub fn run(args: BenchArgs) -> Result<()> {
    if args.versus.len() < 2 {
        anyhow::bail!("--versus needs two or more settings to compare (one --versus KEY=VALUE each)");
    }
    let scenes: Vec<Scene> = args
        .versus
        .iter()
        .map(|v| {
            let mut a = args.scene.clone();
            a.set.push(v.clone());
            a.load().with_context(|| format!("--versus {v}"))
        })
        .collect::<Result<_>>()?;
    let mut outputs = Outputs::default();
    let json_out = outputs.prepare_opt(args.json.as_deref())?;
    let trace_out = outputs.prepare_opt(args.trace.as_deref())?;
    let host = HostState::before();
    let ctx = args.gpu.context()?;
    // Every renderer exists before the first frame, so that creating one (pipeline
    // compilation, the eikonal light simulation) never overlaps another's measured frames.
    let mut renderers: Vec<Renderer> = scenes
        .iter()
        .zip(&args.versus)
        .map(|(s, v)| Renderer::new(&ctx, s).with_context(|| format!("cannot set up the renderer for --versus {v}")))
        .collect::<Result<_>>()?;
    if args.pipeline_stats {
        for r in &mut renderers {
            super::bench::enable_pipeline_stats(r)?;
        }
    }
    let own = technique_passes(&scenes.iter().collect::<Vec<_>>());

    let n = renderers.len();
    let total = u64::from(args.warmup) + u64::from(args.frames);
    let bar = ProgressBar::new(total * n as u64).with_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(format!("bench {} versus", scenes[0].name));
    let schedule = Interleave::new(vec![total; n]);
    for (round, order) in (0..).zip(schedule.order()) {
        for k in order {
            let r = &mut renderers[k];
            r.render_frame()?;
            // One frame at a time: recording the next setting's frame must not compete with
            // this one's execution for the CPU (lavapipe runs on it).
            r.finish()?;
            bar.inc(1);
        }
        if args.stats.is_some_and(|s| (round + 1) % s == 0) {
            bar.suspend(|| super::print_stats(round + 1, &ctx));
        }
    }
    bar.finish_and_clear();
    check_validation(&ctx)?;
    let host = host.after();
    let mut per_change = Vec::new();
    let mut timings: Vec<Vec<FrameTiming>> = Vec::new();
    for r in renderers.iter_mut() {
        let all = r.take_timings();
        per_change.push(PerChange::of(&all, r.once_costs()));
        timings.push(all.into_iter().filter(|f| f.frame >= u64::from(args.warmup)).collect());
    }
    let first_change_ms = per_change[0].ms;

    // Technique and frame time per frame number, per setting.
    let per_frame = |i: usize| -> (BTreeMap<u64, f64>, BTreeMap<u64, f64>) {
        let names: Vec<&str> = own[i].to_vec();
        let t = timings[i].iter().map(|f| (f.frame, pass_sum(f, &names))).collect();
        let w = timings[i].iter().map(|f| (f.frame, f.total_ms())).collect();
        (t, w)
    };
    let series: Vec<_> = (0..n).map(per_frame).collect();
    let ratios = |a: &BTreeMap<u64, f64>, b: &BTreeMap<u64, f64>| -> Vec<f64> {
        a.iter().filter_map(|(k, x)| b.get(k).filter(|y| **y > 0.0).map(|y| x / y)).collect()
    };
    let results: Vec<VersusSetting> = (0..n)
        .map(|i| {
            let (passes, frame) = summarize_detailed(&timings[i]);
            let (t, w) = &series[i];
            let (t0, w0) = &series[0];
            VersusSetting {
                setting: args.versus[i].clone(),
                scene_toml: scenes[i].canonical.clone(),
                technique_passes: own[i].iter().map(|s| s.to_string()).collect(),
                technique: PassStats::detailed("technique", t.values().copied().collect()),
                frame,
                technique_ratio: if i == 0 { None } else { RatioStats::of(ratios(t, t0)) },
                frame_ratio: if i == 0 { None } else { RatioStats::of(ratios(w, w0)) },
                passes,
                memory: renderers[i].technique_memory().to_vec(),
                per_change_ratio: (i > 0 && first_change_ms > 0.0).then(|| per_change[i].ms / first_change_ms),
                per_change: per_change[i].clone(),
                light_simulation: renderers[i].light_stats().cloned(),
            }
        })
        .collect();

    println!(
        "prism bench --versus: {} at {}x{}, {} settings interleaved frame by frame, {} frames each after {} warm-up, on {} ({} {})",
        scenes[0].name,
        renderers[0].width(),
        renderers[0].height(),
        n,
        args.frames,
        args.warmup,
        ctx.info.name,
        ctx.info.driver_name,
        ctx.info.driver_info
    );
    print_summary(&results);
    if results.iter().any(|r| !r.per_change.costs.is_empty()) {
        println!("\nPaid once per change (at setup and in the first frame, the settings one after another):");
        for (i, r) in results.iter().enumerate() {
            let ratio = r.per_change_ratio.map_or_else(String::new, |x| format!(", {x:.3}x the first setting's"));
            println!("#{} {}: {:.3} ms{ratio}: {}", i + 1, r.setting, r.per_change.ms, r.per_change.describe());
            if let Some(l) = &r.light_simulation {
                println!(
                    "   light simulation: {} patch-steps, {} step dispatches, {} dropped",
                    l.patch_steps, l.steps, l.dropped_patches
                );
            }
        }
    }
    for (i, r) in results.iter().enumerate() {
        println!("\n#{} {}", i + 1, r.setting);
        print_pass_table(&r.passes, &r.frame);
        if args.pipeline_stats {
            print_counts_table(&r.passes);
            print_memory_table(&r.memory);
        }
    }
    if ctx.info.device_type == "CPU" {
        println!(
            "note: a CPU device (lavapipe): times are CPU time; the interleaved ratios are what compares, not absolute times."
        );
    }

    let mut written = Vec::new();
    if let Some(out) = trace_out {
        let runs: Vec<(String, &[FrameTiming])> =
            results.iter().zip(&timings).map(|(r, t)| (format!("prism GPU: {}", r.setting), t.as_slice())).collect();
        let trace = super::bench::chrome_trace_of(&runs, &scenes[0].name);
        written.push(out.write(serde_json::to_string(&trace)?.as_bytes())?);
    }
    if let Some(out) = json_out {
        let report = VersusReport {
            scene: scenes[0].name.clone(),
            scene_file: scenes[0].source.display().to_string(),
            device: ctx.info.clone(),
            width: renderers[0].width(),
            height: renderers[0].height(),
            frames: args.frames,
            warmup: args.warmup,
            git_revision: git_revision(),
            settings: args.scene.set.clone(),
            interleaving: "round-robin, one frame per setting per round, first setting rotating, each frame waited for",
            versus: results,
            host,
            note: "GPU timestamps; on a CPU device (lavapipe) these are CPU times: compare the ratios, not absolute values",
        };
        written.push(out.write(serde_json::to_string_pretty(&report)?.as_bytes())?);
    }
    output::commit_all(written)
}

fn pass_sum(f: &FrameTiming, names: &[&str]) -> f64 {
    f.passes.iter().filter(|p| names.contains(&p.name.as_str())).map(|p| p.duration_ms()).sum()
}

/// One line per setting: its technique passes, their median time and the frame's, and the
/// ratios to the first setting.
fn print_summary(results: &[VersusSetting]) {
    let sw = results.iter().map(|r| r.setting.len()).max().unwrap_or(7).max(7) + 3;
    println!(
        "{:sw$}  {:>12}  {:>12}  {:>24}  {:>24}  technique passes",
        "setting", "technique ms", "frame ms", "technique ratio min/med/max", "frame ratio min/med/max"
    );
    let fmt = |r: &Option<RatioStats>| {
        r.as_ref().map_or_else(|| "-".to_string(), |r| format!("{:.3}/{:.3}/{:.3}", r.min, r.median, r.max))
    };
    for (i, r) in results.iter().enumerate() {
        let label = format!("#{} {}", i + 1, r.setting);
        // Settings that differ in no technique (render.update, exposure) have no technique time.
        let technique_ms = match r.technique_passes.is_empty() {
            true => "-".to_string(),
            false => format!("{:.3}", r.technique.stats.median_ms),
        };
        println!(
            "{:sw$}  {:>12}  {:>12.3}  {:>24}  {:>24}  {}",
            label,
            technique_ms,
            r.frame.stats.median_ms,
            if i == 0 { "(1)".to_string() } else { fmt(&r.technique_ratio) },
            if i == 0 { "(1)".to_string() } else { fmt(&r.frame_ratio) },
            if r.technique_passes.is_empty() { "(none)".to_string() } else { r.technique_passes.join(", ") }
        );
    }
}

#[cfg(test)]
mod tests {
    use super::Interleave;

    /// Equal counts: every participant every round, the first rotating (`bench --versus`).
    /// Unequal: the shorter participant spread evenly, its last frame in the last round, and
    /// every participant renders exactly its frames.
    #[test]
    fn interleave_rotates_and_spreads() {
        let s = Interleave::new(vec![3, 3, 3]);
        let rounds: Vec<Vec<usize>> = s.order().collect();
        assert_eq!(rounds, [vec![0, 1, 2], vec![1, 2, 0], vec![2, 0, 1]]);
        let s = Interleave::new(vec![25, 25, 4]);
        let rounds: Vec<Vec<usize>> = s.order().collect();
        assert_eq!(rounds.len(), 25);
        let with_2: Vec<usize> = (0..25).filter(|&r| rounds[r].contains(&2)).collect();
        assert_eq!(with_2, [6, 12, 18, 24]);
        for i in 0..3 {
            let n = rounds.iter().map(|r| r.iter().filter(|&&k| k == i).count()).sum::<usize>();
            assert_eq!(n, [25, 25, 4][i]);
        }
        // The rounds with all three rotate among themselves: participant 2 takes every place.
        assert_eq!(
            [&rounds[6], &rounds[12], &rounds[18], &rounds[24]],
            [&[0, 1, 2], &[1, 2, 0], &[2, 0, 1], &[0, 1, 2]]
        );
        assert_eq!((&rounds[0], &rounds[1], &rounds[7]), (&vec![0, 1], &vec![1, 0], &vec![0, 1]));
        assert_eq!(Interleave::new(vec![0, 0]).order().count(), 0);
    }
}
