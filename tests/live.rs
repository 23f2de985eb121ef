//! Live changes (`Renderer::update`): a running renderer that takes a changed scene renders
//! exactly what a renderer created for that scene renders, and re-creates only the
//! techniques the change affects.
mod common;

use prism::renderer::{Renderer, Update};

const SIZE: u32 = 64;

/// The linear radiance and the tone-mapped image of the next frame.
fn frame(r: &mut Renderer) -> (Vec<f32>, Vec<u8>) {
    r.render_frame().unwrap();
    (r.read_hdr().unwrap(), r.read_ldr().unwrap())
}

/// Render `scene` with `before`, update the running renderer to `after`, and require the
/// image of a renderer created for `after`, bit for bit: both record the same commands on the
/// same data, so any difference is state the update left stale. Returns what the update did.
fn live(scene: &str, before: &[&str], after: &[&str]) -> Update {
    let ctx = common::context(false);
    let mut running = Renderer::new(&ctx, &common::scene(scene, SIZE, before)).unwrap();
    frame(&mut running);
    let changed = common::scene(scene, SIZE, after);
    let update = running.update(&changed).unwrap();
    let (hdr, ldr) = frame(&mut running);
    let mut fresh = Renderer::new(&ctx, &changed).unwrap();
    let (expected_hdr, expected_ldr) = frame(&mut fresh);
    let differing = hdr.chunks(4).zip(expected_hdr.chunks(4)).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{scene} {before:?} -> {after:?}: {differing} HDR pixels differ ({update:?})");
    let differing = ldr.chunks(4).zip(expected_ldr.chunks(4)).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{scene} {before:?} -> {after:?}: {differing} LDR pixels differ ({update:?})");
    assert_eq!(running.plan(), fresh.plan());
    drop((running, fresh));
    common::assert_clean_teardown(ctx);
    update
}

#[test]
fn a_technique_parameter_re_creates_that_technique_only() {
    if !common::in_own_process() {
        return;
    }
    let u = live(
        "sphere_nearby",
        &["render.refraction=hu_qin", "render.hu_qin.search_steps=8"],
        &["render.refraction=hu_qin", "render.hu_qin.search_steps=2"],
    );
    assert_eq!(
        (u.rebuilt, u.recreated.as_slice(), u.dropped.as_slice()),
        (false, &["refraction = \"hu_qin\""][..], &[][..])
    );
    assert!(!u.materials);
}

#[test]
fn a_material_value_rewrites_the_materials_buffer_only() {
    if !common::in_own_process() {
        return;
    }
    let u = live("sphere_env", &["render.refraction=wyman"], &["render.refraction=wyman", "materials.glass.ior=1.33"]);
    assert_eq!((u.rebuilt, u.recreated.len(), u.materials), (false, 0, true), "{u:?}");
}

/// Hu & Qin's exit search assumes a back-facing exit (§4) only where every dielectric is
/// denser than air (`assume_back_facing = "auto"`): an ior taken below 1 in the window must
/// bring back §2.1.2's decision, which a rewrite of the materials buffer alone would not.
#[test]
fn an_ior_taken_below_one_brings_back_hu_qin_s_exit_decision() {
    if !common::in_own_process() {
        return;
    }
    let u =
        live("sphere_env", &["render.refraction=hu_qin"], &["render.refraction=hu_qin", "materials.glass.ior=0.75"]);
    assert!(u.rebuilt, "{u:?}");
}

#[test]
fn switching_a_technique_creates_the_new_one_and_drops_the_old() {
    if !common::in_own_process() {
        return;
    }
    let u = live("sphere_env", &["render.refraction=single"], &["render.refraction=hu_qin"]);
    assert!(!u.rebuilt, "{u:?}");
    assert_eq!(u.recreated, ["refraction = \"hu_qin\""]);
    assert_eq!(u.dropped, ["refraction = \"single\""]);
    let u = live("room_mirror", &[], &["render.reflection=impostor", "render.impostor.iterations=2"]);
    assert_eq!((u.rebuilt, u.recreated.as_slice()), (false, &["reflection = \"impostor\""][..]), "{u:?}");
}

/// The G-buffer carries Wyman's d_N on the refractors Wyman shades: choosing Wyman in the
/// window re-creates it with d_N, leaving Wyman re-creates it without, and a ball that grows
/// gets its new d_N (the live image equals a fresh renderer's, so a G-buffer left as it was
/// would show in the image).
#[test]
fn wyman_s_d_n_in_the_g_buffer_follows_the_technique_and_the_mesh() {
    if !common::in_own_process() {
        return;
    }
    let u = live("sphere_env", &["render.refraction=single"], &["render.refraction=wyman"]);
    assert_eq!((u.rebuilt, u.recreated.as_slice()), (false, &["gbuffer", "refraction = \"wyman\""][..]), "{u:?}");
    let u = live("sphere_env", &["render.refraction=wyman"], &["render.refraction=single"]);
    assert_eq!((u.rebuilt, u.recreated.as_slice()), (false, &["gbuffer", "refraction = \"single\""][..]), "{u:?}");
    let u = live("sphere_env", &["render.refraction=wyman"], &["render.refraction=wyman", "objects.0.radius=1.2"]);
    assert!(u.recreated.contains(&"gbuffer"), "{u:?}");
}

