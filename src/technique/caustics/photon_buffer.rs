//! Photon-buffer caustics: Hu & Qin 2007, "Interactive Approximate Rendering of
//! Reflections, Refractions, and Caustics", section 3
//! (../shared/papers/hu-qin2007-reflections-refractions-caustics.md).
//!
//! Five graph passes (six with `merge_texels`), each timed under its own name:
//!
//! 1. `photon_buffer_refractors`: the specular objects seen from each light, front and back
//!    surfaces with positions and normals (the refractor layers caustics mapping renders too,
//!    `caustics_map::RefractorLayers`), at the photon buffer's resolution.
//! 2. `photon_buffer_receivers` (§2.2.2, TEX_DEPTH_i): each receiver OBJ_i rendered with its
//!    rectangle's parallel projection, storing its signed distance from RECT_i's plane along
//!    O_R O_i (the shadow pass's shaders with the rectangle as a directional "light").
//! 3. `photon_buffer` (§3.1, Fig. 19b): "we render the reflector/refractor from the light
//!    position"; each pixel is one photon. glsl/caustics/photon_buffer.frag refracts through
//!    both interfaces (caustics mapping's `exit = "march"`, glsl/caustics/light_path.glsl:
//!    Hu & Qin build the photon buffer with their own refraction, §3 "using the method to
//!    implement reflection and refraction", whose d_T search needs no precomputed d_N, so
//!    Wyman's d_V/d_N, Shah et al.'s estimator, is not offered here) or reflects, intersects the ray with the receiver
//!    rectangles RECT_i (§2.2.1, Fig. 13), moves the nearest hit onto the receiver itself
//!    with §2.2.2's iterative depth correction (Fig. 16; `correction_iterations`), and writes
//!    (u, v, k) there, k = i + 1, k = 0 for no photon, plus the photon's power (see below).
//!    §3.1 writes the rectangle's own (u, v); but §3.3 looks the caustic up by projecting the
//!    receiver's position in parallel onto RECT_k, so a receiver off its rectangle's plane
//!    (a wall, a box, anything tilted from O_R O_i) would show the photon displaced along its
//!    ray. The correction is the paper's own tool for exactly that mismatch (§2.2.2).
//! 4. `photon_buffer_scatter` (§3.2): the filtered caustic textures TEX_CAUSTICS_i, one layer
//!    of a 2D array per rectangle, c(u, v) = s sum_{i,j=-k..k} p(u+i, v+j)
//!    sqrt(1 + 2k^2 - (i^2 + j^2)). The paper reads the photon buffer back (glReadPixels),
//!    counts on the CPU, then filters every texel; here, all on the GPU as the paper suggests,
//!    one point of (2k + 1)^2 texels is drawn per photon-buffer pixel, its vertex shader
//!    fetches (u, v, k) (vertex texture fetch) and centres the point on texel (u, v) of
//!    layer k - 1, and additive blending sums each photon's kernel
//!    (glsl/caustics/photon_scatter.glsl): the filter is linear in the counts, so this is the
//!    same c, for work in proportion to the photons instead of to every texel.
//!    With `merge_texels` (the default), `photon_buffer_bin` first sums the photons of each
//!    texel (glsl/caustics/photon_bin.comp, in fixed point by integer atomics, so that the
//!    sums do not depend on the order the device adds them in) and the scatter pass draws one point
//!    per texel reached, with the sum: a photon's kernel depends only on its texel, so this is
//!    the same c again, for work in proportion to the texels the photons reach. A CPU device
//!    pays about 0.6 us to set up each point whatever its size, and a lens focuses many
//!    photons into one texel (caustic_sphere: 12 156 photons, 672 texels): the scatter went
//!    from 8.9 ms to 1.6 ms plus 0.8 ms of binning at 512^2 (docs/BENCHMARKS.md).
//!
//! Deferred shading then looks the caustic up (§3.3, Fig. 23): the receiver's position is
//! projected with its rectangle's parallel projection into TEX_CAUSTICS_i
//! (glsl/shading/deferred.frag, `photon_caustic`).
//!
//! Units (`render.photon_buffer.normalization`): the paper counts photons and scales the
//! filtered count by an arbitrary s ("paper"). The default, "physical", gives each photon its
//! share of the light's flux (the light's intensity times the pixel's solid angle, or its
//! irradiance times the pixel's area: the photon buffer is a uniform sampling of the light's
//! view of the objects) times its Fresnel and Beer-Lambert weights, divides the kernel by its
//! sum so that the filter conserves energy, and divides by a texel's area on the rectangle:
//! irradiance in W/m^2, which `prism compare` can hold against the reference.
//!
//! The rectangles: the receivers (the diffuse objects only: a mirror or conductor shows no
//! caustic) as §2.2.1 builds them, a square of side
//! 2 d_i centred at the object's centre O_i (mean of its vertices), perpendicular to O_R O_i
//! (O_R: the mean of the specular objects' vertices), with the parallel projection from O_R
//! along O_R O_i of glOrtho(-d_i, d_i, -d_i, d_i, near, far): the nearby-geometry impostors'
//! rectangles (src/technique/refraction/nearby_impostors.rs, `rect_for`), see `receiver_rectangles`.
use std::sync::Arc;

