//! The demo's heads-up overlay (egui): per-pass GPU times, frame time, the scene's passes
//! with the plan's reasons, and controls for every parameter the scene exposes. Controls
//! do not touch the renderer: they edit `--set`-style overrides, and the window reloads the
//! scene with them and rebuilds the renderer.
use std::collections::{BTreeMap, VecDeque};

use crate::gpu::PassCounts;
use crate::renderer::plan::PlannedPass;
use crate::renderer::{FrameTiming, TechniqueMemory};
use crate::scene::techniques::{controls, Control, RaytraceParams, TABLES};
use crate::scene::{Light, Material, Scene, TECHNIQUE_KEYS};

use super::ab::{AbMode, AbOptions, AbStatus, MAX_PHOTONS};
use super::camera::Mode;

/// Passes the window appends after the scene's: timed and labelled like every pass, but
/// not part of any technique's cost.
pub use crate::renderer::{OVERLAY, PRESENT_BLIT};

/// Frames the averages run over.
const WINDOW: usize = 60;

/// Rolling GPU and CPU frame statistics.
#[derive(Default)]
pub struct Stats {
    gpu: VecDeque<FrameTiming>,
    cpu_ms: VecDeque<f64>,
}

impl Stats {
    pub fn push_gpu(&mut self, t: FrameTiming) {
        self.gpu.push_back(t);
        if self.gpu.len() > WINDOW {
            self.gpu.pop_front();
        }
    }

    pub fn push_cpu(&mut self, ms: f64) {
        self.cpu_ms.push_back(ms);
        if self.cpu_ms.len() > WINDOW {
            self.cpu_ms.pop_front();
        }
    }

    /// Forget GPU timings (the pass list changed with a rebuilt renderer).
    pub fn clear_gpu(&mut self) {
        self.gpu.clear();
    }

    pub fn cpu_avg_ms(&self) -> f64 {
        mean(self.cpu_ms.iter().copied())
    }

    pub fn cpu_last_ms(&self) -> f64 {
        self.cpu_ms.back().copied().unwrap_or(0.0)
    }

    /// (name, last ms, average ms, last frame's pipeline statistics) of every pass of the
    /// latest frame, in order.
    pub fn passes(&self) -> Vec<(String, f64, f64, Option<PassCounts>)> {
        let Some(last) = self.gpu.back() else { return Vec::new() };
        last.passes
            .iter()
            .map(|p| {
                let avg = mean(
                    self.gpu.iter().flat_map(|f| f.passes.iter().filter(|q| q.name == p.name).map(|q| q.duration_ms())),
                );
                (p.name.clone(), p.duration_ms(), avg, p.counts)
            })
            .collect()
    }

    /// Average technique total: first start to last end of the scene's own passes, without
    /// the window's blit and overlay.
    pub fn technique_total_ms(&self) -> f64 {
        mean(self.gpu.iter().map(technique_total))
    }
}

