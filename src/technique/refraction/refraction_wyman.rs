//! Wyman 2005, "An Approximate Image-Space Approach for Interactive Refraction" (SIGGRAPH
//! 2005): refraction of a distant environment through two interfaces. `render.refraction =
//! "wyman"`, parameters `[render.wyman]` ([`WymanParams`]).
//!
//! - `refraction_wyman_layers`: the refractors' back surface, depth and normal (§3.1 Fig. 3a,
//!   §3.2 Fig. 3d), either the furthest surface or the second one, "the first backfacing
//!   surface" (§3.2, `back_surface`). The paper's object is one refractor: the back surface
//!   is kept per refractor (one array layer each), so that a pixel's d_V and N2 come from its
//!   own refractor, never from another one behind it or in front of it.
//! - The front faces, with d_N interpolated from the vertices, are the G-buffer's
//!   (src/technique/baseline/gbuffer.rs): as in the paper, the front faces are drawn once.
//! - `refraction_wyman`: glsl/refraction/wyman.frag, the fragment program of §4: T1 by
//!   Snell's law at the G-buffer's P1, d_V from the two depths, d~ interpolated between d_V
//!   and d_N (§3.1), P2~ = P1 + d~ T1 projected into the back normals for N2 (§3.2), T2, the
//!   environment; TIR clamped to the critical angle and the silhouette fallback of §3.3.
//!
//! d_N is precomputed per vertex on the CPU ([`super::wyman_distance`]) and reaches the
//! shading through the G-buffer.
//!
//! `oracle` (an analysis tool, [`WymanOracle`]) replaces the exit point of §3.1 and/or the
//! exit normal of §3.2 by the exact ones, traced through the reference's geometry
//! (glsl/reference/trace.glsl): the pass then runs glsl/refraction/wyman_oracle.frag, with the
//! tracer's buffers in a set 2 of its own and the ORACLE specialisation constant. With
//! `"none"` neither the variant, nor the tracer's geometry, nor its set exist.

use crate::gpu::{Buffer, Spec};
use crate::graph::Frame;
use crate::scene::techniques::{BackSurface, WymanOracle, WymanParams};
use crate::scene::{Material, Scene};
use crate::technique::baseline::specular_single::has_dispersion;
use crate::technique::scene_specialization;
use crate::technique::{
    in_stage, list, params, refracting_objects, registration, FrameInputs, PlannedPass, Registration, RenderError,
    Setup, Stage, Technique,
};
use crate::{
    BINDING_GBUF_ALBEDO, BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL, BINDING_REFR_BACK_DEPTH, BINDING_REFR_BACK_NORMAL,
    BINDING_REFR_SLOTS,
};

use super::oracle::Oracle;
use super::refractor_layers::{
    refractor_slots, DebugTarget, LayerKind, LayerScope, RefractorLayers, ShadeDesc, ShadePass,
};
use super::wyman_distance::distance_along_normals_timed;

pub const REFRACTION_WYMAN_LAYERS: &str = "refraction_wyman_layers";
pub const REFRACTION_WYMAN: &str = "refraction_wyman";

/// `render.refraction = "wyman"`, parameters `[render.wyman]`.
pub const TECHNIQUE: Registration = registration!("refraction = \"wyman\"", plan, WymanPass, ["wyman"]);

fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let Some(dielectric) = refracting_objects(scene, "wyman") else {
        return Vec::new();
    };
    let list = list(&dielectric);
    let layers = PlannedPass::new(
        REFRACTION_WYMAN_LAYERS,
        format!("back surface (depth, normal) of dielectric {list} (render.refraction = \"wyman\")"),
    );
    let shade = PlannedPass::new(
        REFRACTION_WYMAN,
        format!("two-interface refraction of {list} (d_V/d_N interpolation, Wyman 2005)"),
    );
    in_stage(Stage::Refraction, [layers, shade])
}

impl Technique for WymanPass {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        self.layers.record(frame, inputs.scene, inputs.frame_set);
        self.shade.record(frame, inputs);
    }

    fn debug_targets(&self) -> &[DebugTarget] {
        &self.shade.debug
    }

    fn once_costs(&self) -> Vec<crate::technique::OnceCost> {
        let mut costs = vec![d_n_cost(self.d_n_ms)];
        costs.extend(self.oracle.as_ref().map(|o| o.cost()));
        costs
    }
}

pub struct WymanPass {
    layers: RefractorLayers,
    shade: ShadePass,
    pub params: WymanParams,
    /// Per object, its layer in the per-refractor back surface.
    _slots: Buffer,
    /// Host milliseconds §3.1's d_N took for the refractors' meshes when computed.
    d_n_ms: f64,
    /// The exact tracer an oracle reads (bound in the shading pass's set 2).
    oracle: Option<Oracle>,
}

