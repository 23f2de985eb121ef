//! Deferred shading of diffuse surfaces (direct light with shadow maps, environment
//! irradiance) and the environment background: glsl/shading/deferred.frag.
use std::sync::Arc;

use crate::gpu::{DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, Sampler};
use crate::graph::{Frame, ImageId};
use crate::renderer::gpu_scene::GpuScene;
use crate::renderer::plan::DEFERRED_SHADING;
use crate::renderer::targets::Targets;
use crate::{BINDING_GBUF_ALBEDO, BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL};

use super::fullscreen::{FullscreenDesc, FullscreenPass};

pub struct DeferredShadingPass {
    pass: FullscreenPass,
    /// Whether a shadow_map pass writes the atlas this frame (then it is a declared read).
    shadowed: bool,
    /// Whether a caustics_map pass writes the caustic atlas this frame.
    caustics: bool,
    /// The photon-buffer caustic textures, when a photon_buffer pass writes them.
    photon: Option<ImageId>,
}

impl DeferredShadingPass {
    pub fn new(
        ctx: &Arc<GpuContext>,
        frame_layout: &DescriptorSetLayout,
        targets: &Targets,
        nearest: &Sampler,
        shadowed: bool,
        caustic_filter: Option<u32>,
        photon: Option<(u32, u32, ImageId)>,
    ) -> GpuResult<Self> {
        let pass = FullscreenPass::new(
            ctx,
            &FullscreenDesc {
                name: DEFERRED_SHADING,
                fragment_shader: "shading/deferred.frag",
                inputs: &[
                    (BINDING_GBUF_NORMAL, &targets.gbuf_normal),
                    (BINDING_GBUF_ALBEDO, &targets.gbuf_albedo),
                    (BINDING_GBUF_DEPTH, &targets.depth),
                ],
                target: (&targets.hdr, targets.hdr_id),
                clear: true,
                // Caustics mapping on/off and its low-pass filter radius; photon-buffer
                // caustics' rectangle count (0: off) and normalisation (deferred.frag).
                specialization: &[
                    u32::from(caustic_filter.is_some()),
                    caustic_filter.unwrap_or(0),
                    photon.map_or(0, |p| p.0),
                    photon.map_or(0, |p| p.1),
                ],
            },
            frame_layout,
            nearest,
        )?;
        Ok(DeferredShadingPass { pass, shadowed, caustics: caustic_filter.is_some(), photon: photon.map(|p| p.2) })
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &GpuScene,
        targets: &Targets,
        frame_set: DescriptorSet,
    ) {
        let mut reads = vec![targets.gbuf_normal_id, targets.gbuf_albedo_id, targets.depth_id, scene.environment_id];
        if self.shadowed {
            reads.push(targets.shadow_atlas_id);
        }
        if self.caustics {
            reads.push(targets.caustic_atlas_id);
        }
        if let Some(id) = self.photon {
            reads.push(id);
        }
        self.pass.record(frame, frame_set, &reads);
    }
}
