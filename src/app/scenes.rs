//! `prism scenes`: the bundled scenes (assets/scenes/*.toml), each with its description and
//! the techniques it selects, read from the files themselves.
use anyhow::{Context, Result};

use crate::scene;

pub fn run() -> Result<()> {
    let names = scene::bundled_scenes().context("cannot list assets/scenes/")?;
    println!("bundled scenes ({}; `prism render NAME` renders one):", scene::assets_dir().join("scenes").display());
    let width = names.iter().map(|n| n.len()).max().unwrap_or(0);
    for name in &names {
        let s = scene::load(&scene::benchmark_scene_path(name), &[])?;
        let r = &s.render;
        println!("  {name:width$}  refraction {}, reflection {}, caustics {}", r.refraction, r.reflection, r.caustics);
        println!("  {:width$}  {}", "", s.description.as_deref().unwrap_or("(no description)"));
    }
    Ok(())
}
