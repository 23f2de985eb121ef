//! The oracles of the image-space refraction techniques (`render.wyman.oracle`,
//! `render.hu_qin.oracle`), of the distance impostors (`render.impostor.oracle`) and of
//! caustics mapping (`render.caustics_map.oracle`): an analysis tool that replaces a
//! technique's approximate intermediates by the exact tracer's (`prism ablation`). The oracle
//! variants of the shading passes (glsl/refraction/*_oracle.frag, glsl/impostor/*_oracle.frag,
//! ORACLE_TRACE defined) include the reference's intersection code
//! (glsl/reference/trace.glsl) with its buffers in a set 2 of their own: REF_BINDING_* would
//! meet the G-buffer's, the layers' and the impostors' bindings in set 1. Caustics mapping's
//! hits pass (glsl/caustics/splat_hits_oracle.comp) has one set of its own and binds them in
//! set 1.
use std::rc::Rc;
use std::sync::Arc;

use crate::frame::gpu_scene::GpuScene;
use crate::gpu::{vk, Buffer, GpuContext, GpuResult};
use crate::graph::{Bindings, BoundSet};
use crate::reference::TraceGeometry;
use crate::technique::{trace_geometry_cost, OnceCost, RenderError, Setup, Timed};
use crate::REF_BINDING_UNIFORMS;

/// What an oracle binds: the reference's geometry and the tracer's uniforms.
pub struct Oracle {
    uniforms: Buffer,
    geometry: Rc<Timed<TraceGeometry>>,
}

impl Oracle {
    /// The exact tracer over `s`'s scene, its geometry shared through the technique cache.
    pub fn new(s: &mut Setup<'_>) -> Result<Oracle, RenderError> {
        let (ctx, scene) = (s.ctx, s.scene);
        let geometry = s.cache.get_or_try_insert_timed(TraceGeometry::key(scene), || TraceGeometry::new(ctx, scene))?;
        // Only the geometry's counts and the ray epsilon are read: no path is followed, so
        // max_depth and the cutoff do not matter.
        let uniforms = geometry.value.uniforms(scene, s.gpu, 1);
        let uniforms = Buffer::storage(ctx, "refraction_oracle_uniforms", std::slice::from_ref(&uniforms))?;
        Ok(Oracle { uniforms, geometry })
    }

    /// The cost paid once: the tracer's geometry, shared with `raytrace` through the cache.
    pub fn cost(&self) -> OnceCost {
        trace_geometry_cost(&self.geometry)
    }

    /// The tracer's set of the oracle variants (REF_BINDING_*, glsl/reference/trace.glsl),
    /// for `stages`. Its buffers are host-written once at creation: visible at submission.
    pub fn set(
        &self,
        ctx: &Arc<GpuContext>,
        gpu: &GpuScene,
        stages: vk::ShaderStageFlags,
        name: &str,
    ) -> GpuResult<BoundSet> {
        let b = Bindings::new(stages).storage(REF_BINDING_UNIFORMS, &self.uniforms);
        self.geometry.value.bind(gpu, b)?.build(ctx, name)
    }
}
