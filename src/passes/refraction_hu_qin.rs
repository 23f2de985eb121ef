//! Hu & Qin 2007, "Interactive Approximate Rendering of Reflections, Refractions, and
//! Caustics" (IEEE TVCG 13(1)), §2.1 and §4: refraction of the environment through two
//! interfaces without preprocessing. `render.refraction = "hu_qin"`, parameters
//! `[render.hu_qin]` ([`HuQinParams`]).
//!
//! - `refraction_hu_qin_layers`: depth and normal of the refractors' nearest back faces and
//!   nearest front faces (Fig. 4, "initial pass").
//! - `refraction_hu_qin`: glsl/refraction/hu_qin.frag: T1, the binary search for the dividing
//!   pixel p_e (Fig. 7, `search_steps`), the theta_1/theta_2 test for a front- or back-facing
//!   exit (Fig. 5), the iterative d_T search (Fig. 9, `tolerance`, `max_iterations`), N2 from
//!   the matching normal layer, T2; or section 4's shortcut (`assume_back_facing`).
use std::sync::Arc;

use crate::gpu::{DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, Sampler};
use crate::graph::{Frame, FrameGraph};
use crate::renderer::gpu_scene::GpuScene;
use crate::renderer::plan::{REFRACTION_HU_QIN, REFRACTION_HU_QIN_LAYERS};
use crate::renderer::targets::Targets;
use crate::scene::techniques::HuQinParams;
use crate::scene::Scene;
use crate::{
    BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL, BINDING_REFR_BACK_DEPTH, BINDING_REFR_BACK_NORMAL,
    BINDING_REFR_FRONT_DEPTH, BINDING_REFR_FRONT_NORMAL,
};

use super::refractor_layers::{DebugTarget, LayerKind, RefractorLayers, ShadeDesc, ShadePass};

pub struct HuQinPass {
    layers: RefractorLayers,
    shade: ShadePass,
    pub params: HuQinParams,
}

impl HuQinPass {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Arc<GpuContext>,
        params: HuQinParams,
        scene: &Scene,
        gpu: &GpuScene,
        graph: &mut FrameGraph,
        frame_layout: &DescriptorSetLayout,
        targets: &Targets,
        nearest: &Sampler,
    ) -> GpuResult<Self> {
        let layers = RefractorLayers::new(
            ctx,
            REFRACTION_HU_QIN_LAYERS,
            &[LayerKind::BackNearest, LayerKind::Front],
            None,
            scene,
            gpu,
            graph,
            frame_layout,
            targets,
            nearest,
        )?;
        let (b, f) = (&layers.layers[0], &layers.layers[1]);
        let shade = ShadePass::new(
            ctx,
            &ShadeDesc {
                name: REFRACTION_HU_QIN,
                fragment_shader: "refraction/hu_qin.frag",
                inputs: &[
                    (BINDING_GBUF_NORMAL, &targets.gbuf_normal, targets.gbuf_normal_id),
                    (BINDING_GBUF_DEPTH, &targets.depth, targets.depth_id),
                    (BINDING_REFR_BACK_NORMAL, &b.normal, b.normal_id),
                    (BINDING_REFR_BACK_DEPTH, &b.depth, b.depth_id),
                    (BINDING_REFR_FRONT_NORMAL, &f.normal, f.normal_id),
                    (BINDING_REFR_FRONT_DEPTH, &f.depth, f.depth_id),
                ],
                // Specialisation constants 1..4 of hu_qin.frag.
                specialization: &[
                    params.search_steps,
                    params.tolerance.to_bits(),
                    params.max_iterations,
                    u32::from(params.assume_back_facing),
                ],
                debug: params.debug,
            },
            graph,
            frame_layout,
            targets,
            nearest,
        )?;
        Ok(HuQinPass { layers, shade, params })
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &'a GpuScene,
        targets: &Targets,
        frame_set: DescriptorSet,
    ) {
        self.layers.record(frame, scene, targets, frame_set);
        self.shade.record(frame, scene.environment_id, frame_set);
    }

    /// P2 and T2 (with `debug = true`), see [`ShadePass`].
    pub fn debug_targets(&self) -> &[DebugTarget] {
        &self.shade.debug
    }
}
