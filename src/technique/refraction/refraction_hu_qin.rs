//! Hu & Qin 2007, "Interactive Approximate Rendering of Reflections, Refractions, and
//! Caustics" (IEEE TVCG 13(1)), §2.1 and §4: refraction of the environment through two
//! interfaces without preprocessing. `render.refraction = "hu_qin"`, parameters
//! `[render.hu_qin]` ([`HuQinParams`]).
//!
//! - `refraction_hu_qin_nearby` (with `nearby = true` and other objects in the scene): §2.2,
//!   the impostor rectangles and textures TEX_i of the nearby objects, one rectangle set per
//!   dielectric (src/technique/refraction/nearby_impostors.rs), and `_r1`.. the §2.2.1 recursion levels;
//!   before them `refraction_hu_qin_nearby_back`, the back faces of the dielectric impostors.
//! - `refraction_hu_qin_layers`: depth and normal of the refractors' nearest back faces and
//!   nearest front faces (Fig. 4, "initial pass"). Where every object is a closed refractor,
//!   the G-buffer already holds the front faces' depth and normal
//!   ([`gbuffer_holds_front_layer`]): with `front_layer = "auto"` the pass then draws the back
//!   faces only, and the exit search reads the G-buffer for the front layer, as Wyman's
//!   shading reads its front faces.
//! - `refraction_hu_qin`: glsl/refraction/hu_qin.frag: T1, the binary search for the dividing
//!   pixel p_e (Fig. 7, `search_steps`), the theta_1/theta_2 test for a front- or back-facing
//!   exit (Fig. 5), the iterative d_T search (Fig. 9, `tolerance`, `max_iterations`), N2 from
//!   the matching normal layer, T2; or section 4's shortcut (`assume_back_facing`). R at P1
//!   and T2 at P2 then look up the nearby rectangles (Fig. 13) with the seed search of Fig. 17
//!   (`seed_samples`) and the iterative correction of Fig. 16 (`correction_iterations`,
//!   `correction_tolerance`), the environment map where no rectangle is hit
//!   (glsl/include/nearby.glsl); reflection and refraction are weighted by Fresnel.
//!
//! `oracle` (an analysis tool, [`HuQinOracle`]) replaces the exit point, the exit normal
//! and/or the nearby lookup by the exact ones, traced through the reference's geometry
//! ([`super::oracle`], glsl/refraction/hu_qin_oracle.frag); with `"none"` nothing of it exists.

use crate::gpu::Spec;
use crate::graph::Frame;
use crate::scene::techniques::{BackFacing, DTStep, FrontLayer, HuQinOracle, HuQinParams, RecursiveExit};
use crate::scene::{Material, Scene};
use crate::technique::baseline::specular_single::has_dispersion;
use crate::technique::scene_specialization;
use crate::technique::{
    in_stage, list, params, refracting_objects, registration, FrameInputs, PlannedPass, Registration, RenderError,
    Setup, Stage, Technique,
};
use crate::{
    BINDING_GBUF_ALBEDO, BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL, BINDING_NEARBY_RECTS, BINDING_NEARBY_TEXTURE,
    BINDING_REFR_BACK_DEPTH, BINDING_REFR_BACK_NORMAL, BINDING_REFR_FRONT_DEPTH, BINDING_REFR_FRONT_NORMAL,
    D_T_STEP_NEWTON, D_T_STEP_PAPER,
};

use super::nearby_impostors::{
    has_dielectric_rect, nearby_layout, nearby_lookup_constant, needs_copy, NearbyDesc, NearbyImpostors, BACK_PASS,
    COPY_PASS, RECURSION_PASSES,
};
use super::oracle::Oracle;
use super::refractor_layers::{
    gbuffer_holds_front_layer, DebugTarget, LayerKind, LayerScope, RefractorLayers, ShadeDesc, ShadePass,
};