/// The scene passes' span of one frame (the overlay and blit excluded).
pub fn technique_total(f: &FrameTiming) -> f64 {
    let scene: Vec<_> = f.passes.iter().filter(|p| p.name != PRESENT_BLIT && p.name != OVERLAY).collect();
    if scene.is_empty() {
        return 0.0;
    }
    let start = scene.iter().map(|p| p.start_ms).fold(f64::INFINITY, f64::min);
    let end = scene.iter().map(|p| p.end_ms).fold(f64::NEG_INFINITY, f64::max);
    end - start
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// What the overlay asks the window to do this frame.
#[derive(Default)]
pub struct Requests {
    pub screenshot: bool,
    pub reset_camera: bool,
    pub toggle_mode: bool,
    pub reload: bool,
    /// The overrides changed: reload the scene with them and rebuild the renderer.
    pub rebuild: bool,
}

/// Overlay state that outlives a frame.
pub struct UiState {
    pub visible: bool,
    /// Overrides set from the overlay, by key (applied after the command line's).
    pub overrides: BTreeMap<String, String>,
    /// Animate heightfield objects (water) with the elapsed time.
    pub animate: bool,
    /// The last scene or renderer error, shown until the next successful rebuild.
    pub error: Option<String>,
    /// The last status line (a screenshot written, a reload).
    pub status: Option<String>,
    /// Count each pass's invocations with pipeline-statistics queries, shown beside its time.
    pub counts: bool,
    /// The intermediate target shown in place of the final image (`None`: the final image).
    pub shown_target: Option<String>,
    /// Map the shown target's range (min..max over its finite values) to black..white
    /// instead of clamping to [0, 1].
    pub normalize_target: bool,
    /// The A/B view against the live exact image.
    pub ab: AbOptions,
}

impl UiState {
    pub fn new(visible: bool) -> Self {
        UiState {
            visible,
            overrides: BTreeMap::new(),
            animate: true,
            error: None,
            status: None,
            counts: false,
            shown_target: None,
            normalize_target: false,
            ab: AbOptions::default(),
        }
    }

    fn set(&mut self, requests: &mut Requests, key: String, value: String) {
        self.overrides.insert(key, value);
        requests.rebuild = true;
    }
}

/// Facts the overlay shows.
pub struct View<'a> {
    pub scene: &'a Scene,
    pub plan: &'a [PlannedPass],
    pub device: &'a str,
    pub render_size: (u32, u32),
    pub present_mode: &'a str,
    pub stats: &'a Stats,
    pub camera_mode: Mode,
    pub has_heightfield: bool,
    /// The adaptive tone map's state in the last completed frame (`render.tonemap = "adaptive"`).
    pub tonemap: Option<crate::technique::baseline::tonemap::AdaptiveStats>,
    /// Device memory per technique, as `prism bench --pipeline-stats` prints it.
    pub memory: &'a [TechniqueMemory],
    /// The frame's images that can be shown in place of the final image.
    pub targets: &'a [String],
    /// The shown target, read back after the last frame.
    pub target_texture: Option<&'a egui::TextureHandle>,
    /// The A/B view's exact image and live error, while it is on and has samples.
    pub ab: Option<AbStatus>,
    /// Long work in progress (the eikonal light simulation).
    pub progress: Option<WorkProgress>,
    /// The frames the shown image averages, where the raytrace technique accumulates them
    /// (`render.raytrace.accumulate`).
    pub accumulated: Option<u32>,
}

/// Long work in progress, as the renderer reports it.
#[derive(Clone, Debug)]
pub struct WorkProgress {
    pub task: String,
    pub detail: String,
    /// Done, 0..1.
    pub fraction: f32,
}

/// The current value of `render.<key>` for a technique key.
fn technique_value<'a>(scene: &'a Scene, key: &str, accepted: &'a [&'a str]) -> &'a str {
    match key {
        "refraction" => &scene.render.refraction,
        "reflection" => &scene.render.reflection,
        "caustics" => &scene.render.caustics,
        "tonemap" => &scene.render.tonemap,
        "update" => &scene.render.update,
        _ => accepted.first().copied().unwrap_or(""),
    }
}