use bytemuck::Zeroable;

use crate::frame::gpu_scene::Draw;
use crate::frame::targets::DEPTH_FORMAT;
use crate::gpu::{
    vk, Access, Blend, Buffer, Clear, ComputePipeline, DepthState, GpuContext, GpuResult, GraphicsPipeline,
    GraphicsPipelineDesc, Image, ImageDesc, ImageViewKind, RenderTarget, Sampler, SamplerDesc, Spec,
};
use crate::graph::{Bindings, BoundSet, Frame, FrameGraph, ImageId};
use crate::scene::techniques::{PhotonBufferParams, PhotonNormalization};
use crate::scene::{is_grey, Light, Material, Scene};
pub use crate::shader_structs::GpuPhotonRect;
use crate::shader_structs::{GpuCausticFace, PhotonBufferPush, PhotonScatterPush, ShadowPush};
use crate::technique::baseline::shadow_map::FAR_DISTANCE;
use crate::technique::caustics::caustics_map::{is_specular, refractor_bindings, RefractorLayers};
use crate::technique::refraction::nearby_impostors::{receiver_objects, rect_for};
use crate::technique::{
    caustic_objects, in_stage, list, params, record_kept, tables_and_placement, FrameInputs, Inputs, PlannedPass,
    Regeneration, Registration, RenderError, Setup, Stage, Technique,
};
use crate::{
    CAUSTIC_BINDING_FACES, CAUSTIC_BINDING_MATERIALS, LIGHT_DIRECTIONAL, MAX_NEARBY_RECTS,
    PHOTON_BINDING_RECEIVER_DEPTH, PHOTON_BINDING_RECTS, PHOTON_PAPER, PHOTON_PHYSICAL,
};

/// Photon buffer and caustic textures: 32-bit float, so that counts stay exact to 2^24
/// photons per texel and (u, v) resolves far below a texel of the largest texture.
pub const PHOTON_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub const PHOTON_BUFFER_REFRACTORS: &str = "photon_buffer_refractors";
pub const PHOTON_BUFFER_RECEIVERS: &str = "photon_buffer_receivers";
pub const PHOTON_BUFFER: &str = "photon_buffer";
pub const PHOTON_BUFFER_BIN: &str = "photon_buffer_bin";
pub const PHOTON_BUFFER_SCATTER: &str = "photon_buffer_scatter";

/// `render.caustics = "photon_buffer"`, parameters `[render.photon_buffer]`.
/// Built from its settings, from where things are, and, for the texel sums' channels, from
/// whether the photons are grey (a material value can change that without a rebuild).
pub const TECHNIQUE: Registration = Registration {
    key: "caustics = \"photon_buffer\"",
    plan,
    create: |s| Ok(Box::new(PhotonBufferPass::new(s)?)),
    inputs: |scene| {
        let inputs = tables_and_placement(scene, &["photon_buffer"]);
        Inputs { settings: format!("{} grey photons {}", inputs.settings, grey_photons(scene)), ..inputs }
    },
};

fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let Some((diffuse, specular)) = caustic_objects(scene, "photon_buffer") else {
        return Vec::new();
    };
    let merged = PhotonBufferParams::from_settings(&scene.render).is_ok_and(|p| p.merge_texels);
    let bin = merged.then(|| {
        PlannedPass::new(
            PHOTON_BUFFER_BIN,
            "photons summed per caustic texel before the filter (render.photon_buffer.merge_texels; empty on a \
             device without vertex-shader stores)",
        )
    });
    let passes = [
        PlannedPass::new(
            PHOTON_BUFFER_REFRACTORS,
            format!("positions and normals of the specular {} seen from the light(s)", list(&specular)),
        ),
        PlannedPass::new(
            PHOTON_BUFFER_RECEIVERS,
            format!("depth of the receivers {} along their rectangles' projections (§2.2.2)", list(&diffuse)),
        ),
        PlannedPass::new(
            PHOTON_BUFFER,
            format!(
                "photons through {} onto the rectangles of the receivers {} (render.caustics = \"photon_buffer\")",
                list(&specular),
                list(&diffuse)
            ),
        ),
    ]
    .into_iter()
    .chain(bin)
    .chain([PlannedPass::new(
        PHOTON_BUFFER_SCATTER,
        format!("photons filtered (Hu & Qin 2007 §3.2) into the caustic textures of {}", list(&diffuse)),
    )]);
    in_stage(Stage::Caustics, passes)
}

impl Technique for PhotonBufferPass {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        if !self.regeneration.rendering() {
            let mut passes = vec![PHOTON_BUFFER_REFRACTORS, PHOTON_BUFFER_RECEIVERS, PHOTON_BUFFER];
            if self.params.merge_texels {
                passes.push(PHOTON_BUFFER_BIN);
            }
            passes.push(PHOTON_BUFFER_SCATTER);
            return record_kept(frame, &passes);
        }
        let (scene, caustics) = (inputs.scene, inputs.photon_caustics);
        self.refractors.record(frame, scene);

        let (size, rects) = (self.params.size, caustics.count);
        frame
            .pass(PHOTON_BUFFER_RECEIVERS)
            .write(self.receiver_depth.1, Access::ColorAttachment)
            .write(self.receiver_zbuffer.1, Access::DepthAttachment)
            .record(move |cmd| {
                for (i, (push, draw)) in self.receiver_draws.iter().enumerate() {
                    cmd.in_target(
                        &self.receiver_target,
                        i,
                        &[Clear::Color([FAR_DISTANCE; 4]), Clear::Depth(1.0)],
                        |cmd| {
                            cmd.bind_graphics(&self.receiver_pipeline, &[]);
                            cmd.push_graphics(&self.receiver_pipeline, push);
                            cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                            cmd.draw_indexed(draw.index_count, draw.first_index, draw.vertex_offset);
                        },
                    );
                }
            });
        let iterations = self.params.correction_iterations;
        frame
            .pass(PHOTON_BUFFER)
            .uses(&self.photon_set)
            .write(self.photons.1, Access::ColorAttachment)
            .write(self.flux.1, Access::ColorAttachment)
            .record(move |cmd| {
                for s in 0..self.faces {
                    let clears = [Clear::Color([0.0; 4]), Clear::Color([0.0; 4])];
                    cmd.in_target(&self.photon_target, s as usize, &clears, |cmd| {
                        cmd.bind_graphics(&self.photon_pipeline, &[self.photon_set.set()]);
                        cmd.push_graphics(
                            &self.photon_pipeline,
                            &PhotonBufferPush { info: [s, size, rects, iterations] },
                        );
                        cmd.draw(3, 1);
                    });
                }
            });

