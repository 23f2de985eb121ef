//! Host-side mirrors of the GPU structs in glsl/include/frame.glsl. `#[repr(C)]` + bytemuck,
//! only vec4-sized members so std140 and std430 agree, and compile-time size checks.
use bytemuck::{Pod, Zeroable};

use crate::MAX_LIGHTS;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub checker_uv: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<Vertex>() == 32);

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 4],
    pub intensity: [f32; 4],
    pub shadow: [f32; 4],
    pub origin: [f32; 4],
    pub view_proj: [[f32; 4]; 4],
}
const _: () = assert!(std::mem::size_of::<GpuLight>() == 128);

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view: [[f32; 4]; 4],
    pub proj: [[f32; 4]; 4],
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub inv_view: [[f32; 4]; 4],
    pub camera_position: [f32; 4],
    pub clip: [f32; 4],
    pub viewport: [f32; 4],
    pub env_sh: [[f32; 4]; 9],
    pub info: [u32; 4],
    pub lights: [GpuLight; MAX_LIGHTS as usize],
}
const _: () =
    assert!(std::mem::size_of::<FrameUniforms>() == 5 * 64 + 3 * 16 + 9 * 16 + 16 + 128 * MAX_LIGHTS as usize);

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuMaterial {
    pub albedo_a: [f32; 4],
    pub albedo_b: [f32; 4],
    pub spec_a: [f32; 4],
    pub spec_b: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuMaterial>() == 64);

/// Push constants of the shadow pass (glsl/shadow/shadow.vert).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadowPush {
    pub view_proj: [[f32; 4]; 4],
    pub light: [f32; 4],
    pub origin: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<ShadowPush>() <= 128);
