//! Golden images of the baseline passes at 128^2 (metric and threshold: see
//! tests/common/mod.rs, `assert_golden`). sphere_env exercises the refraction baseline and
//! the environment, sphere_nearby shadows from a point light's cube map and the checker,
//! room_mirror the reflection baseline and walls lit by a point light, metal_ring the
//! directional light's orthographic shadow map.
mod common;

use common::*;

const GOLDEN_SIZE: u32 = 128;

#[test]
fn golden_sphere_env() {
    if !common::in_own_process() {
        return;
    }
    assert_golden("sphere_env", &render(&scene("sphere_env", GOLDEN_SIZE, &[])));
}

#[test]
fn golden_sphere_nearby() {
    if !common::in_own_process() {
        return;
    }
    assert_golden("sphere_nearby", &render(&scene("sphere_nearby", GOLDEN_SIZE, &[])));
}

#[test]
fn golden_room_mirror() {
    if !common::in_own_process() {
        return;
    }
    assert_golden("room_mirror", &render(&scene("room_mirror", GOLDEN_SIZE, &[])));
}

#[test]
fn golden_metal_ring() {
    if !common::in_own_process() {
        return;
    }
    assert_golden("metal_ring", &render(&scene("metal_ring", GOLDEN_SIZE, &[])));
}

/// The threshold is tight enough to see a small change: the ball's ior 1.5 -> 1.45 must
/// fail the sphere_env comparison, and so must a shadow map that no longer shadows.
#[test]
fn golden_comparison_detects_small_changes() {
    if !common::in_own_process() {
        return;
    }
    if !golden_dir().join("sphere_env.png").exists() {
        return; // written by golden_sphere_env on first run
    }
    let (differing, psnr) =
        golden_difference("sphere_env", &render(&scene("sphere_env", GOLDEN_SIZE, &["materials.glass.ior=1.45"])));
    eprintln!("ior 1.45 vs 1.5: {:.2}% of pixels differ, PSNR {psnr:.1} dB", differing * 100.0);
    assert!(differing > MAX_DIFFERING || psnr < MIN_PSNR, "ior 1.45 passed as 1.5: {differing} {psnr}");
    if golden_dir().join("sphere_nearby.png").exists() {
        // Moving the light 0.3 m shifts every shadow edge and the shading.
        let (differing, psnr) = golden_difference(
            "sphere_nearby",
            &render(&scene("sphere_nearby", GOLDEN_SIZE, &["lights.0.position=[2.3, 5, 3]"])),
        );
        eprintln!("light moved 0.3 m: {:.2}% of pixels differ, PSNR {psnr:.1} dB", differing * 100.0);
        assert!(differing > MAX_DIFFERING || psnr < MIN_PSNR, "moved light passed: {differing} {psnr}");
    }
}
