//! The pass list is derived from the scene (model only what the scene requires), and
//! `prism passes` prints it with reasons; `prism scenes` and `prism --help` list the
//! scenes there are.
mod common;

use prism::renderer::plan::plan;

fn names(scene: &str, overrides: &[&str]) -> Vec<&'static str> {
    plan(&common::scene(scene, 64, overrides)).iter().map(|p| p.name).collect()
}

#[test]
fn pass_lists_follow_the_scene() {
    if !common::in_own_process() {
        return;
    }
    // No light: no shadow map. A refractor: the refraction baseline.
    assert_eq!(names("sphere_env", &[]), ["gbuffer", "deferred_shading", "refraction_single", "tonemap"]);
    // A point light and diffuse receivers: a shadow map first.
    assert_eq!(
        names("sphere_nearby", &[]),
        ["shadow_map", "gbuffer", "deferred_shading", "refraction_single", "tonemap"]
    );
    // A mirror and no refractor: reflection, no refraction pass.
    assert_eq!(
        names("room_mirror", &[]),
        ["shadow_map", "gbuffer", "deferred_shading", "reflection_single", "tonemap"]
    );
    assert_eq!(names("metal_ring", &[]), ["shadow_map", "gbuffer", "deferred_shading", "reflection_single", "tonemap"]);
    // room_glass: the glass ball refracts; nothing reflects only.
    assert_eq!(names("room_glass", &[]), ["shadow_map", "gbuffer", "deferred_shading", "refraction_single", "tonemap"]);
}

#[test]
fn the_adaptive_tone_map_adds_its_reduction_only_when_named() {
    if !common::in_own_process() {
        return;
    }
    // Default (clamp, SCENES.md's PNG rule): the tone map alone, on every scene.
    for scene in ["sphere_env", "caustic_sphere", "eikonal_sphere"] {
        let n = names(scene, &[]);
        assert!(!n.iter().any(|p| p.starts_with("tonemap_")), "{scene}: {n:?}");
        assert_eq!(n.last(), Some(&"tonemap"));
        assert_eq!(names(scene, &["render.tonemap=clamp"]), n);
    }
    // Adaptive (Ihrke et al. 2007 §5.3): the log-average reduction and the adaptation first.
    assert_eq!(
        names("sphere_env", &["render.tonemap=adaptive"]),
        ["gbuffer", "deferred_shading", "refraction_single", "tonemap_log_average", "tonemap_adapt", "tonemap"]
    );
}

#[test]
fn a_scene_without_refractors_records_no_refraction_pass() {
    if !common::in_own_process() {
        return;
    }
    // Turning sphere_nearby's glass into a diffuse material removes the refraction pass.
    let n = names("sphere_nearby", &["objects.3.material=\"bunny\""]);
    assert!(!n.contains(&"refraction_single"), "{n:?}");
    assert!(n.contains(&"shadow_map"));
}

