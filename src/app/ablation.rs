//! `prism ablation`: where an image-space refraction technique's error comes from. The
//! technique is measured with each of its approximations replaced, one at a time, by the
//! exact tracer's value (`render.wyman.oracle`, `render.hu_qin.oracle`; for the distance
//! impostors, `render.impostor.oracle`, `Hit()` alone; for caustics mapping,
//! `render.caustics_map.oracle`, the receiver estimate alone), and with all of them replaced,
//! in one interleaved run against one cached reference. A step's share of the error is the error it
//! removes when made exact (error of the paper's technique minus error with that step exact);
//! what remains with every step exact is the model's structural error (two interfaces, no
//! internal reflection, Fresnel at P1 only). The shares need not add up: the steps interact
//! (an exact exit point also moves the texel §3.2's normal is read from).
use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;

use super::compare::{cached_reference, MeasureArgs};
use super::equaltime::{measure_interleaved, reference_noise, Noise, Setting};
use super::output::{self, Outputs};
use super::{check_validation, GpuArgs, SceneArgs};
use crate::scene::techniques::{CausticsMapOracle, HuQinOracle, ImpostorOracle, WymanOracle};

#[derive(Args, Debug)]
pub struct AblationArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The technique whose approximations are replaced: wyman, hu_qin, impostor (the
    /// distance impostors' reflection and refraction, whose `Hit()` is replaced) or
    /// caustics_map (Shah et al.'s caustics, whose receiver estimate is replaced; the scene's
    /// refraction stays, and the reference traces its photons as `prism compare`'s does).
    #[arg(long, default_value = "wyman")]
    pub technique: String,
    /// Also write the table as JSON to this file.
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub measure: MeasureArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// One row of the table: the technique with `oracle` exact.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AblationRow {
    /// The oracle value (`"none"`: the paper's technique; `"all"`: every step exact).
    pub oracle: String,
    pub rmse: f64,
    pub flip_mean: f64,
    /// Error of `"none"` minus this row's: the part of the error this step causes
    /// (for `"all"`, what all steps together cause).
    pub rmse_share: f64,
    pub flip_mean_share: f64,
    /// Median GPU frame time (ms): the oracle's tracing is not the technique's cost.
    pub frame_ms: f64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct Ablation {
    pub scene: String,
    pub technique: String,
    pub width: u32,
    pub height: u32,
    pub revision: String,
    pub device: String,
    pub rows: Vec<AblationRow>,
    /// The model's structural error: the error with every step exact (RMSE, FLIP mean).
    pub residual_rmse: f64,
    pub residual_flip_mean: f64,
    /// How much of a measured error the reference's noise may account for
    /// ([`Noise::floor`]): a measured e stands for a true error in [e - floor, e], and a
    /// share (a difference of two errors) is known to within +- floor.
    pub noise_floor_rmse: f64,
    pub noise_floor_flip_mean: f64,
    pub noise: Noise,
}

/// The oracle values of `technique`, the paper's first and every step exact last.
pub fn oracle_values(technique: &str) -> Result<Vec<&'static str>> {
    match technique {
        "wyman" => Ok(WymanOracle::NAMES.to_vec()),
        "hu_qin" => Ok(HuQinOracle::NAMES.to_vec()),
        "impostor" => Ok(ImpostorOracle::NAMES.to_vec()),
        "caustics_map" => Ok(CausticsMapOracle::NAMES.to_vec()),
        _ => bail!("--technique {technique}: the oracle ablation knows wyman, hu_qin, impostor and caustics_map"),
    }
}

/// The table from one measurement per oracle value (in [`oracle_values`]' order).
pub fn table(values: &[&str], errors: &[(f64, f64, f64)]) -> (Vec<AblationRow>, (f64, f64)) {
    let (none_rmse, none_flip, _) = errors[0];
    let rows = values
        .iter()
        .zip(errors)
        .map(|(v, &(rmse, flip_mean, frame_ms))| AblationRow {
            oracle: v.to_string(),
            rmse,
            flip_mean,
            rmse_share: none_rmse - rmse,
            flip_mean_share: none_flip - flip_mean,
            frame_ms,
        })
        .collect::<Vec<_>>();
    let last = rows.last().map(|r| (r.rmse, r.flip_mean)).unwrap_or_default();
    (rows, last)
}

