//! The scene file with its `--set` overrides: the input is the TOML text, then up to
//! four override strings, each after a NUL byte. Loading must return a scene or a
//! `SceneError`, never panic, whatever the bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let mut parts = text.split('\0');
    let toml = parts.next().unwrap_or_default();
    let overrides: Vec<String> = parts.take(4).map(str::to_string).collect();
    // In assets/scenes/, so the bundled scenes' relative mesh paths resolve.
    let origin = prism::scene::assets_dir().join("scenes").join("fuzz.toml");
    if let Ok(scene) = prism::scene::load_str(toml, &origin, &overrides) {
        // The promises the renderer relies on (src/scene/mesh.rs, Mesh).
        for o in &scene.objects {
            let m = &o.mesh;
            assert_eq!(m.normals.len(), m.positions.len());
            assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
            assert!(m.positions.iter().all(|p| p.is_finite()));
        }
    }
});
