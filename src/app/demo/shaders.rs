//! Shader hot reload: the window watches a GLSL tree (the source tree's `glsl/`, or
//! `--shaders DIR`), and recompiles what changed with the same shaderc/glslang as build.rs.
//! Which pipelines a shader affects is the renderer's business (`Renderer::reload_shaders`).
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

/// How often the tree's modification times are read.
const POLL: Duration = Duration::from_millis(250);

pub struct ShaderWatch {
    dir: PathBuf,
    mtimes: HashMap<PathBuf, SystemTime>,
    last_poll: Instant,
}

fn is_stage(p: &Path) -> bool {
    matches!(p.extension().and_then(|e| e.to_str()), Some("vert" | "frag" | "comp" | "geom"))
}

fn scan(dir: &Path, out: &mut HashMap<PathBuf, SystemTime>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            scan(&p, out);
        } else if is_stage(&p) || p.extension().is_some_and(|e| e == "glsl") {
            if let Ok(t) = e.metadata().and_then(|m| m.modified()) {
                out.insert(p, t);
            }
        }
    }
}

impl ShaderWatch {
    pub fn new(dir: PathBuf) -> ShaderWatch {
        let mut mtimes = HashMap::new();
        scan(&dir, &mut mtimes);
        ShaderWatch { dir, mtimes, last_poll: Instant::now() }
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The shaders (paths relative to the tree, as the pipelines name them) to recompile
    /// because a file changed since the last poll: a changed stage file itself, and every
    /// stage file that includes a changed `.glsl`, directly or through other includes.
    pub fn poll(&mut self) -> Vec<String> {
        if self.last_poll.elapsed() < POLL {
            return Vec::new();
        }
        self.last_poll = Instant::now();
        let mut now = HashMap::new();
        scan(&self.dir, &mut now);
        let changed: Vec<PathBuf> =
            now.iter().filter(|(p, t)| self.mtimes.get(*p) != Some(t)).map(|(p, _)| p.clone()).collect();
        self.mtimes = now;
        if changed.is_empty() {
            return Vec::new();
        }
        // Include names reached from the changed headers, to a fixed point.
        let mut headers: Vec<String> = changed
            .iter()
            .filter(|p| !is_stage(p))
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        let sources: Vec<(PathBuf, String)> =
            self.mtimes.keys().filter_map(|p| Some((p.clone(), std::fs::read_to_string(p).ok()?))).collect();
        let includes = |text: &str, name: &str| text.contains(&format!("#include \"{name}\""));
        loop {
            let more: Vec<String> = sources
                .iter()
                .filter(|(p, text)| !is_stage(p) && headers.iter().any(|h| includes(text, h)))
                .filter_map(|(p, _)| p.file_name().map(|n| n.to_string_lossy().into_owned()))
                .filter(|n| !headers.contains(n))
                .collect();
            if more.is_empty() {
                break;
            }
            headers.extend(more);
        }
        let mut stages: Vec<String> = sources
            .iter()
            .filter(|(p, text)| is_stage(p) && (changed.contains(p) || headers.iter().any(|h| includes(text, h))))
            .filter_map(|(p, _)| p.strip_prefix(&self.dir).ok().map(|r| r.to_string_lossy().replace('\\', "/")))
            .collect();
        stages.sort();
        stages
    }
}