#[test]
fn image_space_refraction_replaces_the_baseline() {
    if !common::in_own_process() {
        return;
    }
    assert_eq!(
        names("sphere_env", &["render.refraction=wyman"]),
        ["gbuffer", "deferred_shading", "refraction_wyman_layers", "refraction_wyman", "tonemap"]
    );
    // Hu & Qin §2.2: nearby diffuse objects get impostor textures first.
    assert_eq!(
        names("sphere_nearby", &["render.refraction=hu_qin"]),
        [
            "shadow_map",
            "gbuffer",
            "deferred_shading",
            "refraction_hu_qin_nearby",
            "refraction_hu_qin_layers",
            "refraction_hu_qin",
            "tonemap"
        ]
    );
    // Switched off, or nothing to stand in for (sphere_env has no diffuse object): no pass.
    assert_eq!(
        names("sphere_nearby", &["render.refraction=hu_qin", "render.hu_qin.nearby=false"]),
        ["shadow_map", "gbuffer", "deferred_shading", "refraction_hu_qin_layers", "refraction_hu_qin", "tonemap"]
    );
    assert_eq!(
        names("sphere_env", &["render.refraction=hu_qin"]),
        ["gbuffer", "deferred_shading", "refraction_hu_qin_layers", "refraction_hu_qin", "tonemap"]
    );
    // §2.2.1 recursion: one pass per level only where a rectangle stands for a specular object
    // (two_glass_balls: each ball is a rectangle of the other's set); none for one refractor
    // among diffuse objects, whatever the depth.
    let n = names("two_glass_balls", &["render.refraction=hu_qin", "render.hu_qin.recursion_depth=2"]);
    assert!(n.contains(&"refraction_hu_qin_nearby_r2") && !n.contains(&"refraction_hu_qin_nearby_r3"), "{n:?}");
    assert!(n.contains(&"refraction_hu_qin_nearby_back"), "{n:?}");
    // The diffuse textures are rendered once and copied for the levels >= 1; not without levels.
    assert!(n.contains(&"refraction_hu_qin_nearby_copy"), "{n:?}");
    let n = names("two_glass_balls", &["render.refraction=hu_qin", "render.hu_qin.recursion_depth=0"]);
    assert!(!n.contains(&"refraction_hu_qin_nearby_copy"), "{n:?}");
    let n = names("sphere_nearby", &["render.refraction=hu_qin", "render.hu_qin.recursion_depth=3"]);
    assert!(!n.iter().any(|p| p.starts_with("refraction_hu_qin_nearby_")), "{n:?}");
    // Only hu_qin has impostor rectangles.
    assert!(!names("sphere_nearby", &["render.refraction=wyman"]).contains(&"refraction_hu_qin_nearby"));
    // Without a refractor, none of their passes.
    for t in ["wyman", "hu_qin"] {
        let n = names("sphere_nearby", &[&format!("render.refraction={t}"), "objects.3.material=\"bunny\""]);
        assert!(!n.iter().any(|p| p.starts_with("refraction")), "{t}: {n:?}");
        let n = names("room_mirror", &[&format!("render.refraction={t}")]);
        assert!(!n.iter().any(|p| p.starts_with("refraction")), "{t}: {n:?}");
    }
}

/// Caustics mapping (Shah et al. 2007) needs a light, a specular object and a diffuse
/// receiver, and `render.caustics = "caustics_map"`; its passes run after the shadow map.
#[test]
fn caustic_passes_only_with_light_specular_object_and_receiver() {
    if !common::in_own_process() {
        return;
    }
    const CAUSTIC: [&str; 4] =
        ["caustics_map_receivers", "caustics_map_refractors", "caustics_map_hits", "caustics_map"];
    let on = "render.caustics=caustics_map";
    assert_eq!(
        names("caustic_sphere", &[on]),
        [
            "shadow_map",
            "caustics_map_receivers",
            "caustics_map_refractors",
            "caustics_map_hits",
            "caustics_map",
            "gbuffer",
            "deferred_shading",
            "refraction_single",
            "tonemap"
        ]
    );
    // A mirror forms reflective caustics.
    assert!(names("metal_ring", &[on]).contains(&"caustics_map"));
    let absent = |scene: &str, o: &[&str]| {
        let n = names(scene, o);
        assert!(!n.iter().any(|p| CAUSTIC.contains(p)), "{scene} {o:?}: {n:?}");
    };
    // caustics = none (the default).
    absent("caustic_sphere", &[]);
    // No light (sphere_env), no diffuse receiver, no specular object.
    absent("sphere_env", &[on]);
    absent("caustic_sphere", &[on, "objects.0.material=\"glass\""]);
    absent("caustic_sphere", &[on, "objects.1.material=\"floor\""]);
}

/// Photon-buffer caustics (Hu & Qin 2007 §3) likewise: only with `render.caustics =
/// "photon_buffer"`, a light, a specular object and a diffuse receiver.
#[test]
fn photon_buffer_passes_only_with_light_specular_object_and_receiver() {
    if !common::in_own_process() {
        return;
    }
    const PHOTON: [&str; 5] = [
        "photon_buffer_refractors",
        "photon_buffer_receivers",
        "photon_buffer",
        "photon_buffer_bin",
        "photon_buffer_scatter",
    ];
    let on = "render.caustics=photon_buffer";
    assert_eq!(
        names("caustic_sphere", &[on]),
        [
            "shadow_map",
            "photon_buffer_refractors",
            "photon_buffer_receivers",
            "photon_buffer",
            "photon_buffer_bin",
            "photon_buffer_scatter",
            "gbuffer",
            "deferred_shading",
            "refraction_single",
            "tonemap"
        ]
    );
    assert!(names("metal_ring", &[on]).contains(&"photon_buffer"));
    // The per-texel sums only with merge_texels.
    let single = names("caustic_sphere", &[on, "render.photon_buffer.merge_texels=false"]);
    assert!(!single.contains(&"photon_buffer_bin"), "{single:?}");
    let absent = |scene: &str, o: &[&str]| {
        let n = names(scene, o);
        assert!(!n.iter().any(|p| PHOTON.contains(p)), "{scene} {o:?}: {n:?}");
    };
    absent("caustic_sphere", &[]);
    absent("caustic_sphere", &["render.caustics=caustics_map"]);
    absent("sphere_env", &[on]);
    absent("caustic_sphere", &[on, "objects.0.material=\"glass\""]);
    absent("caustic_sphere", &[on, "objects.1.material=\"floor\""]);
    // And caustics mapping's passes are not recorded with photon_buffer.
    assert!(!names("caustic_sphere", &[on]).contains(&"caustics_map"));
}