pub fn format_vec(v: glam::Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// Draw the overlay; returns what the window should do.
pub fn draw(ctx: &egui::Context, state: &mut UiState, view: &View) -> Requests {
    let mut req = Requests::default();
    if let Some(texture) = view.target_texture {
        // In place of the final image: the whole window, the overlay on top.
        egui::CentralPanel::default().frame(egui::Frame::NONE.fill(egui::Color32::BLACK)).show(ctx, |ui| {
            ui.add(egui::Image::new(texture).fit_to_exact_size(ui.available_size()));
        });
    }
    if !state.visible {
        return req;
    }
    egui::Window::new(format!("prism: {}", view.scene.name))
        .default_pos([8.0, 8.0])
        .default_width(300.0)
        .resizable(true)
        .show(ctx, |ui| {
            ui.label(format!(
                "{} · {}x{} · {}",
                view.device, view.render_size.0, view.render_size.1, view.present_mode
            ));
            if let Some(e) = &state.error {
                ui.colored_label(egui::Color32::from_rgb(255, 96, 96), format!("error: {e}"));
            }
            if let Some(s) = &state.status {
                ui.label(s);
            }
            if let Some(p) = &view.progress {
                ui.add(egui::ProgressBar::new(p.fraction).text(format!("{} {:.0}%", p.task, 100.0 * p.fraction)));
                ui.small(&p.detail);
            }
            ui.separator();
            ui.checkbox(&mut state.counts, "count invocations (pipeline statistics)");
            timings(ui, view, state.counts);
            egui::CollapsingHeader::new("memory per technique").default_open(false).show(ui, |ui| {
                memory(ui, view.memory);
            });
            shown_target(ui, state, view.targets);
            ab_view(ui, &mut state.ab, view);
            ui.separator();
            egui::CollapsingHeader::new("passes (why each runs)").default_open(false).show(ui, |ui| {
                for p in view.plan {
                    ui.label(egui::RichText::new(p.name).strong());
                    ui.label(&p.reason);
                }
            });
            egui::CollapsingHeader::new("parameters").default_open(true).show(ui, |ui| {
                parameters(ui, state, view, &mut req);
            });
            ui.separator();
            ui.horizontal(|ui| {
                if ui.button(format!("camera: {}", view.camera_mode.name())).clicked() {
                    req.toggle_mode = true;
                }
                if ui.button("reset camera").clicked() {
                    req.reset_camera = true;
                }
            });
            ui.horizontal(|ui| {
                if ui.button("screenshot").clicked() {
                    req.screenshot = true;
                }
                if ui.button("reload scene").clicked() {
                    req.reload = true;
                }
                if ui.button("defaults").clicked() && !state.overrides.is_empty() {
                    state.overrides.clear();
                    req.rebuild = true;
                }
            });
        });
    req
}

/// A count for a narrow column: 1234 -> "1.2k", 3456789 -> "3.5M".
fn short_count(n: u64) -> String {
    match n {
        0..=9_999 => n.to_string(),
        10_000..=9_999_999 => format!("{:.1}k", n as f64 / 1e3),
        _ => format!("{:.1}M", n as f64 / 1e6),
    }
}

/// Which of the frame's images the window shows (`prism render --targets` writes them all).
fn shown_target(ui: &mut egui::Ui, state: &mut UiState, targets: &[String]) {
    ui.horizontal(|ui| {
        ui.label("show");
        let selected = state.shown_target.clone().unwrap_or_else(|| "final image".to_string());
        egui::ComboBox::from_id_salt("shown_target").selected_text(selected).show_ui(ui, |ui| {
            ui.selectable_value(&mut state.shown_target, None, "final image");
            for t in targets {
                ui.selectable_value(&mut state.shown_target, Some(t.clone()), t);
            }
        });
        ui.checkbox(&mut state.normalize_target, "min..max");
    });
}

/// The A/B view's controls, its live error and both costs.
fn ab_view(ui: &mut egui::Ui, ab: &mut AbOptions, view: &View) {
    ui.horizontal(|ui| {
        ui.checkbox(&mut ab.on, "A/B against the exact image");
        egui::ComboBox::from_id_salt("ab_mode").selected_text(ab.mode.name()).show_ui(ui, |ui| {
            for m in AbMode::ALL {
                ui.selectable_value(&mut ab.mode, m, m.name());
            }
        });
    });
    if !ab.on {
        return;
    }
    ui.horizontal(|ui| {
        ui.label("split");
        ui.add(egui::Slider::new(&mut ab.split, 0.0..=1.0).show_value(false));
        ui.label("photons/sample");
        ui.add(egui::DragValue::new(&mut ab.photons).range(0..=MAX_PHOTONS).speed(256.0));
    });
    let technique_ms = view.stats.technique_total_ms();
    match &view.ab {
        None => {
            ui.label("exact image: starts when the view holds still");
        }
        Some(s) => {
            ui.label(format!(
                "technique {technique_ms:.1} ms/frame (GPU) · exact {} samples of {} photons, {:.1} ms/sample",
                s.samples, s.photons, s.ms_per_sample
            ));
            if let Some((n, e)) = &s.errors {
                ui.label(format!(
                    "FLIP mean {:.4} · HDR-FLIP {:.4} · relMSE {:.5} · RMSE {:.5} (at {n} samples)",
                    e.flip_mean, e.hdr_flip_mean, e.rel_mse, e.rmse
                ));
            }
        }
    }
}

fn memory(ui: &mut egui::Ui, memory: &[TechniqueMemory]) {
    let mib = |b: u64| format!("{:.2}", b as f64 / (1024.0 * 1024.0));
    egui::Grid::new("memory").striped(true).num_columns(4).show(ui, |ui| {
        for h in ["technique", "buffers MiB", "images MiB", "volumes MiB"] {
            ui.label(egui::RichText::new(h).strong());
        }
        ui.end_row();
        for m in memory {
            ui.label(&m.technique);
            ui.label(mib(m.bytes.buffer_bytes));
            ui.label(mib(m.bytes.image_bytes));
            ui.label(mib(m.bytes.volume_bytes));
            ui.end_row();
        }
    });
}

fn timings(ui: &mut egui::Ui, view: &View, counts: bool) {
    let s = view.stats;
    let cpu = s.cpu_avg_ms();
    ui.label(format!(
        "frame {:.1} ms avg ({:.1} fps), last {:.1} ms",
        cpu,
        if cpu > 0.0 { 1000.0 / cpu } else { 0.0 },
        s.cpu_last_ms()
    ));
    let columns = if counts { 6 } else { 3 };
    egui::Grid::new("gpu_times").striped(true).num_columns(columns).show(ui, |ui| {
        let mut heads = vec!["GPU pass", "avg ms", "last ms"];
        if counts {
            heads.extend(["vertices", "fragments", "compute"]);
        }
        for h in heads {
            ui.label(egui::RichText::new(h).strong());
        }
        ui.end_row();
        for (name, last, avg, pass_counts) in s.passes() {
            let window_pass = name == PRESENT_BLIT || name == OVERLAY;
            let text = if window_pass { format!("({name})") } else { name };
            ui.label(text);
            ui.label(format!("{avg:.3}"));
            ui.label(format!("{last:.3}"));
            if counts {
                // Lavapipe counts fragments per 4x4 block a triangle touches, and cannot count
                // compute invocations (src/gpu/timing.rs): "-" there.
                let c = pass_counts.unwrap_or_default();
                ui.label(short_count(c.vertex_invocations));
                ui.label(short_count(c.fragment_invocations));
                ui.label(c.compute_invocations.map_or_else(|| "-".to_string(), short_count));
            }
            ui.end_row();
        }
        ui.label(egui::RichText::new("technique total").strong());
        ui.label(egui::RichText::new(format!("{:.3}", s.technique_total_ms())).strong());
        ui.label("");
        ui.end_row();
    });
    ui.small("(window passes in parentheses: not in the total)");
    if let Some(n) = view.accumulated {
        let limit = RaytraceParams::from_settings(&view.scene.render).map_or(1, |p| p.accumulate);
        // The pass list's raytrace_accumulate averages these; any change starts again at 1.
        ui.label(format!("raytrace: {n} of {limit} frames accumulated (any change restarts)"));
    }
}

fn parameters(ui: &mut egui::Ui, state: &mut UiState, view: &View, req: &mut Requests) {
    let scene = view.scene;
    egui::Grid::new("params").num_columns(2).show(ui, |ui| {
        for (key, accepted) in TECHNIQUE_KEYS {
            let current = technique_value(scene, key, accepted).to_string();
            ui.label(*key);
            let mut chosen = current.clone();
            egui::ComboBox::from_id_salt(*key).selected_text(&chosen).show_ui(ui, |ui| {
                for v in *accepted {
                    ui.selectable_value(&mut chosen, v.to_string(), *v);
                }
            });
            if chosen != current {
                state.set(req, format!("render.{key}"), format!("\"{chosen}\""));
            }
            ui.end_row();
        }

        ui.label("exposure");
        let mut exposure = scene.render.exposure;
        if ui.add(egui::Slider::new(&mut exposure, 0.05..=16.0).logarithmic(true)).changed() {
            state.set(req, "render.exposure".into(), exposure.to_string());
        }
        ui.end_row();

        if let Some(t) = view.tonemap {
            // The adaptive tone map (Krawczyk et al. 2005): the frame's log-average, the
            // luminance the eye has adapted to so far, the key and L_white.
            ui.label("adaptation");
            ui.label(format!(
                "L_avg {:.3e}  L_a {:.3e}\nkey {:.3}  L_white {:.3}",
                t.l_avg, t.l_adapted, t.key, t.white
            ));
            ui.end_row();
        }

        ui.label("shadow map");
        let mut size = scene.render.shadow_map_size;
        egui::ComboBox::from_id_salt("shadow_map_size").selected_text(size.to_string()).show_ui(ui, |ui| {
            for s in [128u32, 256, 512, 1024, 2048, 4096] {
                ui.selectable_value(&mut size, s, s.to_string());
            }
        });
        if size != scene.render.shadow_map_size {
            state.set(req, "render.shadow_map_size".into(), size.to_string());
        }
        ui.end_row();

        ui.label("sphere segments");
        let mut segments = scene.render.sphere_segments;
        if ui.add(egui::Slider::new(&mut segments, 8..=512).logarithmic(true)).changed() {
            state.set(req, "render.sphere_segments".into(), segments.to_string());
        }
        ui.end_row();

        for (name, m) in scene.material_names.iter().zip(&scene.materials) {
            if let Material::Dielectric { ior, .. } = m {
                ui.label(format!("{name} ior"));
                let mut v = ior.x;
                let dispersive = ior.y != ior.x || ior.z != ior.x;
                let slider = egui::Slider::new(&mut v, 1.0..=3.0);
                if ui.add_enabled(!dispersive, slider).changed() {
                    state.set(req, format!("materials.{name}.ior"), v.to_string());
                }
                ui.end_row();
            }
        }

        technique_parameters(ui, state, scene, req);

        if let Some(light) = scene.lights.first() {
            let (key, mut v) = match light {
                Light::Point { position, .. } => ("lights.0.position", *position),
                Light::Directional { direction, .. } => ("lights.0.direction", *direction),
            };
            ui.label(if key.ends_with("position") { "light 0 position" } else { "light 0 direction" });
            let before = v;
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(&mut v.x).speed(0.02));
                ui.add(egui::DragValue::new(&mut v.y).speed(0.02));
                ui.add(egui::DragValue::new(&mut v.z).speed(0.02));
            });
            if v != before {
                state.set(req, key.into(), format_vec(v));
            }
            ui.end_row();
        }

        for (i, name, center) in object_centers(scene) {
            ui.label(format!("{name} center"));
            let mut v = center;
            ui.horizontal(|ui| {
                ui.add(egui::DragValue::new(&mut v.x).speed(0.02));
                ui.add(egui::DragValue::new(&mut v.y).speed(0.02));
                ui.add(egui::DragValue::new(&mut v.z).speed(0.02));
            });
            if v != center {
                state.set(req, format!("objects.{i}.center"), format_vec(v));
            }
            ui.end_row();
        }

        if view.has_heightfield {
            ui.label("animate water");
            ui.checkbox(&mut state.animate, "");
            ui.end_row();
        }
    });
}

