//! Which passes a scene needs, and why (../shared/DESIGN.md, rule 4: model only what the
//! scene requires). Pure CPU: `prism passes SCENE` prints this without touching the GPU, and
//! the renderer creates and records exactly these passes.
use crate::scene::{Light, Material, Scene};

/// Snake_case pass names: also the timing names and golden-image names.
pub const SHADOW_MAP: &str = "shadow_map";
pub const GBUFFER: &str = "gbuffer";
pub const DEFERRED_SHADING: &str = "deferred_shading";
pub const REFRACTION_SINGLE: &str = "refraction_single";
pub const REFLECTION_SINGLE: &str = "reflection_single";
pub const TONEMAP: &str = "tonemap";
/// The adaptive tone map (src/passes/tonemap.rs; `render.tonemap = "adaptive"`): the
/// log-average luminance by a reduction on the GPU, then the adaptation state.
pub const TONEMAP_LOG_AVERAGE: &str = "tonemap_log_average";
pub const TONEMAP_ADAPT: &str = "tonemap_adapt";
/// Wyman 2005 (src/passes/refraction_wyman.rs): the refractor layers, then the shading.
pub const REFRACTION_WYMAN_LAYERS: &str = "refraction_wyman_layers";
pub const REFRACTION_WYMAN: &str = "refraction_wyman";
/// Hu & Qin 2007 (src/passes/refraction_hu_qin.rs): the refractor layers, then the shading.
pub const REFRACTION_HU_QIN_LAYERS: &str = "refraction_hu_qin_layers";
pub const REFRACTION_HU_QIN: &str = "refraction_hu_qin";
/// Hu & Qin 2007 §2.2 (src/passes/nearby_impostors.rs): TEX_i of the nearby objects' impostor
/// rectangles, before the shading that looks them up.
pub const REFRACTION_HU_QIN_NEARBY: &str = "refraction_hu_qin_nearby";
/// Szirmay-Kalos et al. 2005 (src/passes/distance_impostor.rs): the environment distance
/// impostor around the specular objects, the refractor map, then the shading.
pub const REFLECTION_IMPOSTOR_MAP: &str = "reflection_impostor_map";
pub const REFLECTION_IMPOSTOR: &str = "reflection_impostor";
pub const REFRACTION_IMPOSTOR_MAP: &str = "refraction_impostor_map";
pub const REFRACTION_IMPOSTOR_REFRACTOR_MAP: &str = "refraction_impostor_refractor_map";
pub const REFRACTION_IMPOSTOR: &str = "refraction_impostor";
/// Shah et al. 2007 (src/passes/caustics_map.rs): the receivers' positions and the
/// refractors' positions and normals from the light, then the splatted caustic map.
pub const CAUSTICS_MAP_RECEIVERS: &str = "caustics_map_receivers";
pub const CAUSTICS_MAP_REFRACTORS: &str = "caustics_map_refractors";
pub const CAUSTICS_MAP: &str = "caustics_map";
/// Szirmay-Kalos et al. 2005 §5 (src/passes/impostor_lightmap.rs): the uv cube map, the
/// refractor map (dielectrics only), the caustic map from the light, the splats into the
/// receivers' light maps, and the light maps added in deferred shading.
pub const IMPOSTOR_LIGHTMAP_UV_MAP: &str = "impostor_lightmap_uv_map";
pub const IMPOSTOR_LIGHTMAP_REFRACTOR_MAP: &str = "impostor_lightmap_refractor_map";
pub const IMPOSTOR_LIGHTMAP_CAUSTIC_MAP: &str = "impostor_lightmap_caustic_map";
pub const IMPOSTOR_LIGHTMAP_SPLAT: &str = "impostor_lightmap_splat";
pub const IMPOSTOR_LIGHTMAP_APPLY: &str = "impostor_lightmap_apply";
/// Hu & Qin 2007 §3 (src/passes/photon_buffer.rs): the specular objects from the light, the
/// photon buffer, the caustic textures (photons scattered per rectangle), and their filter.
pub const PHOTON_BUFFER_REFRACTORS: &str = "photon_buffer_refractors";
pub const PHOTON_BUFFER: &str = "photon_buffer";
pub const PHOTON_BUFFER_SCATTER: &str = "photon_buffer_scatter";
pub const PHOTON_BUFFER_FILTER: &str = "photon_buffer_filter";
/// Ihrke et al. 2007 (src/passes/eikonal.rs): curved view rays through the `[volume]`.
pub const EIKONAL_VIEW: &str = "eikonal_view";
/// Ihrke et al. 2007 section 5.2 (src/passes/eikonal_light.rs): the light simulation (run
/// when the renderer is created) and the diffuse receivers inside its irradiance volume.
pub const EIKONAL_LIGHT: &str = "eikonal_light";
/// Hu & Qin 2007 §2.2 impostor textures of the objects near the volume, for eikonal_view's
/// exit and reflected rays (src/passes/eikonal_nearby.rs; branch `eikview`).
pub const EIKONAL_NEARBY: &str = "eikonal_nearby";