/// §3.1's d_N as a cost paid once (`ms` host milliseconds, [`scene_distance_along_normals_timed`]):
/// cached per mesh (positions, normals, indices), and measured along the object's own
/// normals, so a rigid move, a light or the camera leaves it valid.
pub fn d_n_cost(ms: f64) -> crate::technique::OnceCost {
    crate::technique::OnceCost { name: "wyman_d_n".into(), ms, clock: "cpu", rerun_on: "mesh change" }
}

/// d_N of every scene vertex, in GpuScene's vertex order (0 for non-refractors).
pub fn scene_distance_along_normals(scene: &Scene) -> Vec<f32> {
    scene_distance_along_normals_timed(scene).0
}

/// [`scene_distance_along_normals`] and the host milliseconds its computation took (the
/// meshes' own times, cached or not: [`distance_along_normals_timed`]; a mesh shared by
/// several objects is computed, and counted, once).
pub fn scene_distance_along_normals_timed(scene: &Scene) -> (Vec<f32>, f64) {
    let (mut out, mut ms, mut seen) = (Vec::new(), 0.0, Vec::new());
    for o in &scene.objects {
        if matches!(scene.materials[o.material], Material::Dielectric { .. }) {
            let (d, t) = distance_along_normals_timed(&o.mesh);
            out.extend_from_slice(&d);
            if !seen.iter().any(|s| std::sync::Arc::ptr_eq(s, &d)) {
                ms += t;
                seen.push(d);
            }
        } else {
            out.extend(std::iter::repeat_n(0.0, o.mesh.positions.len()));
        }
    }
    (out, ms)
}

impl WymanPass {
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let params = params("wyman", WymanParams::from_settings(&s.scene.render))?;
        let oracle = if params.oracle == WymanOracle::None { None } else { Some(Oracle::new(s)?) };
        let (ctx, scene, frame_layout, targets, nearest) = (s.ctx, s.scene, s.frame_layout, s.targets, s.nearest);
        let back = match params.back_surface {
            BackSurface::Furthest => LayerKind::BackFurthest,
            BackSurface::Second => LayerKind::BackNearest,
        };
        // The G-buffer carries d_N (it draws the front faces), computed there from the same
        // per-mesh cache: this call only reads the time the computation took.
        let d_n_ms = scene_distance_along_normals_timed(scene).1;
        let layers = RefractorLayers::new(s, REFRACTION_WYMAN_LAYERS, &[(back, LayerScope::PerRefractor)])?;
        let slot_of_object = refractor_slots(scene, s.gpu);
        let refractors = slot_of_object.iter().filter(|&&slot| slot != u32::MAX).count();
        let slots = Buffer::storage(ctx, "refraction_wyman_slots", &slot_of_object)?;
        let b = &layers.layers[0];
        let mut specialization = vec![
            ("DISPERSION", Spec::U32(u32::from(has_dispersion(scene)))),
            ("BACK_FURTHEST", Spec::U32(u32::from(back == LayerKind::BackFurthest))),
            ("ONE_REFRACTOR", Spec::U32(u32::from(refractors == 1))),
        ];
        specialization.extend(scene_specialization(scene));
        let fragment_shader = match &oracle {
            None => "refraction/wyman.frag",
            Some(_) => {
                specialization.push(("ORACLE", Spec::U32(params.oracle.bits())));
                "refraction/wyman_oracle.frag"
            }
        };
        let shade = ShadePass::new(
            ctx,
            &ShadeDesc {
                name: REFRACTION_WYMAN,
                fragment_shader,
                inputs: &[
                    (BINDING_GBUF_NORMAL, &targets.gbuf_normal, targets.gbuf_normal_id),
                    (BINDING_GBUF_DEPTH, &targets.depth, targets.depth_id),
                    (BINDING_GBUF_ALBEDO, &targets.gbuf_albedo, targets.gbuf_albedo_id),
                    (BINDING_REFR_BACK_NORMAL, &b.normal, b.normal_id),
                    (BINDING_REFR_BACK_DEPTH, &b.depth, b.depth_id),
                ],
                buffers: &[(BINDING_REFR_SLOTS, &slots)],
                uniforms: &[],
                tracer: oracle.as_ref().map(|o| (o, s.gpu)),
                specialization: &specialization,
                debug: params.debug,
                scene,
            },
            s.graph,
            frame_layout,
            targets,
            nearest,
        )?;
        Ok(WymanPass { layers, shade, params, _slots: slots, d_n_ms, oracle })
    }
}