#[test]
fn the_field_of_view_and_the_exposure_are_uniforms() {
    if !common::in_own_process() {
        return;
    }
    let u = live("sphere_nearby", &[], &["camera.vfov_deg=35", "render.exposure=1.7"]);
    assert_eq!(u, Update { ms: u.ms, ..Update::default() });
    // The camera's position bounds the scene that the shadow faces are fitted to: a move.
    let u = live("sphere_nearby", &[], &["camera.position=[0.3, 1.1, 3.6]"]);
    assert!(!u.rebuilt && u.moved && u.recreated == ["shadow_map"], "{u:?}");
}

#[test]
fn the_adaptive_tone_map_is_re_created_with_its_settings() {
    if !common::in_own_process() {
        return;
    }
    let u = live(
        "caustic_sphere",
        &["render.tonemap=adaptive"],
        &["render.tonemap=adaptive", "render.tonemap_adaptive.key=0.3"],
    );
    assert_eq!((u.rebuilt, u.recreated.as_slice()), (false, &["tonemap"][..]), "{u:?}");
}

#[test]
fn topology_re_creates_the_renderer() {
    if !common::in_own_process() {
        return;
    }
    let u = live("sphere_env", &[], &["render.sphere_segments=24"]);
    assert!(u.rebuilt, "{u:?}");
    let u = live("sphere_nearby", &[], &["objects.3.material=\"bunny\""]);
    assert!(u.rebuilt, "{u:?}");
}

#[test]
fn switching_the_caustics_rebinds_their_textures_without_a_rebuild() {
    if !common::in_own_process() {
        return;
    }
    for (from, to) in [("none", "caustics_map"), ("caustics_map", "photon_buffer"), ("photon_buffer", "none")] {
        let u = live("caustic_sphere", &[&format!("render.caustics={from}")], &[&format!("render.caustics={to}")]);
        assert!(!u.rebuilt, "{from} -> {to}: {u:?}");
        assert!(u.recreated.contains(&"deferred_shading"), "{from} -> {to}: {u:?}");
    }
    // A new atlas size: the atlas, and the two techniques that draw into and read it.
    let u = live(
        "caustic_sphere",
        &["render.caustics=caustics_map"],
        &["render.caustics=caustics_map", "render.caustics_map.map_size=128"],
    );
    assert_eq!((u.rebuilt, u.recreated.as_slice()), (false, &["caustics = \"caustics_map\""][..]), "{u:?}");
    // Deferred shading reads only the filter radius.
    let u = live(
        "caustic_sphere",
        &["render.caustics=caustics_map"],
        &["render.caustics=caustics_map", "render.caustics_map.filter=2"],
    );
    assert_eq!(u.recreated, ["caustics = \"caustics_map\"", "deferred_shading"], "{u:?}");
}

#[test]
fn moving_an_object_or_a_light_updates_everything_built_from_positions() {
    if !common::in_own_process() {
        return;
    }
    // Hu & Qin §2.2's impostor rectangles and textures, caustics mapping's light frusta and
    // Hu & Qin §3's photon rectangles are built from where the objects are: after a move the
    // running renderer draws what a renderer created for the new positions draws.
    let hu_qin = ["render.refraction=hu_qin"];
    let u = live("sphere_nearby", &hu_qin, &["render.refraction=hu_qin", "objects.3.center=[0.4, 0.1, 0.3]"]);
    assert!(!u.rebuilt && u.moved, "{u:?}");
    assert!(u.recreated.contains(&"refraction = \"hu_qin\"") && u.recreated.contains(&"shadow_map"), "{u:?}");
    assert!(!u.recreated.contains(&"gbuffer") && !u.recreated.contains(&"deferred_shading"), "{u:?}");
    for caustics in ["render.caustics=caustics_map", "render.caustics=photon_buffer"] {
        let u = live("caustic_sphere", &[caustics], &[caustics, "objects.1.center=[0.3, 1.0, -0.2]"]);
        assert!(!u.rebuilt && u.moved, "{caustics}: {u:?}");
        let u = live("caustic_sphere", &[caustics], &[caustics, "lights.0.position=[0.5, 4.5, 0.2]"]);
        assert!(!u.rebuilt && u.moved, "{caustics}, light: {u:?}");
    }
    // The water's heightfield over time: same topology, new vertices.
    let u = live("water_pool", &[], &["objects.5.time=0.7"]);
    assert!(!u.rebuilt && u.moved, "{u:?}");
}

