//! `prism scenes`: the bundled scenes (assets/scenes/*.toml), each with its description, the
//! techniques it selects (read from the files themselves) and its typical render time on the
//! machine named in assets/scene-times.toml (written by scripts/scene-times).
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::scene;

/// assets/scene-times.toml.
#[derive(serde::Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SceneTimes {
    pub command: String,
    pub machine: String,
    pub device: String,
    pub driver: String,
    pub revision: String,
    pub date: String,
    /// What else ran on the machine, when it was not idle.
    pub note: Option<String>,
    #[serde(default)]
    pub scene: BTreeMap<String, SceneTime>,
}

/// One scene's entry: the wall-clock seconds of `prism render NAME` and the frame's GPU
/// time, or why it was not measured.
#[derive(serde::Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SceneTime {
    pub seconds: Option<f64>,
    pub frame_ms: Option<f64>,
    pub not_measured: Option<String>,
}

pub fn times_path() -> PathBuf {
    scene::assets_dir().join("scene-times.toml")
}

/// The times file at `path`; `None` when there is none.
pub fn read_times(path: &Path) -> Result<Option<SceneTimes>> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("{}: cannot read the scene times", path.display())),
    };
    let times = toml::from_str(&text).map_err(|e| {
        anyhow::anyhow!("{}: {}\nrerun scripts/scene-times to rewrite it", path.display(), e.to_string().trim_end())
    })?;
    Ok(Some(times))
}

/// What `prism scenes` prints for one scene's time.
fn time_line(times: Option<&SceneTimes>, name: &str) -> String {
    match times.and_then(|t| t.scene.get(name)) {
        Some(SceneTime { seconds: Some(s), frame_ms, .. }) => match frame_ms {
            Some(ms) => format!("render {s:.1} s (GPU frame {ms:.0} ms)"),
            None => format!("render {s:.1} s"),
        },
        Some(SceneTime { not_measured: Some(why), .. }) => format!("render time not measured ({why})"),
        _ => "render time not measured".into(),
    }
}

pub fn run() -> Result<()> {
    use std::fmt::Write as _;
    let names = scene::bundled_scenes().context("cannot list assets/scenes/")?;
    let times = read_times(&times_path())?;
    let mut out = String::new();
    let scenes_dir = scene::assets_dir().join("scenes");
    writeln!(out, "bundled scenes ({}; `prism render NAME` renders one):", scenes_dir.display())?;
    let width = names.iter().map(|n| n.len()).max().unwrap_or(0);
    for name in &names {
        let s = scene::load(&scene::benchmark_scene_path(name), &[])?;
        let r = &s.render;
        writeln!(
            out,
            "  {name:width$}  refraction {}, reflection {}, caustics {}",
            r.refraction, r.reflection, r.caustics
        )?;
        writeln!(out, "  {:width$}  {}", "", s.description.as_deref().unwrap_or("(no description)"))?;
        writeln!(out, "  {:width$}  {}", "", time_line(times.as_ref(), name))?;
    }
    match &times {
        Some(t) => writeln!(
            out,
            "render times: {}; {}, {}, {}; revision {}, {}{} (from assets/scene-times.toml, written by scripts/scene-times)",
            t.command,
            t.machine,
            t.device,
            t.driver,
            t.revision,
            t.date,
            t.note.as_deref().map(|n| format!("; {n}")).unwrap_or_default()
        )?,
        None => writeln!(out, "render times: not measured ({} is missing: run scripts/scene-times)", times_path().display())?,
    }
    // Written at once: a reader that stops early (`| head`) is not an error.
    match std::io::Write::write_all(&mut std::io::stdout().lock(), out.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e).context("cannot write to stdout"),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(text: &str) -> SceneTimes {
        toml::from_str(text).unwrap()
    }

    const HEADER: &str =
        "command = \"c\"\nmachine = \"m\"\ndevice = \"d\"\ndriver = \"v\"\nrevision = \"r\"\ndate = \"t\"\n";

    #[test]
    fn a_scene_without_an_entry_is_not_measured() {
        let t = times(&format!(
            "{HEADER}[scene.a]\nseconds = 2.25\nframe_ms = 80.4\n[scene.b]\nnot_measured = \"over 180 s\"\n"
        ));
        assert_eq!(time_line(Some(&t), "a"), "render 2.2 s (GPU frame 80 ms)");
        assert_eq!(time_line(Some(&t), "b"), "render time not measured (over 180 s)");
        assert_eq!(time_line(Some(&t), "c"), "render time not measured");
        assert_eq!(time_line(None, "a"), "render time not measured");
    }

    #[test]
    fn a_bad_times_file_is_an_error_naming_it_and_the_key() {
        let dir = std::env::temp_dir().join(format!("prism-scene-times-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scene-times.toml");
        std::fs::write(&path, format!("{HEADER}[scene.a]\nsecond = 2\n")).unwrap();
        let e = format!("{:#}", read_times(&path).unwrap_err());
        assert!(e.contains("scene-times.toml") && e.contains("second") && e.contains("scripts/scene-times"), "{e}");
        assert!(read_times(&dir.join("missing.toml")).unwrap().is_none());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