/// The stacked table as text: each step's error with it exact and its share of the paper's
/// error, then the residual with everything exact.
pub fn format_table(a: &Ablation) -> String {
    let mut s = format!(
        "oracle ablation: {} on {} ({}x{}), {} ({})\n",
        a.technique, a.scene, a.width, a.height, a.device, a.revision
    );
    s += &format!(
        "reference noise: a measured error e stands for a true one in [e - floor, e]; \
         floor RMSE {:.4}, FLIP mean {:.4} (a share: +- floor)\n",
        a.noise_floor_rmse, a.noise_floor_flip_mean
    );
    s += "step exact   | RMSE    | share of RMSE    | FLIP mean | share of FLIP    | frame ms\n";
    s += "-------------|---------|------------------|-----------|------------------|---------\n";
    let none = &a.rows[0];
    let pct = |share: f64, of: f64| if of > 0.0 { 100.0 * share / of } else { 0.0 };
    for r in &a.rows {
        let (rs, fs) = if r.oracle == "none" {
            ("(the paper's)".to_string(), "(the paper's)".to_string())
        } else {
            (
                format!("{:.4} ({:.0}%)", r.rmse_share, pct(r.rmse_share, none.rmse)),
                format!("{:.4} ({:.0}%)", r.flip_mean_share, pct(r.flip_mean_share, none.flip_mean)),
            )
        };
        s += &format!(
            "{:<12} | {:.4}  | {:<16} | {:.4}    | {:<16} | {:.1}\n",
            r.oracle, r.rmse, rs, r.flip_mean, fs, r.frame_ms
        );
    }
    s += &format!(
        "residual with every step exact (the model's structural error): RMSE {:.4} ({:.0}%), FLIP mean {:.4} ({:.0}%)\n",
        a.residual_rmse,
        pct(a.residual_rmse, none.rmse),
        a.residual_flip_mean,
        pct(a.residual_flip_mean, none.flip_mean)
    );
    s
}

pub fn run(args: AblationArgs) -> Result<()> {
    let values = oracle_values(&args.technique)?;
    let settings = args.measure.reference.settings();
    settings.validate()?;
    let mut scenes = Vec::new();
    for v in &values {
        let mut sa = args.scene.clone();
        if args.technique == "caustics_map" {
            // A caustics technique: the scene's refraction and reflection draw the specular
            // objects as before, and only the caustic map changes between the rows.
            sa.set.push("render.caustics=caustics_map".to_string());
        } else {
            sa.set.push(format!("render.refraction={}", args.technique));
        }
        if args.technique == "impostor" {
            // The distance impostors serve mirrors and conductors too (§3).
            sa.set.push("render.reflection=impostor".to_string());
        }
        sa.set.push(format!("render.{}.oracle={v}", args.technique));
        scenes.push(sa.load()?);
    }
    let mut outputs = Outputs::default();
    let json_out = outputs.prepare_opt(args.json.as_deref())?;
    let ctx = args.gpu.context()?;
    // One truth: the oracle changes the technique, not the scene.
    let reference = cached_reference(&ctx, &scenes[0], &settings, args.measure.reference_policy())?.image;
    let noise = reference_noise(&ctx, &scenes[0], &settings, &reference, args.measure.reference_policy())?;
    let timed: Vec<Setting> = scenes.iter().map(|scene| Setting { scene, reference: &reference }).collect();
    let (measured, _) = measure_interleaved(&ctx, &timed, &args.measure, None)?;
    check_validation(&ctx)?;
    let errors: Vec<(f64, f64, f64)> =
        measured.iter().map(|m| (m.errors.rmse, m.errors.flip_mean, m.frame.median_ms)).collect();
    let (rows, (residual_rmse, residual_flip_mean)) = table(&values, &errors);
    let a = Ablation {
        scene: scenes[0].name.clone(),
        technique: args.technique.clone(),
        width: scenes[0].camera.width,
        height: scenes[0].camera.height,
        revision: super::bench::git_revision(),
        device: ctx.info.name.clone(),
        rows,
        residual_rmse,
        residual_flip_mean,
        noise_floor_rmse: noise.floor("rmse"),
        noise_floor_flip_mean: noise.floor("flip_mean"),
        noise,
    };
    print!("{}", format_table(&a));
    if let Some(out) = json_out {
        output::commit_all([out.write(serde_json::to_string_pretty(&a)?.as_bytes())?])?;
        eprintln!("wrote {}", args.json.as_ref().unwrap().display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Shares are the paper's error minus the error with the step exact; the residual is the
    /// last row's (every step exact).
    #[test]
    fn shares_are_differences_from_the_papers_error() {
        let values = oracle_values("wyman").unwrap();
        assert_eq!(values.first(), Some(&"none"));
        assert_eq!(values.last(), Some(&"all"));
        let errors = [(0.30, 0.20, 1.0), (0.18, 0.15, 2.0), (0.25, 0.12, 2.0), (0.05, 0.04, 3.0)];
        let (rows, residual) = table(&values, &errors);
        assert!((rows[1].rmse_share - 0.12).abs() < 1e-12 && (rows[2].flip_mean_share - 0.08).abs() < 1e-12);
        assert_eq!(rows[0].rmse_share, 0.0);
        assert_eq!(residual, (0.05, 0.04));
        assert!(oracle_values("single").is_err());
        assert_eq!(oracle_values("hu_qin").unwrap().last(), Some(&"all"));
        assert_eq!(oracle_values("impostor").unwrap(), ["none", "hit"]);
        assert_eq!(oracle_values("caustics_map").unwrap(), ["none", "receiver"]);
    }
}