#[test]
fn a_resize_makes_new_targets_and_keeps_the_scene() {
    if !common::in_own_process() {
        return;
    }
    for scene in ["sphere_nearby", "caustic_sphere"] {
        let u = live(scene, &["render.caustics=caustics_map"], &["render.caustics=caustics_map", "camera.width=48"]);
        assert!(!u.rebuilt && u.resized, "{scene}: {u:?}");
        // The light-space techniques draw into the atlases, which keep their size: kept.
        // The techniques at the image's size are made on the new targets.
        for kept in ["shadow_map", "caustics = \"caustics_map\""] {
            assert!(!u.recreated.contains(&kept), "{scene}: {kept} re-created by a resize: {u:?}");
        }
        for made in ["gbuffer", "deferred_shading", "tonemap"] {
            assert!(u.recreated.contains(&made), "{scene}: {made} not re-created by a resize: {u:?}");
        }
        // Around the new targets with the pipelines they had: no pipeline depends on the
        // image's size (its viewport and scissor are dynamic state).
        assert!(u.pipelines.made == 0 && u.pipelines.reused > 0, "{scene}: pipelines made by a resize: {u:?}");
    }
}

#[test]
fn the_eikonal_light_simulation_survives_a_resize_and_moves_elsewhere() {
    if !common::in_own_process() {
        return;
    }
    // The simulation depends on the volume, the lights, its settings and the voxels whose
    // light is read; a resize, a floor moved within its own plane (the same voxels read) or
    // a setting of the view renderer alone (what exit rays meet) re-creates the technique
    // around it, not the simulation.
    let ctx = common::context(false);
    let base = ["volume.resolution=[16,16,16]"];
    let mut running = Renderer::new(&ctx, &common::scene("eikonal_sphere", SIZE, &base)).unwrap();
    frame(&mut running);
    let seconds = running.light_stats().unwrap().seconds;
    let mut after = base.to_vec();
    for change in
        ["camera.width=48", "camera.height=40", "objects.0.center=[0.2, 0, 0.1]", "render.eikonal.nearby=\"impostor\""]
    {
        after.push(change);
        let u = running.update(&common::scene("eikonal_sphere", SIZE, &after)).unwrap();
        assert!(!u.rebuilt && u.recreated.contains(&"[volume]"), "{change}: {u:?}");
        // The very same statistics: the simulation was not run again.
        assert_eq!(running.light_stats().unwrap().seconds, seconds, "{change}: simulated again");
    }
    // And the image is the fresh renderer's, up to the simulation's run-to-run noise: its
    // deposits are float atomics summed in a different order each run (measured: 1.9e-6 at
    // most on this scene, against radiance of order 1).
    let scene = common::scene("eikonal_sphere", SIZE, &after);
    let (hdr, _) = frame(&mut running);
    let mut fresh = Renderer::new(&ctx, &scene).unwrap();
    let (expected, _) = frame(&mut fresh);
    let worst = hdr.iter().zip(&expected).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
    assert!(worst <= 1e-4, "largest difference {worst}");
    drop((running, fresh));
    common::assert_clean_teardown(ctx);
}

/// The other side of the cache key: a change of any setting the light simulation depends on
/// runs it again (a key without one of them would keep the old light under the new setting).
#[test]
fn every_setting_of_the_light_simulation_runs_it_again() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut after = vec!["volume.resolution=[16,16,16]"];
    let mut running = Renderer::new(&ctx, &common::scene("eikonal_sphere", SIZE, &after)).unwrap();
    frame(&mut running);
    let mut seconds = running.light_stats().unwrap().seconds;
    for change in [
        // The floor moved up by most of a voxel (0.13 m at 16^3): its light is read from other
        // voxels (render.eikonal.light_deposits = "read").
        "objects.0.center=[0, 0.1, 0]",
        "render.eikonal.light_deposits=\"everywhere\"",
        "render.eikonal.skip_air=false",
        "render.eikonal.keep_crossed=false",
        "render.eikonal.light_dt=1.0",
        "render.eikonal.light_integrator=\"euler\"",
        "render.eikonal.light_substeps=2",
        "render.eikonal.energy_threshold=0.001",
        "render.eikonal.float_atomics=false",
        "render.eikonal.sigma=0.5",
        "render.eikonal.voxelization=\"highest_energy\"",
        "render.eikonal.light_fresnel=true",
        "render.eikonal.hardware_filtering=\"false\"",
    ] {
        after.push(change);
        running.update(&common::scene("eikonal_sphere", SIZE, &after)).unwrap();
        frame(&mut running);
        let now = running.light_stats().unwrap().seconds;
        assert_ne!(now, seconds, "{change}: the light simulation was not run again");
        seconds = now;
    }
    drop(running);
    common::assert_clean_teardown(ctx);
}