        if self.params.merge_texels {
            // Planned with the setting; empty where the device cannot merge (see `bins`).
            match (&self.bins, self.scatter_pushes.first()) {
                (Some(b), Some(push)) => frame.pass(PHOTON_BUFFER_BIN).uses(&b.set).record(move |cmd| {
                    cmd.compute(&b.pipeline, &[b.set.set()], push, [b.groups, 1, 1]);
                }),
                _ => frame.pass(PHOTON_BUFFER_BIN).record(|_| {}),
            }
        }
        frame.pass(PHOTON_BUFFER_SCATTER).uses(&self.scatter_set).write(caustics.id, Access::ColorAttachment).record(
            move |cmd| {
                for (i, push) in self.scatter_pushes.iter().enumerate() {
                    cmd.in_target(&self.scatter_target, i, &[Clear::Color([0.0; 4])], |cmd| {
                        cmd.bind_graphics(&self.scatter_pipeline, &[self.scatter_set.set()]);
                        cmd.push_graphics(&self.scatter_pipeline, push);
                        cmd.draw(size * size * self.faces, 1);
                    });
                }
            },
        );
    }

    fn kept(&mut self) -> Option<&mut Regeneration> {
        Some(&mut self.regeneration)
    }
}

/// Hu & Qin 2007 §2.2.1 (Fig. 12): RECT_i for the diffuse objects OBJ_i seen from O_R, as
/// the nearby-geometry impostors build them (src/technique/refraction/nearby_impostors.rs: same O_i, d_i,
/// square, up vector and parallel projection; at most MAX_NEARBY_RECTS, the nearest first).
/// O_R is the mean of the vertices of every specular object (dielectric, mirror or
/// conductor): caustics also form by reflection (metal_ring), which nearby_impostors' O_R
/// (dielectrics only) does not cover.
pub fn receiver_rectangles(scene: &Scene) -> Vec<GpuPhotonRect> {
    let (mut sum, mut n) = (glam::DVec3::ZERO, 0usize);
    for o in scene.objects.iter().filter(|o| is_specular(&scene.materials[o.material])) {
        sum += o.mesh.positions.iter().map(|v| v.as_dvec3()).sum::<glam::DVec3>();
        n += o.mesh.positions.len();
    }
    if n == 0 {
        return Vec::new();
    }
    // "The average value of object's vertices is used in our implementation" (Fig. 13).
    let o_r = (sum / n as f64).as_vec3();
    let (kept, _) = receiver_objects(scene, o_r);
    let mut rects = Vec::new();
    for i in kept {
        if let Some(r) = rect_for(scene, i, o_r, rects.len() as u32) {
            rects.push(GpuPhotonRect {
                view_proj: r.view_proj.to_cols_array_2d(),
                axis: [r.axis.x, r.axis.y, r.axis.z, r.half_size],
                centre: [r.center.x, r.center.y, r.center.z, r.half_size],
                object: [r.object as u32, 0, 0, 0],
            });
        }
    }
    rects
}

/// The sphere the photon buffer's frustum is fitted to: centred at the mean of the specular
/// objects' vertices, through the farthest vertex. Tighter than caustics mapping's sphere
/// around their bounding box (sqrt(3) times a ball's radius), so that the refractor fills
/// the photon buffer ("render the reflector/refractor from the light position", §3.1) and
/// about three times as many of its pixels are photons on caustic_sphere.
fn tight_bounds(scene: &Scene) -> (glam::Vec3, f32) {
    let specular = || scene.objects.iter().filter(|o| is_specular(&scene.materials[o.material]));
    let (mut sum, mut n) = (glam::DVec3::ZERO, 0usize);
    for o in specular() {
        sum += o.mesh.positions.iter().map(|v| v.as_dvec3()).sum::<glam::DVec3>();
        n += o.mesh.positions.len();
    }
    let c = (sum / n.max(1) as f64).as_vec3();
    let r = specular().flat_map(|o| o.mesh.positions.iter()).map(|p| p.distance(c)).fold(0.0f32, f32::max);
    (c, r.max(1e-6))
}

/// The filtered caustic textures and the rectangles, bound in the frame set (set 0,
/// BINDING_PHOTON_CAUSTICS / BINDING_PHOTON_RECTS): a 1x1 cleared stand-in and one zero
/// rectangle when the scene has no photon-buffer caustics.
pub struct PhotonCaustics {
    pub textures: Image,
    pub id: ImageId,
    pub rects: Buffer,
    /// Receiver rectangles (0: the stand-in).
    pub count: u32,
    /// PHOTON_PHYSICAL or PHOTON_PAPER.
    pub mode: u32,
    rect_data: Vec<GpuPhotonRect>,
}