#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PlannedPass {
    pub name: &'static str,
    /// Which objects, lights or settings require the pass.
    pub reason: String,
}

fn names(scene: &Scene, pred: impl Fn(&Material) -> bool) -> Vec<String> {
    scene.objects.iter().filter(|o| pred(&scene.materials[o.material])).map(|o| o.name.clone()).collect()
}

fn list(v: &[String]) -> String {
    v.join(", ")
}

fn describe_light(i: usize, l: &Light) -> String {
    match l {
        Light::Point { position: p, .. } => {
            format!("light {i} (point at ({}, {}, {}))", p.x, p.y, p.z)
        }
        Light::Directional { direction: d, .. } => {
            format!("light {i} (directional ({:.3}, {:.3}, {:.3}))", d.x, d.y, d.z)
        }
    }
}

/// The ordered pass list for `scene`.
pub fn plan(scene: &Scene) -> Vec<PlannedPass> {
    let diffuse = names(scene, Material::is_diffuse);
    let dielectric = names(scene, |m| matches!(m, Material::Dielectric { .. }));
    let metal = names(scene, |m| matches!(m, Material::Mirror { .. } | Material::Conductor { .. }));
    let mut passes = Vec::new();

    if !scene.lights.is_empty() && !diffuse.is_empty() {
        let lights: Vec<_> = scene.lights.iter().enumerate().map(|(i, l)| describe_light(i, l)).collect();
        passes.push(PlannedPass {
            name: SHADOW_MAP,
            reason: format!("{} cast shadows on the diffuse receivers {}", lights.join(" and "), list(&diffuse)),
        });
    }
    passes.extend(caustics(scene, &diffuse, &dielectric, &metal));
    let lightmap = impostor_lightmap(scene, &dielectric, &metal);
    let lightmap_apply = lightmap.last().cloned();
    passes.extend(lightmap.into_iter().filter(|p| p.name != IMPOSTOR_LIGHTMAP_APPLY));
    passes.push(PlannedPass {
        name: GBUFFER,
        reason: if scene.objects.is_empty() {
            "clears depth: the scene has no objects, so the environment fills the frame".into()
        } else {
            format!("rasterises the first visible surface of {} object(s)", scene.objects.len())
        },
    });
    passes.push(PlannedPass {
        name: DEFERRED_SHADING,
        reason: if diffuse.is_empty() {
            "environment background (no diffuse object)".into()
        } else if scene.lights.is_empty() {
            format!("environment background; diffuse {} lit by the environment only", list(&diffuse))
        } else {
            format!("environment background; diffuse {} lit by {} light(s)", list(&diffuse), scene.lights.len())
        },
    });
    passes.extend(lightmap_apply);
    // --- branch `light`: only with a volume, a light, and render.eikonal.light on.
    if let (Some(v), false) = (&scene.volume, scene.lights.is_empty()) {
        let on = crate::scene::techniques::EikonalParams::from_settings(&scene.render).map_or(true, |p| p.light);
        if on {
            passes.push(PlannedPass {
                name: EIKONAL_LIGHT,
                reason: format!(
                    "volume {} lit by {}: wavefront light simulation, Ihrke et al. 2007 §4.2, §5.2 (receivers in its irradiance volume)",
                    v.name,
                    scene.lights.iter().enumerate().map(|(i, l)| describe_light(i, l)).collect::<Vec<_>>().join(", ")
                ),
            });
        }
    }
    if !dielectric.is_empty() && scene.render.refraction == "single" {
        passes.push(PlannedPass {
            name: REFRACTION_SINGLE,
            reason: format!("dielectric {} (render.refraction = \"single\")", list(&dielectric)),
        });
    }
    if !dielectric.is_empty() {
        passes.extend(image_space_refraction(scene, &dielectric));
    }
    if !dielectric.is_empty() && scene.render.refraction == "impostor" {
        passes.extend(impostor_refraction(&dielectric));
    }
    if !metal.is_empty() && scene.render.reflection == "single" {
        passes.push(PlannedPass {
            name: REFLECTION_SINGLE,
            reason: format!("mirror/conductor {} (render.reflection = \"single\")", list(&metal)),
        });
    }
    if !metal.is_empty() && scene.render.reflection == "impostor" {
        passes.push(PlannedPass {
            name: REFLECTION_IMPOSTOR_MAP,
            reason: format!(
                "distance impostor (radiance + distance cube) around mirror/conductor {} (render.reflection = \"impostor\")",
                list(&metal)
            ),
        });
        passes.push(PlannedPass {
            name: REFLECTION_IMPOSTOR,
            reason: format!("localized reflection of {} (Hit(), Szirmay-Kalos et al. 2005)", list(&metal)),
        });
    }
    if let Some(v) = &scene.volume {
        // --- branch `eikview`: after eikonal_light (the simulation ran at creation; the
        // textures carry its caustic and shadow), before the view pass that reads them.
        passes.extend(eikonal_nearby(scene));
        let [nx, ny, nz] = v.resolution;
        passes.push(PlannedPass {
            name: EIKONAL_VIEW,
            reason: format!("volume {} ({nx}x{ny}x{nz}): curved view rays, Ihrke et al. 2007 §4.1, §5.3", v.name),
        });
    }
    if scene.render.tonemap == "adaptive" {
        passes.push(PlannedPass {
            name: TONEMAP_LOG_AVERAGE,
            reason: "log-average luminance of the HDR image, reduced on the GPU (render.tonemap = \"adaptive\")".into(),
        });
        passes.push(PlannedPass {
            name: TONEMAP_ADAPT,
            reason: "adapted luminance, key and L_white (Krawczyk et al. 2005, Ihrke et al. 2007 §5.3)".into(),
        });
        passes.push(PlannedPass {
            name: TONEMAP,
            reason: "linear radiance -> sRGB: Reinhard's operator on the adapted luminance".into(),
        });
    } else {
        passes.push(PlannedPass { name: TONEMAP, reason: "linear radiance -> sRGB PNG output".into() });
    }
    passes
}

