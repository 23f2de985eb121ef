//! Hu & Qin 2007, "Interactive Approximate Rendering of Reflections, Refractions, and
//! Caustics" (IEEE TVCG 13(1)), §2.1 and §4: refraction of the environment through two
//! interfaces without preprocessing. `render.refraction = "hu_qin"`, parameters
//! `[render.hu_qin]` ([`HuQinParams`]).
//!
//! - `refraction_hu_qin_nearby` (with `nearby = true` and other objects in the scene): §2.2,
//!   the impostor rectangles and textures TEX_i of the nearby objects, one rectangle set per
//!   dielectric (src/passes/nearby_impostors.rs), and `_r1`.. the §2.2.1 recursion levels;
//!   before them `refraction_hu_qin_nearby_back`, the back faces of the dielectric impostors.
//! - `refraction_hu_qin_layers`: depth and normal of the refractors' nearest back faces and
//!   nearest front faces (Fig. 4, "initial pass").
//! - `refraction_hu_qin`: glsl/refraction/hu_qin.frag: T1, the binary search for the dividing
//!   pixel p_e (Fig. 7, `search_steps`), the theta_1/theta_2 test for a front- or back-facing
//!   exit (Fig. 5), the iterative d_T search (Fig. 9, `tolerance`, `max_iterations`), N2 from
//!   the matching normal layer, T2; or section 4's shortcut (`assume_back_facing`). R at P1
//!   and T2 at P2 then look up the nearby rectangles (Fig. 13) with the seed search of Fig. 17
//!   (`seed_samples`) and the iterative correction of Fig. 16 (`correction_iterations`,
//!   `correction_tolerance`), the environment map where no rectangle is hit
//!   (glsl/include/nearby.glsl); reflection and refraction are weighted by Fresnel.
use std::sync::Arc;

use crate::gpu::{DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, Sampler};
use crate::graph::ImageId;
use crate::graph::{Frame, FrameGraph};
use crate::renderer::gpu_scene::GpuScene;
use crate::renderer::plan::{REFRACTION_HU_QIN, REFRACTION_HU_QIN_LAYERS, REFRACTION_HU_QIN_NEARBY};
use crate::renderer::targets::Targets;
use crate::scene::techniques::HuQinParams;
use crate::scene::Scene;
use crate::{
    BINDING_GBUF_ALBEDO, BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL, BINDING_NEARBY_RECTS, BINDING_NEARBY_TEXTURE,
    BINDING_REFR_BACK_DEPTH, BINDING_REFR_BACK_NORMAL, BINDING_REFR_FRONT_DEPTH, BINDING_REFR_FRONT_NORMAL,
};

use super::nearby_impostors::{NearbyDesc, NearbyImpostors};
use super::refractor_layers::{DebugTarget, LayerKind, RefractorLayers, ShadeDesc, ShadePass};

pub struct HuQinPass {
    /// The impostors (a stand-in without nearby objects or with `nearby = false`).
    pub nearby: NearbyImpostors,
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
        // The same rule as plan.rs (REFRACTION_HU_QIN_NEARBY): rectangles only when asked for.
        let nearby = if params.nearby {
            let desc = NearbyDesc {
                resolution: params.impostor_resolution,
                recursion_depth: params.recursion_depth,
                correction_iterations: params.correction_iterations,
                correction_tolerance: params.correction_tolerance,
                seed_samples: params.seed_samples,
                exit: params.recursive_exit,
                search_steps: params.search_steps,
                max_iterations: params.max_iterations,
            };
            NearbyImpostors::with_desc(ctx, REFRACTION_HU_QIN_NEARBY, &desc, scene, gpu, graph, frame_layout)?
        } else {
            NearbyImpostors::stand_in(ctx, REFRACTION_HU_QIN_NEARBY, gpu, graph, frame_layout)?
        };
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
                    (BINDING_GBUF_ALBEDO, &targets.gbuf_albedo, targets.gbuf_albedo_id),
                    (BINDING_REFR_BACK_NORMAL, &b.normal, b.normal_id),
                    (BINDING_REFR_BACK_DEPTH, &b.depth, b.depth_id),
                    (BINDING_REFR_FRONT_NORMAL, &f.normal, f.normal_id),
                    (BINDING_REFR_FRONT_DEPTH, &f.depth, f.depth_id),
                    (BINDING_NEARBY_TEXTURE, &nearby.texture, nearby.texture_id),
                ],
                buffers: &[(BINDING_NEARBY_RECTS, &nearby.rect_buffer)],
                // Specialisation constants 1..7 of hu_qin.frag.
                specialization: &[
                    params.search_steps,
                    params.tolerance.to_bits(),
                    params.max_iterations,
                    u32::from(params.assume_back_facing),
                    params.correction_iterations,
                    params.correction_tolerance.to_bits(),
                    params.seed_samples,
                ],
                debug: params.debug,
            },
            graph,
            frame_layout,
            targets,
            nearest,
        )?;
        Ok(HuQinPass { nearby, layers, shade, params })
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &'a GpuScene,
        targets: &Targets,
        frame_set: DescriptorSet,
        shadow_atlas: Option<ImageId>,
    ) {
        if !self.nearby.is_empty() {
            self.nearby.record(frame, scene, frame_set, shadow_atlas);
        }
        self.layers.record(frame, scene, targets, frame_set);
        self.shade.record(frame, scene.environment_id, frame_set);
    }

    /// P2 and T2 (with `debug = true`), see [`ShadePass`].
    pub fn debug_targets(&self) -> &[DebugTarget] {
        &self.shade.debug
    }
}