#[test]
fn the_water_animates_on_the_gpu() {
    if !common::in_own_process() {
        return;
    }
    // The window moves the water's vertices with a compute pass instead of a scene update.
    // Against a renderer created at the new time the image may differ only as much as the
    // golden threshold allows (tests/common/mod.rs): the GPU's sin rounds differently from
    // the CPU's, and the shadow faces stay fitted to the loaded time's bounds.
    use prism::metrics::image::{fraction_differing_rgba8, psnr_rgba8};
    let ctx = common::context(false);
    let mut running = Renderer::new(&ctx, &common::scene("water_pool", SIZE, &[])).unwrap();
    let (_, still) = frame(&mut running);
    assert!(running.animate(0.7));
    let (hdr, animated) = frame(&mut running);
    common::assert_finite("water_pool animated", &hdr);
    let later = common::scene("water_pool", SIZE, &["objects.5.time=0.7"]);
    let (_, expected) = frame(&mut Renderer::new(&ctx, &later).unwrap());
    let (differing, psnr) = (fraction_differing_rgba8(&animated, &expected, 8), psnr_rgba8(&animated, &expected));
    assert!(differing <= common::MAX_DIFFERING && psnr >= common::MIN_PSNR, "{differing} {psnr}");
    // The waves moved far more than that: the comparison can fail.
    let moved = fraction_differing_rgba8(&still, &expected, 8);
    assert!(moved > common::MAX_DIFFERING, "time 0 and 0.7 differ in only {moved} of the pixels");
    // An update to the new time puts everything where a created renderer has it.
    let u = running.update(&later).unwrap();
    assert!(u.moved && !running.animated(), "{u:?}");
    assert_eq!(frame(&mut running).1, expected);
    drop(running);
    common::assert_clean_teardown(ctx);
}

#[test]
fn exact_ray_tracing_follows_a_moved_light_and_a_material_value() {
    if !common::in_own_process() {
        return;
    }
    let rt = "render.refraction=raytrace";
    let u = live("sphere_nearby", &[rt], &[rt, "lights.0.position=[-2, 4, 3]"]);
    assert!(u.recreated.contains(&"refraction = \"raytrace\""), "{u:?}");
    let u = live("sphere_nearby", &[rt], &[rt, "materials.glass.ior=1.33"]);
    assert_eq!((u.rebuilt, u.recreated.len(), u.materials), (false, 0, true), "{u:?}");
}

/// What techniques keep from frame to frame (`render.update = "on_change"`) follows what it
/// shows when that changes in place: a material value. Hu & Qin's textures TEX_i hold
/// sphere_nearby's bunny as the ball refracts it; room_mirror's distance impostor
/// (Szirmay-Kalos et al. 2005 §6, regenerated only on large moves) holds the white walls the
/// mirror ball reflects; the three caustic techniques' maps hold caustic_sphere's caustic,
/// which the ball's index moves. No technique is re-created by the change.
#[test]
fn kept_results_follow_a_material_value() {
    if !common::in_own_process() {
        return;
    }
    let hq = "render.refraction=hu_qin";
    let u = live("sphere_nearby", &[hq], &[hq, "materials.bunny.albedo=[0.2, 0.6, 0.9]"]);
    assert_eq!((u.rebuilt, u.recreated.len(), u.materials), (false, 0, true), "{u:?}");
    let im = "render.reflection=impostor";
    let u = live("room_mirror", &[im], &[im, "materials.white.albedo=0.3"]);
    assert_eq!((u.rebuilt, u.recreated.len(), u.materials), (false, 0, true), "{u:?}");
    for caustics in ["caustics_map", "photon_buffer", "impostor_lightmap"] {
        let c = format!("render.caustics={caustics}");
        let u = live("caustic_sphere", &[&c], &[&c, "materials.glass.ior=1.33"]);
        assert_eq!((u.rebuilt, u.recreated.len(), u.materials), (false, 0, true), "{caustics}: {u:?}");
    }
}

/// The photon buffer's texel sums keep one channel while every photon is grey
/// (`merge_texels`): a material value that colours the photons, the glass's absorption,
/// re-creates the technique with three, and the image is that of a renderer made for it.
#[test]
fn colouring_the_photons_re_creates_the_photon_buffer() {
    if !common::in_own_process() {
        return;
    }
    let c = "render.caustics=photon_buffer";
    let u = live("caustic_sphere", &[c], &[c, "materials.glass.absorption=[0.5, 2.0, 4.0]"]);
    assert_eq!((u.rebuilt, u.recreated.as_slice()), (false, &["caustics = \"photon_buffer\""][..]), "{u:?}");
}
