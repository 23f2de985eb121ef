//! The bodies of the loader fuzz targets, one input each. cargo-fuzz runs them under
//! libFuzzer (fuzz/fuzz_targets/, scripts/fuzz: millions of coverage-guided executions by
//! hand); tests/fuzz_replay.rs runs them on stable Rust over the seeds and a fixed number
//! of seeded random mutations (every CI run). A body returns when its input is refused
//! with an error and panics when a loader panics or breaks a promise the renderer relies
//! on.

use std::sync::atomic::Ordering;

/// The scene's tessellated-triangle budget while fuzzing: 2^16 triangles tessellate in
/// milliseconds, so that a large but valid scene is not reported as a hang.
pub const TESSELLATED_TRIANGLES: u64 = 1 << 16;

/// Volumes with more voxels are loaded but not evaluated: the cost is voxels x regions,
/// legitimately seconds at 256^3, which a fuzzer would report as a hang.
pub const MAX_EVALUATED_VOXELS: usize = 32 * 32 * 32;

fn fuzzing() {
    super::TESSELLATION_BUDGET.store(TESSELLATED_TRIANGLES, Ordering::Relaxed);
}

/// The file every fuzzed scene stands for: in assets/scenes/, so that the bundled scenes'
/// relative mesh paths resolve.
fn origin() -> std::path::PathBuf {
    super::assets_dir().join("scenes").join("fuzz.toml")
}

/// The scene file with its `--set` overrides: the TOML text, then up to four override
/// strings, each after a NUL byte. Loading returns a scene or a `SceneError`; a scene's
/// meshes keep `Mesh`'s promises (one normal per position, indices in range, finite
/// positions).
pub fn scene(data: &[u8]) {
    fuzzing();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let mut parts = text.split('\0');
    let toml = parts.next().unwrap_or_default();
    let overrides: Vec<String> = parts.take(4).map(str::to_string).collect();
    if let Ok(scene) = super::load_str(toml, &origin(), &overrides) {
        for o in &scene.objects {
            let m = &o.mesh;
            assert_eq!(m.normals.len(), m.positions.len());
            assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
            assert!(m.positions.iter().all(|p| p.is_finite()));
        }
    }
}

/// The OBJ loader (tobj behind prism's line-by-line checks), given the file's bytes as a
/// scene's `file = "..."` would read them: text that is not UTF-8 is refused there. A mesh
/// that loads has whole triangles, indices in range, finite positions and one finite unit
/// normal per position.
pub fn obj(data: &[u8]) {
    fuzzing();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(m) = super::parse_obj(text) else {
        return;
    };
    assert!(!m.indices.is_empty() && m.indices.len() % 3 == 0);
    assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
    assert_eq!(m.normals.len(), m.positions.len());
    assert!(m.positions.iter().all(|p| p.is_finite()));
    for n in &m.normals {
        assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-3, "normal {n}");
    }
}

/// The volume sources: a scene file whose `[volume]` and `[[volume.region]]`s are loaded
/// and then evaluated at every voxel centre (`Volume::fields`, the CPU rasterization of
/// implicit shapes, lathes and meshes) when there are at most [`MAX_EVALUATED_VOXELS`].
/// Every field is finite.
pub fn volume(data: &[u8]) {
    fuzzing();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(scene) = super::load_str(text, &origin(), &[]) else {
        return;
    };
    let Some(volume) = scene.volume else {
        return;
    };
    if volume.resolution.iter().map(|&n| n as usize).product::<usize>() > MAX_EVALUATED_VOXELS {
        return;
    }
    let f = volume.fields();
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
    let finite4 = |v: &[[f32; 4]]| v.iter().flatten().all(|x| x.is_finite());
    assert!(f.index.iter().all(|c| finite(c)), "index");
    assert!(finite4(&f.extinction) && finite4(&f.albedo) && finite4(&f.emission), "extinction, albedo, emission");
    assert!(f.coverage.iter().all(|c| finite(c)), "coverage");
}
