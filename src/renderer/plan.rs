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
/// Wyman 2005 (src/passes/refraction_wyman.rs): the refractor layers, then the shading.
pub const REFRACTION_WYMAN_LAYERS: &str = "refraction_wyman_layers";
pub const REFRACTION_WYMAN: &str = "refraction_wyman";
/// Hu & Qin 2007 (src/passes/refraction_hu_qin.rs): the refractor layers, then the shading.
pub const REFRACTION_HU_QIN_LAYERS: &str = "refraction_hu_qin_layers";
pub const REFRACTION_HU_QIN: &str = "refraction_hu_qin";
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
/// Ihrke et al. 2007 (src/passes/eikonal.rs): curved view rays through the `[volume]`.
pub const EIKONAL_VIEW: &str = "eikonal_view";
/// Ihrke et al. 2007 section 5.2 (src/passes/eikonal_light.rs): the light simulation (run
/// when the renderer is created) and the diffuse receivers inside its irradiance volume.
pub const EIKONAL_LIGHT: &str = "eikonal_light";

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
    // --- branch `light`: only with a volume, a light, and render.eikonal.light on.
    if let (Some(v), Some(l)) = (&scene.volume, scene.lights.first()) {
        let on = crate::scene::techniques::EikonalParams::from_settings(&scene.render).map_or(true, |p| p.light);
        if on {
            passes.push(PlannedPass {
                name: EIKONAL_LIGHT,
                reason: format!(
                    "volume {} lit by {}: wavefront light simulation, Ihrke et al. 2007 §4.2, §5.2 (receivers in its irradiance volume)",
                    v.name,
                    describe_light(0, l)
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
        let [nx, ny, nz] = v.resolution;
        passes.push(PlannedPass {
            name: EIKONAL_VIEW,
            reason: format!("volume {} ({nx}x{ny}x{nz}): curved view rays, Ihrke et al. 2007 §4.1, §5.3", v.name),
        });
    }
    passes.push(PlannedPass { name: TONEMAP, reason: "linear radiance -> sRGB PNG output".into() });
    passes
}

/// The caustic passes: only with a light, a specular object, a diffuse receiver and
/// `render.caustics = "caustics_map"`.
fn caustics(scene: &Scene, diffuse: &[String], dielectric: &[String], metal: &[String]) -> Vec<PlannedPass> {
    if scene.render.caustics != "caustics_map" || scene.lights.is_empty() || diffuse.is_empty() {
        return Vec::new();
    }
    let specular: Vec<String> = dielectric.iter().chain(metal).cloned().collect();
    if specular.is_empty() {
        return Vec::new();
    }
    let lights = scene.lights.len();
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
    vec![
        PlannedPass {
            name: layers,
            reason: format!("{what} of dielectric {} (render.refraction = \"{technique}\")", list(dielectric)),
        },
        PlannedPass { name: shade, reason: format!("two-interface refraction of {} ({exit})", list(dielectric)) },
    ]
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
