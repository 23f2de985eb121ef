//! The window's water animation on the GPU: each frame, glsl/common/heightfield.comp
//! evaluates every heightfield's waves at the new time and writes its vertices over its range
//! of the scene's vertex buffer, so the animation costs one dispatch instead of a scene
//! reload and a vertex upload.
//!
//! Only the vertices move. What is fitted to where things are (the shadow faces, impostor
//! rectangles, light frusta) stays as it was built for the loaded time; the window brings it
//! up to date with a full update when the animation stops.
use std::sync::Arc;

use glam::{Mat3, Mat4};

use crate::gpu::{vk, Access, Buffer, ComputePipeline, GpuContext};
use crate::graph::{Bindings, BoundSet, Frame};
use crate::scene::Scene;
use crate::{HEIGHTFIELD_BINDING_FIELDS, HEIGHTFIELD_BINDING_VERTICES, HEIGHTFIELD_BINDING_WAVES, WORKGROUP_2D};

use super::gpu_scene::GpuScene;
use super::RenderError;
use crate::shader_structs::{GpuHeightfield, HeightfieldPush};

pub const WATER_ANIMATION: &str = "water_animation";

pub struct HeightfieldAnimation {
    /// Per heightfield: its grid's cells (nx, nz).
    cells: Vec<[u32; 2]>,
    _fields: Buffer,
    _waves: Buffer,
    set: BoundSet,
    pipeline: ComputePipeline,
}

impl HeightfieldAnimation {
    /// The animation of `scene`'s heightfields over `gpu`'s vertices; `None` without one.
    pub fn new(ctx: &Arc<GpuContext>, scene: &Scene, gpu: &GpuScene) -> Result<Option<Self>, RenderError> {
        let (mut fields, mut waves, mut cells) = (Vec::new(), Vec::new(), Vec::new());
        for (o, draw) in scene.objects.iter().zip(&gpu.draws) {
            let Some(h) = &o.heightfield else { continue };
            let [nx, nz] = h.cells();
            fields.push(GpuHeightfield {
                transform: h.transform.to_cols_array_2d(),
                normal_matrix: Mat4::from_mat3(Mat3::from_mat4(h.transform).inverse().transpose()).to_cols_array_2d(),
                center: h.center.extend(0.0).to_array(),
                size_cells: [h.size.x, h.size.y, nx as f32, nz as f32],
                ranges: [draw.vertex_offset as u32, (waves.len() / 2) as u32, h.waves.len() as u32, 0],
            });
            for w in &h.waves {
                waves.push([w.amplitude, w.kx, w.kz, w.omega]);
                waves.push([w.phase, 0.0, 0.0, 0.0]);
            }
            cells.push([nx, nz]);
        }
        if fields.is_empty() {
            return Ok(None);
        }
        waves.push([0.0; 4]);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let field_buffer = Buffer::with_data(ctx, "heightfield_fields", &fields, storage)?;
        let wave_buffer = Buffer::with_data(ctx, "heightfield_waves", &waves, storage)?;
        // The vertices are not tracked by the frame graph: the pass orders itself (`record`).
        let set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .storage(HEIGHTFIELD_BINDING_FIELDS, &field_buffer)
            .storage(HEIGHTFIELD_BINDING_WAVES, &wave_buffer)
            .storage(HEIGHTFIELD_BINDING_VERTICES, &gpu.vertices)
            .build(ctx, WATER_ANIMATION)?;
        let push = std::mem::size_of::<HeightfieldPush>() as u32;
        let pipeline =
            ComputePipeline::new(ctx, WATER_ANIMATION, "common/heightfield.comp", &[set.layout()], push, &[])?;
        Ok(Some(HeightfieldAnimation { cells, _fields: field_buffer, _waves: wave_buffer, set, pipeline }))
    }

    /// Record the pass that moves every heightfield's vertices to `time`. The draws read the
    /// vertices without declaring them to the frame graph, so the pass orders itself against
    /// them on both sides: after the previous frame's reads, before this frame's.
    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, vertices: &'a Buffer, time: f32) {
        frame.pass(WATER_ANIMATION).record(move |cmd| {
            cmd.buffer_barrier(vertices, Access::VertexData, Access::ComputeWrite);
            cmd.bind_compute(&self.pipeline, &[self.set.set()]);
            for (field, [nx, nz]) in self.cells.iter().enumerate() {
                cmd.push_compute(&self.pipeline, &HeightfieldPush { field: field as u32, time });
                cmd.dispatch((nx + 1).div_ceil(WORKGROUP_2D), (nz + 1).div_ceil(WORKGROUP_2D), 1);
            }
            cmd.buffer_barrier(vertices, Access::ComputeWrite, Access::VertexData);
        });
    }
}