impl PhotonCaustics {
    pub fn new(
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        scene: &Scene,
        params: Option<&PhotonBufferParams>,
    ) -> GpuResult<Self> {
        use vk::ImageUsageFlags as U;
        let rect_data = if params.is_some() { receiver_rectangles(scene) } else { Vec::new() };
        let count = rect_data.len() as u32;
        let size = match params {
            Some(p) if count > 0 => p.texture_size,
            _ => 1,
        };
        let textures = Image::new(
            ctx,
            &ImageDesc {
                name: "photon_caustics".into(),
                format: PHOTON_FORMAT,
                width: size,
                height: size,
                layers: count.max(1),
                usage: U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_DST | U::TRANSFER_SRC,
                view: ImageViewKind::D2Array,
            },
        )?;
        // MAX_NEARBY_RECTS records, as the frame set's uniform block declares them
        // (glsl/include/frame.glsl); the photon pass binds the same buffer as storage.
        let mut data = rect_data.clone();
        data.resize(MAX_NEARBY_RECTS as usize, GpuPhotonRect::zeroed());
        let usage = vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER;
        let rects = Buffer::with_data(ctx, "photon_rects", &data, usage)?;
        let id = graph.register_image(&textures);
        // Defined contents ("no caustic") and the layout the shaders expect.
        ctx.one_shot(|cmd| {
            graph.access_now(cmd, &[(id, Access::TransferWrite)], &[]);
            cmd.clear_color_image(&textures, [0.0; 4]);
            graph.access_now(cmd, &[(id, Access::FragmentSampled)], &[]);
        })?;
        let mode = match params.map(|p| p.normalization) {
            Some(PhotonNormalization::Paper) => PHOTON_PAPER,
            _ => PHOTON_PHYSICAL,
        };
        Ok(PhotonCaustics { textures, id, rects, count, mode, rect_data })
    }

    pub fn rectangles(&self) -> &[GpuPhotonRect] {
        &self.rect_data
    }
}

pub struct PhotonBufferPass {
    /// The caustic maps are rendered when something changed.
    regeneration: Regeneration,
    params: PhotonBufferParams,
    refractors: RefractorLayers,
    // §2.2.2 TEX_DEPTH_i: one framebuffer per rectangle, and per rectangle its projection
    // and its receiver's draw.
    /// Signed distance of each receiver from its rectangle's plane (R32F), one layer each.
    pub receiver_depth: (Image, ImageId),
    receiver_zbuffer: (Image, ImageId),
    receiver_target: RenderTarget,
    receiver_pipeline: GraphicsPipeline,
    receiver_draws: Vec<(ShadowPush, Draw)>,
    // §3.1 photon buffer: one framebuffer per source face.
    photon_target: RenderTarget,
    photon_set: BoundSet,
    photon_pipeline: GraphicsPipeline,
    /// (u, v, k, 0) and the photons' power (rgb), one layer per source face.
    pub photons: (Image, ImageId),
    pub flux: (Image, ImageId),
    faces: u32,
    // §3.2 counting and filter: one framebuffer per rectangle into the caustic textures, and
    // its push constants.
    scatter_target: RenderTarget,
    scatter_set: BoundSet,
    scatter_pipeline: GraphicsPipeline,
    scatter_pushes: Vec<PhotonScatterPush>,
    /// The photons summed per texel before the filter (`merge_texels` on a device that can).
    bins: Option<TexelSums>,
    _faces: Buffer,
    _sampler: Sampler,
}