/// The caustic passes: only with a light, a specular object, a diffuse receiver and
/// `render.caustics = "caustics_map"` or `"photon_buffer"`.
fn caustics(scene: &Scene, diffuse: &[String], dielectric: &[String], metal: &[String]) -> Vec<PlannedPass> {
    if scene.lights.is_empty() || diffuse.is_empty() {
        return Vec::new();
    }
    let specular: Vec<String> = dielectric.iter().chain(metal).cloned().collect();
    if specular.is_empty() {
        return Vec::new();
    }
    let lights = scene.lights.len();
    if scene.render.caustics == "photon_buffer" {
        return vec![
            PlannedPass {
                name: PHOTON_BUFFER_REFRACTORS,
                reason: format!("positions and normals of the specular {} seen from the light(s)", list(&specular)),
            },
            PlannedPass {
                name: PHOTON_BUFFER,
                reason: format!(
                    "photons through {} onto the rectangles of the receivers {} (render.caustics = \"photon_buffer\")",
                    list(&specular),
                    list(diffuse)
                ),
            },
            PlannedPass {
                name: PHOTON_BUFFER_SCATTER,
                reason: format!("photon counts in the caustic textures of {}", list(diffuse)),
            },
            PlannedPass { name: PHOTON_BUFFER_FILTER, reason: "filter of Hu & Qin 2007 §3.2".into() },
        ];
    }
    if scene.render.caustics != "caustics_map" {
        return Vec::new();
    }
    vec![
        PlannedPass {
            name: CAUSTICS_MAP_RECEIVERS,
            reason: format!("positions of the diffuse receivers {} seen from {lights} light(s)", list(diffuse)),
        },
        PlannedPass {
            name: CAUSTICS_MAP_REFRACTORS,
            reason: format!("positions and normals of the specular {} seen from the light(s)", list(&specular)),
        },
        PlannedPass {
            name: CAUSTICS_MAP,
            reason: format!(
                "vertex grid splatted onto the receivers through {} (render.caustics = \"caustics_map\")",
                list(&specular)
            ),
        },
    ]
}

/// The diffuse receivers that get light maps (`render.caustics = "impostor_lightmap"`):
/// quads (one planar chart) and boxes (one per face) (src/passes/impostor_lightmap.rs).
pub fn lightmap_receivers(scene: &Scene) -> Vec<usize> {
    (0..scene.objects.len())
        .filter(|&i| {
            let o = &scene.objects[i];
            scene.materials[o.material].is_diffuse() && (o.shape == "quad" || o.shape == "box")
        })
        .collect()
}