/// The parameter tables of the techniques the scene selects: one per selected refraction,
/// reflection and caustics technique, the adaptive tone map's, the eikonal renderer's with a
/// volume, and the distance impostors' for the light-map caustics built on them.
fn selected_tables(scene: &Scene) -> Vec<String> {
    let r = &scene.render;
    let mut tables = vec![r.refraction.clone(), r.reflection.clone(), r.caustics.clone()];
    tables.push(format!("tonemap_{}", r.tonemap));
    if scene.volume.is_some() {
        tables.push("eikonal".into());
    }
    if r.caustics == "impostor_lightmap" {
        tables.push("impostor".into());
    }
    let mut seen = Vec::new();
    tables.retain(|t| {
        TABLES.contains(&t.as_str()) && !seen.contains(t) && {
            seen.push(t.clone());
            true
        }
    });
    tables
}

/// Every key of the selected techniques' tables, with its value (the default when the file
/// has none), its range and its meaning as a tooltip: the controls come from the same
/// declarations as the parser and docs/scene-format.md (src/scene/techniques.rs).
fn technique_parameters(ui: &mut egui::Ui, state: &mut UiState, scene: &Scene, req: &mut Requests) {
    for table in selected_tables(scene) {
        let Some(views) = controls(&table, &scene.render) else { continue };
        for view in views {
            ui.label(format!("{table}.{}", view.key)).on_hover_text(&view.doc);
            let mut control = view.control.clone();
            let changed = match &mut control {
                Control::Integer { value, range } => {
                    let wide = *range.end() > 64 * range.start().max(&1);
                    ui.add(egui::Slider::new(value, range.clone()).logarithmic(wide)).changed()
                }
                Control::Number { value, range } | Control::Auto { value: Some(value), range } => {
                    let wide = *range.start() > 0.0 && *range.end() > 100.0 * range.start();
                    ui.add(egui::Slider::new(value, range.clone()).logarithmic(wide)).changed()
                }
                Control::Auto { value: None, .. } => {
                    ui.label("auto");
                    false
                }
                Control::Bool(b) => ui.checkbox(b, "").changed(),
                Control::Choice { value, names } => {
                    let before = *value;
                    egui::ComboBox::from_id_salt(format!("{table}.{}", view.key)).selected_text(*value).show_ui(
                        ui,
                        |ui| {
                            for n in names.iter() {
                                ui.selectable_value(value, *n, *n);
                            }
                        },
                    );
                    *value != before
                }
            };
            if changed {
                state.set(req, format!("render.{table}.{}", view.key), control.toml());
            }
            ui.end_row();
        }
    }
}