impl PhotonBufferPass {
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let params = params("photon_buffer", PhotonBufferParams::from_settings(&s.scene.render))?;
        use vk::ImageUsageFlags as U;
        let (ctx, scene, gpu, caustics) = (s.ctx, s.scene, s.gpu, s.photon_caustics);
        let size = params.size;
        let bounds = tight_bounds(scene);
        let (refractors, faces, _) = RefractorLayers::new(s, PHOTON_BUFFER_REFRACTORS, size, bounds, false)?;
        let graph = &mut *s.graph;
        let n_faces = faces.len() as u32;
        let faces_buffer = Buffer::storage(ctx, "photon_faces", &faces)?;
        let sampler = Sampler::new(ctx, "photon_nearest", SamplerDesc::NEAREST_CLAMP)?;
        let usage = U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC;

        // 0. TEX_DEPTH_i (§2.2.2): OBJ_i through RECT_i's parallel projection, at the caustic
        // textures' resolution, storing dot(x - O_i, O_R O_i) (shadow.frag's directional
        // distance with the rectangle's centre as the plane's origin). Cleared to
        // FAR_DISTANCE: no receiver along that line.
        let t = caustics.textures.desc.width;
        let n_rects = caustics.count;
        let receiver_depth = graph.image(
            ctx,
            &ImageDesc::square(
                "photon_receiver_depth",
                vk::Format::R32_SFLOAT,
                t,
                n_rects.max(1),
                ImageViewKind::D2Array,
                usage,
            ),
        )?;
        let receiver_zbuffer = graph.image(
            ctx,
            &ImageDesc::square(
                "photon_receiver_zbuffer",
                DEPTH_FORMAT,
                t,
                n_rects.max(1),
                ImageViewKind::D2Array,
                U::DEPTH_STENCIL_ATTACHMENT,
            ),
        )?;
        let receiver_target = RenderTarget::layered(
            ctx,
            PHOTON_BUFFER_RECEIVERS,
            &[&receiver_depth.0],
            Some(&receiver_zbuffer.0),
            true,
            n_rects,
        )?;
        let receiver_pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc::mesh(
                PHOTON_BUFFER_RECEIVERS,
                "shadow/shadow.vert",
                "shadow/shadow.frag",
                DepthState::LESS,
            ),
            &[],
            std::mem::size_of::<ShadowPush>() as u32,
            &receiver_target.pass,
        )?;
        let receiver_draws = caustics
            .rectangles()
            .iter()
            .map(|r| {
                let push = ShadowPush {
                    view_proj: r.view_proj,
                    light: [r.axis[0], r.axis[1], r.axis[2], LIGHT_DIRECTIONAL as f32],
                    origin: [r.centre[0], r.centre[1], r.centre[2], 0.0],
                };
                (push, gpu.draws[r.object[0] as usize])
            })
            .collect();

        let mut image = |name: &str, width: u32, layers: u32| {
            graph.image(ctx, &ImageDesc::square(name, PHOTON_FORMAT, width, layers, ImageViewKind::D2Array, usage))
        };

        // 1. The photon buffer: a full-screen triangle per source face.
        let photons = image("photon_buffer", size, n_faces)?;
        let flux = image("photon_buffer_flux", size, n_faces)?;
        let photon_target = RenderTarget::layered(ctx, PHOTON_BUFFER, &[&photons.0, &flux.0], None, true, n_faces)?;
        let mut photon_set = Bindings::new(vk::ShaderStageFlags::FRAGMENT)
            .storage(CAUSTIC_BINDING_FACES, &faces_buffer)
            .storage(CAUSTIC_BINDING_MATERIALS, &gpu.materials);
        for (binding, (image, id)) in refractor_bindings().into_iter().zip(&refractors.layers) {
            photon_set = photon_set.sampled(binding, image, &sampler).read(*id);
        }
        let photon_set = photon_set
            .storage(PHOTON_BINDING_RECTS, &caustics.rects)
            .sampled(PHOTON_BINDING_RECEIVER_DEPTH, &receiver_depth.0, &sampler)
            .read(receiver_depth.1)
            .build(ctx, PHOTON_BUFFER)?;
        let photon_pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                blend: &[Blend::Off, Blend::Off],
                ..GraphicsPipelineDesc::fullscreen(PHOTON_BUFFER, "caustics/photon_buffer.frag")
            },
            &[photon_set.layout()],
            std::mem::size_of::<PhotonBufferPush>() as u32,
            &photon_target.pass,
        )?;

        // 2. Counting and the filter: each photon's kernel (or each texel's, its photons
        // summed first) into the caustic textures, additively.
        let can_merge = ctx.info.vertex_stores && n_rects > 0;
        let bins = if params.merge_texels && can_merge {
            Some(TexelSums::new(ctx, graph, (&photons, &flux), &sampler, t, n_rects, grey_photons(scene))?)
        } else {
            None
        };
        let scatter_target =
            RenderTarget::layered(ctx, PHOTON_BUFFER_SCATTER, &[&caustics.textures], None, true, n_rects)?;
        let mut scatter_set = Bindings::new(vk::ShaderStageFlags::VERTEX)
            .sampled(0, &photons.0, &sampler)
            .read(photons.1)
            .sampled(1, &flux.0, &sampler)
            .read(flux.1);
        if let Some(b) = &bins {
            scatter_set = scatter_set.storage_image(2, &b.sums.0).access(b.sums.1, Access::VertexStorageWrite);
        }
        let scatter_set = scatter_set.build(ctx, PHOTON_BUFFER_SCATTER)?;
        let vertex_shader =
            if bins.is_some() { "caustics/photon_scatter_merged.vert" } else { "caustics/photon_scatter.vert" };
        let grey = [("GREY", Spec::U32(bins.as_ref().map_or(0, |b| u32::from(b.grey))))];
        let scatter_pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                vertex_shader,
                specialization: if bins.is_some() { &grey } else { &[] },
                topology: vk::PrimitiveTopology::POINT_LIST,
                blend: &[Blend::Additive],
                ..GraphicsPipelineDesc::fullscreen(PHOTON_BUFFER_SCATTER, "caustics/photon_scatter.frag")
            },
            &[scatter_set.layout()],
            std::mem::size_of::<PhotonScatterPush>() as u32,
            &scatter_target.pass,
        )?;
        // The kernel's weights sqrt(1 + 2k^2 - (i^2 + j^2)) over i, j = -k..k: W.
        let k = params.filter_k as i32;
        let weights: f32 =
            (-k..=k).flat_map(|j| (-k..=k).map(move |i| ((1 + 2 * k * k - (i * i + j * j)) as f32).sqrt())).sum();
        let step = fixed_point_step(&faces);
        let scatter_pushes = caustics
            .rectangles()
            .iter()
            .enumerate()
            .map(|(i, r)| {
                // A texel of TEX_CAUSTICS_i covers (2 d_i / T)^2 of the rectangle.
                let texel = 2.0 * r.axis[3] / t as f32;
                let scale = if caustics.mode == PHOTON_PAPER { params.filter_s } else { texel * texel };
                PhotonScatterPush {
                    info: [size, n_faces, i as u32 + 1, params.filter_k],
                    params: [scale, weights, t as f32, caustics.mode as f32],
                    sum_unit: [step, 0.0, 0.0, 0.0],
                }
            })
            .collect();

        Ok(PhotonBufferPass {
            regeneration: Regeneration::default(),
            params,
            refractors,
            receiver_depth,
            receiver_zbuffer,
            receiver_target,
            receiver_pipeline,
            receiver_draws,
            photon_target,
            photon_set,
            photon_pipeline,
            photons,
            flux,
            faces: n_faces,
            scatter_target,
            scatter_set,
            scatter_pipeline,
            scatter_pushes,
            bins,
            _faces: faces_buffer,
            _sampler: sampler,
        })
    }

    pub fn params(&self) -> &PhotonBufferParams {
        &self.params
    }
}