/// Light-map caustics with distance impostors (Szirmay-Kalos et al. 2005, §5): only with a
/// light, a specular object, a quad or box receiver and `render.caustics = "impostor_lightmap"`.
fn impostor_lightmap(scene: &Scene, dielectric: &[String], metal: &[String]) -> Vec<PlannedPass> {
    let receivers: Vec<String> = lightmap_receivers(scene).iter().map(|&i| scene.objects[i].name.clone()).collect();
    if scene.render.caustics != "impostor_lightmap" || scene.lights.is_empty() || receivers.is_empty() {
        return Vec::new();
    }
    let specular: Vec<String> = dielectric.iter().chain(metal).cloned().collect();
    if specular.is_empty() {
        return Vec::new();
    }
    let (receivers, specular) = (list(&receivers), list(&specular));
    let mut passes = vec![PlannedPass {
        name: IMPOSTOR_LIGHTMAP_UV_MAP,
        reason: format!(
            "uv cube map (light-map uv + receiver id + distance) around {specular} of receivers {receivers}"
        ),
    }];
    if !dielectric.is_empty() {
        passes.push(PlannedPass {
            name: IMPOSTOR_LIGHTMAP_REFRACTOR_MAP,
            reason: format!("refractor map of {} for the photons' exit points", list(dielectric)),
        });
    }
    passes.extend([
        PlannedPass {
            name: IMPOSTOR_LIGHTMAP_CAUSTIC_MAP,
            reason: format!("caustic map of {specular} from {} light(s): Hit() into the uv map", scene.lights.len()),
        },
        PlannedPass {
            name: IMPOSTOR_LIGHTMAP_SPLAT,
            reason: format!(
                "Gaussian splats into the light maps of {receivers} (render.caustics = \"impostor_lightmap\")"
            ),
        },
        PlannedPass {
            name: IMPOSTOR_LIGHTMAP_APPLY,
            reason: format!("caustic irradiance of the light maps on {receivers}"),
        },
    ]);
    passes
}

/// The passes of the two-interface image-space refraction techniques, if one is selected.
fn image_space_refraction(scene: &Scene, dielectric: &[String]) -> Vec<PlannedPass> {
    let (layers, shade, what, exit) = match scene.render.refraction.as_str() {
        "wyman" => (
            REFRACTION_WYMAN_LAYERS,
            REFRACTION_WYMAN,
            "back surface (depth, normal) and front faces with d_N",
            "d_V/d_N interpolation, Wyman 2005",
        ),
        "hu_qin" => (
            REFRACTION_HU_QIN_LAYERS,
            REFRACTION_HU_QIN,
            "back and front faces (depth, normal)",
            "binary search and iterative d_T, Hu & Qin 2007",
        ),
        _ => return Vec::new(),
    };
    let technique = &scene.render.refraction;
    let mut passes = Vec::new();
    if technique == "hu_qin" {
        passes.extend(hu_qin_nearby(scene));
    }
    passes.push(PlannedPass {
        name: layers,
        reason: format!("{what} of dielectric {} (render.refraction = \"{technique}\")", list(dielectric)),
    });
    passes.push(PlannedPass {
        name: shade,
        reason: format!("two-interface refraction of {} ({exit})", list(dielectric)),
    });
    passes
}

