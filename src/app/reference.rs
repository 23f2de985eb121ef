//! `prism reference`: the exact reference image of a scene (src/reference), written as
//! linear EXR (and PNG), with a progress bar and an estimate of the time left.
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::reference::{Reference, ReferenceSettings, ReferenceStats};

use super::output::{self, Outputs};
use super::{check_validation, GpuArgs, SceneArgs};

/// Settings of the reference renderer, shared by `reference`, `compare` and `sweep`.
#[derive(Args, Debug, Clone)]
pub struct ReferenceArgs {
    /// Samples per pixel (each is also one photon-mapping iteration).
    #[arg(long, default_value_t = ReferenceSettings::default().spp)]
    pub spp: u32,
    /// Photons in all, for caustics (0: none).
    #[arg(long, default_value_t = ReferenceSettings::default().photons)]
    pub photons: u64,
    /// Specular interactions followed per path.
    #[arg(long, default_value_t = ReferenceSettings::default().max_depth)]
    pub max_depth: u32,
    /// Random seed; the same seed gives the same image.
    #[arg(long, default_value_t = ReferenceSettings::default().seed)]
    pub seed: u32,
    /// Initial photon gathering radius in metres (default: 1% of the scene's radius).
    #[arg(long)]
    pub radius: Option<f32>,
    /// Initial radius of each pixel in pixel footprints on its receiver, at most --radius;
    /// the caustic is then averaged over the pixel's area (0: every pixel starts at --radius
    /// with its centre ray's visible point, the fixed rule).
    #[arg(long, default_value_t = ReferenceSettings::default().footprint)]
    pub footprint: f32,
    /// SPPM radius reduction alpha (Hachisuka et al. 2008, Eq. 7), in (0, 1).
    #[arg(long, default_value_t = ReferenceSettings::default().alpha)]
    pub alpha: f32,
    /// Supersample each pixel's area (default: the ray through the pixel centre, as SCENES.md).
    #[arg(long)]
    pub jitter: bool,
}

impl ReferenceArgs {
    pub fn settings(&self) -> ReferenceSettings {
        ReferenceSettings {
            spp: self.spp,
            photons: self.photons,
            max_depth: self.max_depth,
            seed: self.seed,
            radius: self.radius,
            footprint: self.footprint,
            alpha: self.alpha,
            jitter: self.jitter,
        }
    }
}

#[derive(Args, Debug)]
pub struct ReferenceCmd {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output file: .exr (linear radiance) or .png (tone-mapped like `render`).
    #[arg(short, long, default_value = "reference.exr")]
    pub output: PathBuf,
    /// Also write a tone-mapped PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    #[command(flatten)]
    pub reference: ReferenceArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// A progress bar with the time left, on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(len: u64, message: String) -> ProgressBar {
    let bar = ProgressBar::new(len).with_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {per_sec} elapsed {elapsed} left {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(message);
    bar
}

/// Render the reference of `scene` with a progress bar. Returns RGBA f32 and what its
/// kernels counted (paths cut by the driver's loop limit or ended at the step cap).
pub fn render_reference(
    ctx: &std::sync::Arc<crate::gpu::GpuContext>,
    scene: &crate::scene::Scene,
    settings: &ReferenceSettings,
) -> Result<(Vec<f32>, ReferenceStats)> {
    let mut r = Reference::new(ctx, scene, settings).context("cannot set up the reference renderer")?;
    let bar = progress_bar(
        settings.spp as u64,
        format!("reference {} ({} photons/iteration)", scene.name, r.photons_per_iteration()),
    );
    r.run_all(|done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    Ok((r.image(), r.stats()))
}

pub fn run(args: ReferenceCmd) -> Result<()> {
    let scene = args.scene.load()?;
    let settings = args.reference.settings();
    settings.validate()?;
    let mut outputs = Outputs::default();
    let out = outputs.prepare(&args.output)?;
    let png = outputs.prepare_opt(args.png.as_deref())?;
    let ctx = args.gpu.context()?;
    let t = std::time::Instant::now();
    let (image, stats) = render_reference(&ctx, &scene, &settings)?;
    check_validation(&ctx)?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let is_png = args.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let out = if is_png {
        output::write_png(out, w, h, &output::tonemap_scene(&image, &scene.render))?
    } else {
        output::write_exr(out, w, h, &image)?
    };
    let png = png.map(|png| output::write_png(png, w, h, &output::tonemap_scene(&image, &scene.render))).transpose()?;
    output::commit_all(std::iter::once(out).chain(png))?;
    eprintln!(
        "wrote {} ({w}x{h}, scene {}, {} spp, {} photons, {:.1} s on {})",
        args.output.display(),
        scene.name,
        settings.spp,
        if settings.photons > 0 { settings.photons.to_string() } else { "no".into() },
        t.elapsed().as_secs_f32(),
        ctx.info.name
    );
    if let Some(w) = stats.warning(&scene.name) {
        eprintln!("warning: {w}");
    }
    Ok(())
}