/// (index, name, center) of every object whose file entry has a `center` (spheres, quads,
/// boxes, heightfields...), read from the effective scene text: moving one is an override.
pub fn object_centers(scene: &Scene) -> Vec<(usize, String, glam::Vec3)> {
    let Ok(table) = scene.canonical.parse::<toml::Table>() else { return Vec::new() };
    let Some(toml::Value::Array(objects)) = table.get("objects") else { return Vec::new() };
    let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| {
            let c = o.get("center")?.as_array()?;
            let xyz: Vec<f32> = c.iter().filter_map(number).map(|x| x as f32).collect();
            let name = o.get("name").and_then(|n| n.as_str()).unwrap_or("object").to_string();
            (xyz.len() == 3).then(|| (i, name, glam::Vec3::new(xyz[0], xyz[1], xyz[2])))
        })
        .collect()
}

/// The override that moves light 0 by `delta` (point light) or turns its direction
/// (directional light: `delta` added to the unit direction, then renormalized on load).
pub fn light_override(scene: &Scene, delta: glam::Vec3) -> Option<(String, String)> {
    match scene.lights.first()? {
        Light::Point { position, .. } => Some(("lights.0.position".into(), format_vec(*position + delta))),
        Light::Directional { direction, .. } => {
            let d = (*direction + delta).try_normalize()?;
            Some(("lights.0.direction".into(), format_vec(d)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::renderer::PassTime;

    fn frame(passes: &[(&str, f64, f64)]) -> FrameTiming {
        FrameTiming {
            frame: 0,
            gpu_start_ms: 0.0,
            passes: passes
                .iter()
                .map(|&(n, s, e)| PassTime { name: n.into(), start_ms: s, end_ms: e, counts: None, idle: false })
                .collect(),
        }
    }

    #[test]
    fn object_centers_come_from_the_scene_file() {
        let scene = crate::scene::load(&crate::scene::benchmark_scene_path("sphere_nearby"), &[]).unwrap();
        let centers = object_centers(&scene);
        assert!(!centers.is_empty());
        let (i, _, c) = &centers[0];
        assert_eq!(scene.objects[*i].name, centers[0].1);
        assert!(c.is_finite());
    }

    #[test]
    fn technique_total_excludes_the_window_passes() {
        let f = frame(&[("gbuffer", 0.0, 1.0), ("tonemap", 1.0, 1.5), (PRESENT_BLIT, 1.5, 2.0), (OVERLAY, 2.0, 5.0)]);
        assert_eq!(technique_total(&f), 1.5);
        let mut s = Stats::default();
        s.push_gpu(f);
        s.push_gpu(frame(&[("gbuffer", 0.0, 3.0), ("tonemap", 3.0, 3.5), (OVERLAY, 3.5, 9.0)]));
        assert_eq!(s.technique_total_ms(), 2.5);
        let passes = s.passes();
        assert_eq!(passes[0], ("gbuffer".to_string(), 3.0, 2.0, None));
    }
}