/// The power of one step of the texel sums' 64-bit fixed point (glsl/caustics/photon_bin.comp):
/// the brightest photon the faces can send, over 2^32. A photon's power is its light's
/// intensity times its texel's measure (glsl/caustics/light_path.glsl `texel_measure`, largest
/// at the face's centre: (2 t / G)^2) times weights that are at most 1 for physical materials
/// (Fresnel, absorption, reflectance). So a photon keeps a float's precision down to 2^-8 of
/// that bound, a texel holds 2^32 photons at it, and a photon up to 2^32 times brighter (a
/// mirror given a reflectance above 1) still fits. The step stays a normal float: for a light so
/// dim that the bound's 2^-32 would be subnormal it is the smallest normal float, and where the
/// bound overflows, every finite photon still fits in 2^32 steps.
fn fixed_point_step(faces: &[GpuCausticFace]) -> f32 {
    let brightest = faces
        .iter()
        .map(|f| {
            let texel = 2.0 * f.measure[1] / f.measure[2];
            f.intensity[..3].iter().fold(0f32, |m, &i| m.max(i)) * texel * texel
        })
        .fold(0f32, f32::max);
    let word = 2f32.powi(-32);
    (brightest * word).clamp(f32::MIN_POSITIVE, f32::MAX * word)
}