pub const REFRACTION_HU_QIN_LAYERS: &str = "refraction_hu_qin_layers";
pub const REFRACTION_HU_QIN: &str = "refraction_hu_qin";
/// §2.2: TEX_i of the nearby objects' impostor rectangles, before the shading that looks
/// them up.
pub const REFRACTION_HU_QIN_NEARBY: &str = "refraction_hu_qin_nearby";

/// `render.refraction = "hu_qin"`, parameters `[render.hu_qin]`.
pub const TECHNIQUE: Registration = registration!("refraction = \"hu_qin\"", plan, HuQinPass, ["hu_qin"]);

/// Whether the exit search assumes a back-facing exit (§4) for `scene`: `"auto"` does where
/// every dielectric object is a closed mesh at least as dense as air in every channel
/// ([`BackFacing::Auto`]). §4's argument is about a closed refractor: light that entered an
/// open surface (a heightfield's water) has no far side of it to leave through.
pub fn assumes_back_facing(params: &HuQinParams, scene: &Scene) -> bool {
    match params.assume_back_facing {
        BackFacing::True => true,
        BackFacing::False => false,
        BackFacing::Auto => scene.objects.iter().all(|o| match scene.material_of(o) {
            Material::Dielectric { ior, .. } => {
                ior.min_element() >= 1.0 && o.heightfield.is_none() && o.mesh.is_closed_outward()
            }
            _ => true,
        }),
    }
}

/// Whether the exit search reads the front faces from the G-buffer (`front_layer = "auto"`
/// where it holds them) instead of a layer of their own.
fn front_from_gbuffer(params: &HuQinParams, scene: &Scene) -> bool {
    params.front_layer == FrontLayer::Auto && gbuffer_holds_front_layer(scene)
}

fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let Some(dielectric) = refracting_objects(scene, "hu_qin") else {
        return Vec::new();
    };
    let mut passes = nearby_plan(scene);
    let params = HuQinParams::from_settings(&scene.render).unwrap_or_default();
    let layers = if front_from_gbuffer(&params, scene) {
        format!(
            "back faces (depth, normal) of dielectric {} (render.refraction = \"hu_qin\"); their front faces are \
             the G-buffer's: every object is a closed refractor (render.hu_qin.front_layer = \"auto\")",
            list(&dielectric)
        )
    } else {
        format!(
            "back and front faces (depth, normal) of dielectric {} (render.refraction = \"hu_qin\")",
            list(&dielectric)
        )
    };
    passes.push(PlannedPass::new(REFRACTION_HU_QIN_LAYERS, layers));
    passes.push(PlannedPass::new(
        REFRACTION_HU_QIN,
        format!("two-interface refraction of {} (binary search and iterative d_T, Hu & Qin 2007)", list(&dielectric)),
    ));
    in_stage(Stage::Refraction, passes)
}

