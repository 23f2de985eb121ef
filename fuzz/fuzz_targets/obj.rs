//! The OBJ loader (tobj behind prism's line-by-line checks), given the file's bytes as
//! a scene's `file = "..."` would read them: text that is not UTF-8 is refused there.
//! A mesh that loads keeps the promises of `Mesh`: indices in range, finite positions,
//! one finite unit normal per position.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(m) = prism::scene::parse_obj(text) else {
        return;
    };
    assert!(!m.indices.is_empty() && m.indices.len() % 3 == 0);
    assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
    assert_eq!(m.normals.len(), m.positions.len());
    assert!(m.positions.iter().all(|p| p.is_finite()));
    for n in &m.normals {
        assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-3, "normal {n}");
    }
});