/// Hu & Qin 2007 §2.2: the impostor textures, when `render.hu_qin.nearby` is on and a
/// dielectric has other objects to stand in for; §2.2.1's recursion levels when a rectangle
/// stands for a specular object (another dielectric, a mirror or a conductor).
fn hu_qin_nearby(scene: &Scene) -> Vec<PlannedPass> {
    use crate::passes::nearby_impostors::{
        has_dielectric_rect, nearby_layout, needs_copy, BACK_PASS, COPY_PASS, RECURSION_PASSES,
    };
    let params = crate::scene::techniques::HuQinParams::from_settings(&scene.render).unwrap_or_default();
    if !params.nearby {
        return Vec::new();
    }
    let layout = nearby_layout(scene, params.recursion_depth);
    if layout.rects.is_empty() {
        return Vec::new();
    }
    let name = |i: usize| scene.objects[i].name.clone();
    let sets: Vec<String> = layout
        .sets
        .iter()
        .map(|s| {
            let kept: Vec<String> =
                layout.rects[s.first as usize..(s.first + s.count) as usize].iter().map(|r| name(r.object)).collect();
            let mut t = format!("{} sees {}", name(s.object), list(&kept));
            if !s.dropped.is_empty() {
                let dropped: Vec<String> = s.dropped.iter().map(|&i| name(i)).collect();
                t += &format!(
                    " ({} left to the environment map: at most {} rectangles, the nearest are kept)",
                    list(&dropped),
                    crate::MAX_NEARBY_RECTS
                );
            }
            t
        })
        .collect();
    let mut reason = format!(
        "impostor rectangles + textures for the refracted and reflected rays (Hu & Qin 2007 §2.2): {}",
        sets.join("; ")
    );
    if !layout.without_set.is_empty() {
        let names: Vec<String> = layout.without_set.iter().map(|&i| name(i)).collect();
        reason += &format!(
            "; {} without a rectangle set of its own (at most {} sets): environment only",
            list(&names),
            crate::MAX_NEARBY_SETS
        );
    }
    let mut passes = Vec::new();
    if params.recursive_exit.uses_layers() && has_dielectric_rect(scene, &layout) {
        let names: Vec<String> = layout
            .rects
            .iter()
            .filter(|r| matches!(scene.materials[scene.objects[r.object].material], Material::Dielectric { .. }))
            .map(|r| name(r.object))
            .collect();
        passes.push(PlannedPass {
            name: BACK_PASS,
            reason: format!(
                "{} faces (normal, depth) of dielectric impostor(s) {} in their rectangles' projections: the exit \
                 surfaces of their refraction (Hu & Qin 2007 §2.1 in §2.2.1's textures; \
                 render.hu_qin.recursive_exit = \"{}\")",
                if params.recursive_exit == crate::scene::techniques::RecursiveExit::Full {
                    "back and front"
                } else {
                    "back"
                },
                list(&names),
                params.recursive_exit.name()
            ),
        });
    }
    passes.push(PlannedPass { name: REFRACTION_HU_QIN_NEARBY, reason });
    if needs_copy(scene, &layout) {
        passes.push(PlannedPass {
            name: COPY_PASS,
            reason: "level 0's diffuse impostor textures copied into the recursion's other array: they do not \
                     change between levels, which re-render only the specular ones (Hu & Qin 2007 §2.2.1)"
                .to_string(),
        });
    }
    for level in 1..=layout.levels {
        passes.push(PlannedPass {
            name: RECURSION_PASSES[level as usize - 1],
            reason: format!(
                "recursion level {level} of {} (render.hu_qin.recursion_depth): the mirrors, conductors and \
                 dielectrics among the impostors reflect and refract the impostors of level {} of their own \
                 rectangle sets (Hu & Qin 2007 §2.2.1)",
                params.recursion_depth,
                level - 1
            ),
        });
    }
    passes
}

/// Issue 7: the impostor textures of the objects that eikonal_view's exit and reflected rays
/// may meet (render.eikonal.nearby; none when every nearby object is intersected exactly).
fn eikonal_nearby(scene: &Scene) -> Option<PlannedPass> {
    use crate::passes::eikonal_nearby::impostor_objects;
    let p = crate::scene::techniques::EikonalParams::from_settings(&scene.render).unwrap_or_default();
    let (kept, dropped) = impostor_objects(scene, p.nearby);
    let names = |v: &[usize]| v.iter().map(|&i| scene.objects[i].name.clone()).collect::<Vec<_>>();
    let mut reason = format!(
        "impostor rectangles + textures of {} around the volume for its exit and reflected rays (Hu & Qin 2007 §2.2)",
        list(&names(&kept))
    );
    if !dropped.is_empty() {
        reason += &format!("; {} left to the environment map", list(&names(&dropped)));
    }
    (!kept.is_empty()).then_some(PlannedPass { name: EIKONAL_NEARBY, reason })
}

/// The passes of double refraction with distance impostors (Szirmay-Kalos et al. 2005, §4).
fn impostor_refraction(dielectric: &[String]) -> Vec<PlannedPass> {
    let list = list(dielectric);
    vec![
        PlannedPass {
            name: REFRACTION_IMPOSTOR_MAP,
            reason: format!("distance impostor around dielectric {list} (render.refraction = \"impostor\")"),
        },
        PlannedPass {
            name: REFRACTION_IMPOSTOR_REFRACTOR_MAP,
            reason: format!("refractor map (distance + normal cube) of {list}"),
        },
        PlannedPass {
            name: REFRACTION_IMPOSTOR,
            reason: format!("double refraction of {list} through the refractor map (Szirmay-Kalos et al. 2005, §4)"),
        },
    ]
}

/// Whether the plan contains `name`.
pub fn has(plan: &[PlannedPass], name: &str) -> bool {
    plan.iter().any(|p| p.name == name)
}