/// §2.2: the impostor textures, when `render.hu_qin.nearby` is on and a dielectric has other
/// objects to stand in for; §2.2.1's recursion levels when a rectangle stands for a specular
/// object (another dielectric, a mirror or a conductor).
fn nearby_plan(scene: &Scene) -> Vec<PlannedPass> {
    let params = HuQinParams::from_settings(&scene.render).unwrap_or_default();
    if !params.nearby {
        return Vec::new();
    }
    let layout = nearby_layout(scene, params.recursion_depth);
    if layout.rects.is_empty() {
        return Vec::new();
    }
    let name = |i: usize| scene.objects[i].name.clone();
    let names = |objects: &[usize]| list(&objects.iter().map(|&i| name(i)).collect::<Vec<_>>());
    let sets: Vec<String> = layout
        .sets
        .iter()
        .map(|s| {
            let kept: Vec<String> =
                layout.rects[s.first as usize..(s.first + s.count) as usize].iter().map(|r| name(r.object)).collect();
            let mut t = format!("{} sees {}", name(s.object), list(&kept));
            if !s.dropped.is_empty() {
                t += &format!(
                    " ({} left to the environment map: at most {} rectangles, the nearest are kept)",
                    names(&s.dropped),
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
        reason += &format!(
            "; {} without a rectangle set of its own (at most {} sets): environment only",
            names(&layout.without_set),
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
        passes.push(PlannedPass::new(
            BACK_PASS,
            format!(
                "{} faces (normal, depth) of dielectric impostor(s) {} in their rectangles' projections: the exit \
                 surfaces of their refraction (Hu & Qin 2007 §2.1 in §2.2.1's textures; \
                 render.hu_qin.recursive_exit = \"{}\")",
                if params.recursive_exit == RecursiveExit::Full { "back and front" } else { "back" },
                list(&names),
                params.recursive_exit.name()
            ),
        ));
    }
    passes.push(PlannedPass::new(REFRACTION_HU_QIN_NEARBY, reason));
    if needs_copy(scene, &layout) {
        passes.push(PlannedPass::new(
            COPY_PASS,
            "level 0's diffuse impostor textures copied into the recursion's other array: they do not \
             change between levels, which re-render only the specular ones (Hu & Qin 2007 §2.2.1)",
        ));
    }
    for level in 1..=layout.levels {
        passes.push(PlannedPass::new(
            RECURSION_PASSES[level as usize - 1],
            format!(
                "recursion level {level} of {} (render.hu_qin.recursion_depth): the mirrors, conductors and \
                 dielectrics among the impostors reflect and refract the impostors of level {} of their own \
                 rectangle sets (Hu & Qin 2007 §2.2.1)",
                params.recursion_depth,
                level - 1
            ),
        ));
    }
    passes
}

impl Technique for HuQinPass {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        let (scene, frame_set) = (inputs.scene, inputs.frame_set);
        if !self.nearby.is_empty() {
            self.nearby.record(frame, inputs);
        }
        self.layers.record(frame, scene, frame_set);
        self.shade.record(frame, inputs);
    }

    /// P2 and T2 (with `debug = true`), see [`ShadePass`].
    fn debug_targets(&self) -> &[DebugTarget] {
        &self.shade.debug
    }

    fn kept(&mut self) -> Option<&mut crate::technique::Regeneration> {
        Some(&mut self.nearby.regeneration)
    }

    fn once_costs(&self) -> Vec<crate::technique::OnceCost> {
        self.oracle.iter().map(Oracle::cost).collect()
    }
}

pub struct HuQinPass {
    /// The impostors (a stand-in without nearby objects or with `nearby = false`).
    pub nearby: NearbyImpostors,
    layers: RefractorLayers,
    shade: ShadePass,
    pub params: HuQinParams,
    /// The exact tracer an oracle reads (bound in the shading pass's set 2).
    oracle: Option<Oracle>,
}

impl HuQinPass {
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let params = params("hu_qin", HuQinParams::from_settings(&s.scene.render))?;
        let oracle = if params.oracle == HuQinOracle::None { None } else { Some(Oracle::new(s)?) };
        let (ctx, scene, gpu, frame_layout) = (s.ctx, s.scene, s.gpu, s.frame_layout);
        let graph = &mut *s.graph;
        // The same rule as the plan's REFRACTION_HU_QIN_NEARBY: rectangles only when asked for.
        let nearby = if params.nearby {
            let desc = NearbyDesc {
                resolution: params.impostor_resolution,
                recursion_depth: params.recursion_depth,
                correction_iterations: params.correction_iterations,
                correction_tolerance: params.correction_tolerance,
                seed_samples: params.seed_samples,
                lookup: params.recursive_lookup,
                exit: params.recursive_exit,
                search_steps: params.search_steps,
                max_iterations: params.max_iterations,
            };
            NearbyImpostors::with_desc(ctx, REFRACTION_HU_QIN_NEARBY, &desc, scene, gpu, graph, frame_layout)?
        } else {
            NearbyImpostors::stand_in(ctx, REFRACTION_HU_QIN_NEARBY, gpu, graph, frame_layout)?
        };
        let front_in_gbuffer = front_from_gbuffer(&params, scene);
        let mut kinds = vec![(LayerKind::BackNearest, LayerScope::Shared)];
        if !front_in_gbuffer {
            kinds.push((LayerKind::Front, LayerScope::Shared));
        }
        let layers = RefractorLayers::new(s, REFRACTION_HU_QIN_LAYERS, &kinds)?;
        let (graph, targets, nearest) = (&mut *s.graph, s.targets, s.nearest);
        let b = &layers.layers[0];
        // The front layer's reversed-Z depth, cleared to 0 where no refractor is, and its
        // normal in xyz (the G-buffer's w, the material, is not read as a layer's).
        let front = match layers.layer(LayerKind::Front) {
            Some(f) => [(&f.normal, f.normal_id), (&f.depth, f.depth_id)],
            None => [(&targets.gbuf_normal, targets.gbuf_normal_id), (&targets.depth, targets.depth_id)],
        };
        let mut specialization = vec![
            ("SEARCH_STEPS", Spec::U32(params.search_steps)),
            ("TOLERANCE", Spec::F32(params.tolerance)),
            ("MAX_ITERATIONS", Spec::U32(params.max_iterations)),
            ("ASSUME_BACK_FACING", Spec::U32(u32::from(assumes_back_facing(&params, scene)))),
            ("NEARBY_ITERATIONS", Spec::U32(params.correction_iterations)),
            ("NEARBY_TOLERANCE", Spec::F32(params.correction_tolerance)),
            ("NEARBY_SEEDS", Spec::U32(params.seed_samples)),
            ("NEARBY_LOOKUP", Spec::U32(nearby_lookup_constant(params.nearby_lookup))),
            // No rectangle: the lookups are compiled out, R and T2 see the environment.
            ("NEARBY", Spec::U32(u32::from(!nearby.is_empty()))),
            ("DISPERSION", Spec::U32(u32::from(has_dispersion(scene)))),
            (
                "D_T_STEP",
                Spec::U32(match params.d_t_step {
                    DTStep::Paper => D_T_STEP_PAPER,
                    DTStep::Newton => D_T_STEP_NEWTON,
                }),
            ),
            ("D_T_BRACKET", Spec::U32(u32::from(params.d_t_bracket))),
        ];
        specialization.extend(scene_specialization(scene));
        let fragment_shader = match &oracle {
            None => "refraction/hu_qin.frag",
            Some(_) => {
                specialization.push(("ORACLE", Spec::U32(params.oracle.bits())));
                "refraction/hu_qin_oracle.frag"
            }
        };
        let shade = ShadePass::new(
            ctx,
            &ShadeDesc {
                name: REFRACTION_HU_QIN,
                fragment_shader,
                inputs: &[
                    (BINDING_GBUF_NORMAL, &targets.gbuf_normal, targets.gbuf_normal_id),
                    (BINDING_GBUF_DEPTH, &targets.depth, targets.depth_id),
                    (BINDING_GBUF_ALBEDO, &targets.gbuf_albedo, targets.gbuf_albedo_id),
                    (BINDING_REFR_BACK_NORMAL, &b.normal, b.normal_id),
                    (BINDING_REFR_BACK_DEPTH, &b.depth, b.depth_id),
                    (BINDING_REFR_FRONT_NORMAL, front[0].0, front[0].1),
                    (BINDING_REFR_FRONT_DEPTH, front[1].0, front[1].1),
                    (BINDING_NEARBY_TEXTURE, &nearby.texture, nearby.texture_id),
                ],
                buffers: &[],
                uniforms: &[(BINDING_NEARBY_RECTS, &nearby.rect_buffer)],
                tracer: oracle.as_ref().map(|o| (o, gpu)),
                specialization: &specialization,
                debug: params.debug,
                scene,
            },
            graph,
            frame_layout,
            targets,
            nearest,
        )?;
        Ok(HuQinPass { nearby, layers, shade, params, oracle })
    }
}
