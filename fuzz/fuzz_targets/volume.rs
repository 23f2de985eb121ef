//! The volume sources: a scene file whose `[volume]` and `[[volume.region]]`s are loaded
//! and then evaluated at every voxel centre (`Volume::fields`, the CPU rasterization of
//! implicit shapes, lathes and meshes). Every field must be finite.
#![no_main]

use libfuzzer_sys::fuzz_target;

/// Volumes with more voxels are loaded but not evaluated: the cost is voxels x regions,
/// legitimately seconds at 256^3, which libFuzzer would report as a hang.
const MAX_EVALUATED_VOXELS: usize = 32 * 32 * 32;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let origin = prism::scene::assets_dir().join("scenes").join("fuzz.toml");
    let Ok(scene) = prism::scene::load_str(text, &origin, &[]) else {
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
});
