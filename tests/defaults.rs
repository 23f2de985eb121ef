//! The bundled scenes' own techniques (the `[render]` table of each file) render them closer
//! to the exact reference than the baseline techniques (`prism::scene::BASELINE`): rendered
//! with no `--set`, each scene shows its paper's effect.
mod common;

use prism::metrics::image::rmse_rgba;
use prism::reference::{Reference, ReferenceSettings};

/// Small enough for the suite (two references and two renders per scene at 64^2), large
/// enough that the ball, the mirror and the water cover hundreds of pixels.
const SIZE: u32 = 64;

#[test]
fn shipped_techniques_beat_the_baseline_against_the_reference() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut names = vec![prism::scene::DEFAULT_SCENE, "caustic_sphere", "room_mirror", "water_pool"];
    names.dedup();
    // Each reference and renderer is built beside the previous one, whose pipelines it shares
    // (common::render_after).
    let (mut last_reference, mut last_renderer) = (None, None);
    for name in names {
        let shipped = common::shipped(name, SIZE, &[]);
        let baseline = common::scene(name, SIZE, &[]);
        let mut reference = |seed| {
            let settings = ReferenceSettings { spp: 16, photons: 1 << 19, seed, ..Default::default() };
            let mut r = Reference::new(&ctx, &shipped, &settings).unwrap();
            r.run_all(|_, _| {}).unwrap();
            let image = r.image();
            last_reference = Some(r);
            image
        };
        let (a, b) = (reference(1), reference(2));
        // The margin is the reference's own noise: the RMSE between two references of
        // different seeds, sqrt(2) times either one's (both errors are measured against the
        // same reference, so its noise adds about equally to both).
        let noise = rmse_rgba(&a, &b);
        let shipped_error = rmse_rgba(&common::render_after(&ctx, &shipped, &mut last_renderer).hdr, &a);
        let baseline_error = rmse_rgba(&common::render_after(&ctx, &baseline, &mut last_renderer).hdr, &a);
        let r = &shipped.render;
        eprintln!(
            "{name} at {SIZE}^2: refraction {}, reflection {}, caustics {}: RMSE {shipped_error:.4}; \
             baseline {baseline_error:.4}; reference noise {noise:.4}",
            r.refraction, r.reflection, r.caustics
        );
        assert!(
            shipped_error + noise < baseline_error,
            "{name}: the scene's techniques (RMSE {shipped_error}) are not better than the baseline \
             ({baseline_error}) by the reference's noise ({noise})"
        );
    }
    drop((last_reference, last_renderer));
    common::assert_clean_teardown(ctx);
}