#[test]
fn impostor_lightmap_passes_only_with_light_specular_object_and_quad_receiver() {
    if !common::in_own_process() {
        return;
    }
    let on = "render.caustics=impostor_lightmap";
    assert_eq!(
        names("caustic_sphere", &[on]),
        [
            "shadow_map",
            "impostor_lightmap_uv_map",
            "impostor_lightmap_refractor_map",
            "impostor_lightmap_caustic_surfaces",
            "impostor_lightmap_caustic_map",
            "impostor_lightmap_splat",
            "gbuffer",
            "deferred_shading",
            "impostor_lightmap_apply",
            "refraction_single",
            "tonemap"
        ]
    );
    // A mirror needs no refractor map.
    let ring = names("metal_ring", &[on]);
    assert!(ring.contains(&"impostor_lightmap_splat") && !ring.contains(&"impostor_lightmap_refractor_map"));
    let absent = |scene: &str, o: &[&str]| {
        let n = names(scene, o);
        assert!(!n.iter().any(|p| p.starts_with("impostor_lightmap")), "{scene} {o:?}: {n:?}");
    };
    absent("caustic_sphere", &[]);
    // No light, no specular object, no quad receiver (the floor made glass).
    absent("sphere_env", &[on]);
    absent("caustic_sphere", &[on, "objects.1.material=\"floor\""]);
    absent("caustic_sphere", &[on, "objects.0.material=\"glass\""]);
}

#[test]
fn distance_impostors_replace_the_baselines() {
    if !common::in_own_process() {
        return;
    }
    assert_eq!(
        names("room_mirror", &["render.reflection=impostor"]),
        ["shadow_map", "gbuffer", "deferred_shading", "reflection_impostor_map", "reflection_impostor", "tonemap"]
    );
    assert_eq!(
        names("room_glass", &["render.refraction=impostor"]),
        [
            "shadow_map",
            "gbuffer",
            "deferred_shading",
            "refraction_impostor_map",
            "refraction_impostor_refractor_map",
            "refraction_impostor",
            "tonemap"
        ]
    );
    // A scene without mirrors or conductors records no reflection impostor pass, one without
    // refractors no refraction impostor pass.
    let n = names("room_glass", &["render.reflection=impostor"]);
    assert!(!n.iter().any(|p| p.starts_with("reflection")), "{n:?}");
    let n = names("room_mirror", &["render.refraction=impostor"]);
    assert!(!n.iter().any(|p| p.starts_with("refraction")), "{n:?}");
    let n = names("room_mirror", &["render.reflection=impostor", "objects.6.material=\"white\""]);
    assert!(!n.iter().any(|p| p.contains("impostor")), "{n:?}");
}

#[test]
fn renderer_records_exactly_the_planned_passes() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    for (name, o) in [
        ("sphere_env", ""),
        ("sphere_nearby", ""),
        ("metal_ring", ""),
        ("sphere_env", "render.refraction=wyman"),
        ("sphere_nearby", "render.refraction=hu_qin"),
        ("room_mirror", "render.reflection=impostor"),
        ("room_glass", "render.refraction=impostor"),
        ("caustic_sphere", "render.caustics=caustics_map"),
        ("metal_ring", "render.caustics=caustics_map"),
        ("caustic_sphere", "render.tonemap=adaptive"),
    ] {
        let o: Vec<&str> = [o].into_iter().filter(|o| !o.is_empty()).collect();
        let s = common::scene(name, 32, &o);
        let mut r = prism::renderer::Renderer::new(&ctx, &s).unwrap();
        r.render_frame().unwrap();
        r.finish().unwrap();
        let t = r.take_timings();
        let recorded: Vec<_> = t[0].passes.iter().map(|p| p.name.as_str()).collect();
        let planned: Vec<_> = plan(&s).iter().map(|p| p.name).collect();
        assert_eq!(recorded, planned, "{name}");
    }
    common::assert_no_validation_errors(&ctx);
}