/// Whether every photon carries the same power in red, green and blue: every light is grey and
/// no specular object filters colour (a dielectric's absorption, a mirror's reflectance, a
/// conductor's eta and k equal in every channel; a dielectric's ior is taken at green,
/// glsl/caustics/photon_buffer.frag). The texel sums then keep one channel.
fn grey_photons(scene: &Scene) -> bool {
    scene.lights.iter().all(Light::is_grey)
        && scene.materials.iter().all(|m| match m {
            Material::Diffuse { .. } => true,
            Material::Mirror { reflectance } => is_grey(*reflectance),
            Material::Conductor { eta, k } => is_grey(*eta) && is_grey(*k),
            Material::Dielectric { absorption, .. } => is_grey(*absorption),
        })
}

/// `merge_texels`: per caustic texel, the sum of its photons' power (64-bit fixed point, two
/// R32UI words a channel, one channel for grey photons) and count, and its first photon's mark
/// (glsl/caustics/photon_sums.glsl), filled by the bin pass and read and emptied again by the
/// texel's point (glsl/caustics/photon_scatter.glsl), so they are zero between frames.
struct TexelSums {
    grey: bool,
    sums: (Image, ImageId),
    set: BoundSet,
    pipeline: ComputePipeline,
    groups: u32,
}

impl TexelSums {
    /// For `rects` caustic textures of `texels`^2, binning every pixel of the photon buffer.
    fn new(
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        (photons, flux): (&(Image, ImageId), &(Image, ImageId)),
        sampler: &Sampler,
        texels: u32,
        rects: u32,
        grey: bool,
    ) -> GpuResult<Self> {
        let d = &photons.0.desc;
        let photons_per_frame = d.width * d.height * d.layers;
        // photon_sums.glsl's SUM_LAYERS: two words per channel, the count, the first photon.
        let layers = if grey { 4 } else { 8 };
        use vk::ImageUsageFlags as U;
        let usage = U::STORAGE | U::TRANSFER_DST | U::TRANSFER_SRC;
        let desc = ImageDesc::square(
            "photon_texel_sums",
            vk::Format::R32_UINT,
            texels,
            layers * rects,
            ImageViewKind::D2Array,
            usage,
        );
        let sums = graph.image(ctx, &desc)?;
        ctx.one_shot(|cmd| {
            graph.access_now(cmd, &[(sums.1, Access::TransferWrite)], &[]);
            // The sums start at zero, and no texel has a photon.
            cmd.clear_color_image(&sums.0, [0.0; 4]);
        })?;
        let set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .sampled(0, &photons.0, sampler)
            .read(photons.1)
            .sampled(1, &flux.0, sampler)
            .read(flux.1)
            .storage_image(2, &sums.0)
            .access(sums.1, Access::ComputeWrite)
            .build(ctx, PHOTON_BUFFER_BIN)?;
        let pipeline = ComputePipeline::new(
            ctx,
            PHOTON_BUFFER_BIN,
            "caustics/photon_bin.comp",
            &[set.layout()],
            std::mem::size_of::<PhotonScatterPush>() as u32,
            &[("GREY", Spec::U32(u32::from(grey)))],
        )?;
        Ok(TexelSums { grey, sums, set, pipeline, groups: photons_per_frame.div_ceil(64) })
    }
}