#[test]
fn prism_passes_prints_the_passes_and_why() {
    if !common::in_own_process() {
        return;
    }
    let out =
        std::process::Command::new(env!("CARGO_BIN_EXE_prism")).args(["passes", "sphere_nearby"]).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("shadow_map") && text.contains("light 0 (point at (2, 5, 3))"), "{text}");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_prism"))
        .args(["passes", "sphere_env", "--json"])
        .args(common::baseline_args())
        .output()
        .unwrap();
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let names: Vec<_> = json.as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_string()).collect();
    assert_eq!(names, ["gbuffer", "deferred_shading", "refraction_single", "tonemap"]);
}

/// The scene files in assets/scenes/, listed here independently of the library.
fn scene_files() -> Vec<String> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes");
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.unwrap().file_name().to_str()?.strip_suffix(".toml").map(str::to_string))
        .collect();
    names.sort();
    names
}

#[test]
fn prism_scenes_lists_every_bundled_scene_with_its_description_techniques_and_render_time() {
    if !common::in_own_process() {
        return;
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_prism")).arg("scenes").output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    // Each scene is a line "  NAME  refraction R, reflection R, caustics C", then its
    // description, then its render time from assets/scene-times.toml; a last line names the
    // machine those times are from.
    let lines: Vec<&str> = text.lines().skip(1).collect();
    let (footer, lines) = lines.split_last().unwrap();
    assert!(footer.starts_with("render times: ") && footer.contains("scripts/scene-times"), "{text}");
    let listed: Vec<&str> = lines.iter().step_by(3).map(|l| l.split_whitespace().next().unwrap()).collect();
    assert_eq!(listed, scene_files(), "{text}");
    let times: toml::Value = toml::from_str(
        &std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scene-times.toml")).unwrap(),
    )
    .unwrap();
    for pair in lines.chunks(3) {
        let name = pair[0].split_whitespace().next().unwrap();
        // Every scene has an entry: its time, or why it was not measured.
        let entry = times["scene"]
            .get(name)
            .unwrap_or_else(|| panic!("assets/scene-times.toml has no entry for {name}: run scripts/scene-times"));
        match entry.get("seconds") {
            Some(s) => assert!(pair[2].trim().starts_with(&format!("render {:.1} s", s.as_float().unwrap())), "{text}"),
            None => assert!(pair[2].trim().starts_with("render time not measured ("), "{name}: {entry:?}\n{text}"),
        }
        let s = common::shipped(name, 64, &[]);
        let techniques = format!(
            "refraction {}, reflection {}, caustics {}",
            s.render.refraction, s.render.reflection, s.render.caustics
        );
        assert!(pair[0].ends_with(&techniques), "{}", pair[0]);
        assert_eq!(pair[1].trim(), s.description.unwrap(), "{text}");
    }
}

#[test]
fn prism_help_names_every_bundled_scene() {
    if !common::in_own_process() {
        return;
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_prism")).arg("--help").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(&scene_files().join(", ")), "{text}");
    assert!(!text.contains("(later)"), "{text}");
}

/// The README's `cargo run --release -- ARGS` commands (the gallery's and the sweep's too),
/// run as `prism ARGS` in a scratch directory with the validation layer on, so that what the
/// README shows keeps working. `demo` needs a window: tests/demo.rs runs those under Xvfb.
/// `./x render` and `./x test` are what .ci/run runs.
#[test]
fn readme_commands_run() {
    if !common::in_own_process() {
        return;
    }
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let dir = std::env::temp_dir().join(format!("prism-readme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut ran = 0;
    for line in readme.lines() {
        let Some(command) = line.strip_prefix("cargo run --release -- ") else { continue };
        let args: Vec<&str> = command.split('#').next().unwrap().split_whitespace().collect();
        if args[0] == "demo" {
            continue;
        }
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_prism"))
            .args(&args)
            .current_dir(&dir)
            .env("PRISM_VALIDATION", "1")
            .env("PRISM_CACHE_DIR", dir.join("cache"))
            .output()
            .unwrap();
        assert!(out.status.success(), "prism {command}:\n{}", String::from_utf8_lossy(&out.stderr));
        ran += 1;
    }
    assert!(ran >= 6, "the README's commands were not found");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Eikonal rendering (Ihrke et al. 2007): its view pass runs only when the scene has a
/// `[volume]`, after the surface techniques and before the tone map.
#[test]
fn eikonal_passes_only_with_a_volume() {
    if !common::in_own_process() {
        return;
    }
    assert_eq!(names("eikonal_luneburg", &[]), ["gbuffer", "deferred_shading", "eikonal_view", "tonemap"]);
    // eikonal_sphere has a light: the light simulation's receiver pass follows
    // deferred shading; without the light, or with render.eikonal.light = false, it is gone.
    let lit = ["shadow_map", "gbuffer", "deferred_shading", "eikonal_light", "eikonal_view", "tonemap"];
    assert_eq!(names("eikonal_sphere", &[]), lit);
    let off = ["shadow_map", "gbuffer", "deferred_shading", "eikonal_view", "tonemap"];
    assert_eq!(names("eikonal_sphere", &["render.eikonal.light=false"]), off);
    let mut unlit = common::scene("eikonal_sphere", 64, &[]);
    unlit.lights.clear();
    assert!(!plan(&unlit).iter().any(|p| p.name == "eikonal_light"));
    // Two lights: one eikonal_light pass (every light is simulated into the same volumes),
    // whose reason names both.
    let mut two = common::scene("eikonal_sphere", 64, &[]);
    two.lights.push(prism::scene::Light::Directional {
        direction: glam::Vec3::new(0.3, -1.0, 0.0).normalize(),
        irradiance: glam::Vec3::ONE,
    });
    let p = plan(&two);
    let light: Vec<_> = p.iter().filter(|p| p.name == "eikonal_light").collect();
    assert_eq!(light.len(), 1, "{p:?}");
    assert!(light[0].reason.contains("light 0") && light[0].reason.contains("light 1"), "{}", light[0].reason);
    // The volume-source scenes: the wine glass's light adds its shadow map and the
    // light simulation (the caustic on the table); the others have no light.
    for scene in ["eikonal_amber_bunny", "eikonal_dispersion_cube"] {
        assert_eq!(names(scene, &[]), ["gbuffer", "deferred_shading", "eikonal_view", "tonemap"]);
    }
    assert_eq!(names("eikonal_wine_glass", &[]), lit);
    for scene in prism::scene::BENCHMARK_SCENES {
        let n = names(scene, &[]);
        assert!(!n.iter().any(|p| p.starts_with("eikonal")), "{scene}: {n:?}");
    }
    let mut no_volume = common::scene("eikonal_luneburg", 64, &[]);
    no_volume.volume = None;
    assert!(!plan(&no_volume).iter().any(|p| p.name.starts_with("eikonal")));
}

/// The impostor textures around a volume (`eikonal_nearby`) are
/// recorded only when an object is left to them: eikonal_sphere's floor quad is intersected
/// exactly by default (no pass), goes through an impostor with render.eikonal.nearby =
/// "impostor" (the pass between the light simulation's receivers and the view pass, whose
/// textures carry the simulated caustic), and with "off" nothing. A non-flat object (here the
/// floor's mesh called a sphere) needs an impostor even in "exact" mode. Volumes without
/// objects never record it.
#[test]
fn eikonal_nearby_only_for_objects_left_to_impostors() {
    if !common::in_own_process() {
        return;
    }
    let lit = ["shadow_map", "gbuffer", "deferred_shading", "eikonal_light", "eikonal_view", "tonemap"];
    assert_eq!(names("eikonal_sphere", &["render.eikonal.nearby=\"exact\""]), lit);
    assert_eq!(names("eikonal_sphere", &["render.eikonal.nearby=\"off\""]), lit);
    assert_eq!(names("eikonal_wine_glass", &[]), lit);
    let with =
        ["shadow_map", "gbuffer", "deferred_shading", "eikonal_light", "eikonal_nearby", "eikonal_view", "tonemap"];
    assert_eq!(names("eikonal_sphere", &["render.eikonal.nearby=\"impostor\""]), with);
    assert_eq!(names("eikonal_wine_glass", &["render.eikonal.nearby=\"impostor\""]), with);
    for scene in ["eikonal_luneburg", "eikonal_amber_bunny", "eikonal_dispersion_cube"] {
        let n = names(scene, &["render.eikonal.nearby=\"impostor\""]);
        assert!(!n.contains(&"eikonal_nearby"), "{scene}: {n:?}");
    }
    let mut s = common::scene("eikonal_sphere", 64, &[]);
    let mut pebble = s.objects[0].clone();
    pebble.name = "pebble".into();
    pebble.shape = "sphere";
    s.objects.push(pebble);
    let p = plan(&s);
    let n: Vec<_> = p.iter().map(|p| p.name).collect();
    assert_eq!(n, with);
    let reason = &p.iter().find(|p| p.name == "eikonal_nearby").unwrap().reason;
    assert!(reason.contains("pebble") && !reason.contains("floor"), "{reason}");
}

/// The options of a `--help` text, `--help` itself left out: the long flag, and the short
/// one where there is one (`-o` for `--output`).
fn help_flags(args: &[&str]) -> Vec<(String, Option<String>)> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_prism")).args(args).arg("--help").output().unwrap();
    assert!(out.status.success());
    let mut flags = Vec::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        // An option line: "  -o, --output <OUTPUT>  ..." or "      --set <KEY=VALUE>  ...".
        let line = line.trim_start();
        let (short, long) = match line.strip_prefix('-') {
            Some(l) if !l.starts_with('-') => (line.get(..2).map(str::to_string), line.get(4..).unwrap_or("")),
            Some(_) => (None, line),
            None => continue,
        };
        if let Some(rest) = long.strip_prefix("--") {
            let name: String = rest.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
            if name != "help" {
                flags.push((format!("--{name}"), short));
            }
        }
    }
    flags
}

/// The `--flag`s a Markdown text names: after a space, a backtick, a bracket or a line start,
/// so that anchors such as `#hu--qin-2007` are not taken for flags.
fn named_flags(text: &str) -> Vec<String> {
    let mut flags = Vec::new();
    for (i, _) in text.match_indices("--") {
        let before = text[..i].chars().next_back();
        if !matches!(before, None | Some(' ' | '`' | '[' | '(' | '\n')) {
            continue;
        }
        let name: String = text[i + 2..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
        if !name.is_empty() {
            flags.push(format!("--{name}"));
        }
    }
    flags
}

/// Every flag of every subcommand is documented in the README or docs/, and every flag the
/// README names is one prism's `--help` shows (or cargo's, for its `cargo run` and
/// `cargo test` lines), so that neither side names a flag the other lacks.
#[test]
fn every_flag_is_documented_and_every_documented_flag_exists() {
    if !common::in_own_process() {
        return;
    }
    let root = env!("CARGO_MANIFEST_DIR");
    let readme = std::fs::read_to_string(format!("{root}/README.md")).unwrap();
    let mut docs = readme.clone();
    for e in std::fs::read_dir(format!("{root}/docs")).unwrap() {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "md") {
            docs += &std::fs::read_to_string(&path).unwrap();
        }
    }
    let documented = named_flags(&docs);
    let subcommands =
        ["render", "bench", "passes", "scenes", "demo", "reference", "compare", "sweep", "report", "ablation"];
    let mut shown = vec!["--help".to_string()];
    for sub in subcommands {
        for (flag, short) in help_flags(&[sub]) {
            // `-o out.png` documents `--output`.
            let short_documented =
                short.is_some_and(|s| docs.contains(&format!("[{s} ")) || docs.contains(&format!(" {s} ")));
            assert!(
                documented.contains(&flag) || short_documented,
                "`prism {sub} {flag}` is in --help but not in README.md or docs/"
            );
            shown.push(flag);
        }
    }
    // cargo's own flags in the README's `cargo run --release --` and `cargo test` lines.
    let cargo = ["--release", "--test", "--nocapture", "--lib"];
    for flag in named_flags(&readme) {
        assert!(
            shown.contains(&flag) || cargo.contains(&flag.as_str()),
            "the README names {flag}, which no `prism SUBCOMMAND --help` shows"
        );
    }
}
