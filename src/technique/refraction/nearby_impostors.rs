//! Hu & Qin 2007, "Interactive Approximate Rendering of Reflections, Refractions, and
//! Caustics" (IEEE TVCG 13(1)), §2.2 and §2.2.1 (Figs. 12, 13): nearby geometry seen through
//! the refractor stands in as one textured square per object, its *impostor rectangle*.
//!
//! Initial pass (Fig. 13), on the CPU ([`nearby_layout`]):
//! - Every dielectric object is its own OBJ_R with its own *rectangle set* ([`NearbySet`]);
//!   O_R is the mean of its vertices ("the average value of object's vertices is used in our
//!   implementation").
//! - For each other object OBJ_i (diffuse, mirror, conductor or another dielectric): O_i = mean
//!   of its vertices, d_i = largest vertex distance from O_i; RECT_i is the square of side 2 d_i
//!   centred at O_i perpendicular to O_R O_i.
//! - TEX_i is OBJ_i rendered from O_R towards O_i with the parallel projection
//!   `glOrtho(-d_i, d_i, -d_i, d_i, near, far)`, with the same up vector as the rectangle, so
//!   that a point of RECT_i and its texel share (u, v): [`NearbyRect::view_proj`].
//!
//! Rendering pass ([`NearbyImpostors`], `refraction_hu_qin_nearby`): every TEX_i of every set
//! into one layer of one 2D array texture (RGBA32F; the rectangles of set s are the layers
//! `first_s .. first_s + count_s`, one uniform buffer holds every set's O_R and rectangles):
//! rgb = the object's shaded radiance (direct light with shadow maps + environment
//! irradiance, glsl/include/lighting.glsl, exactly as deferred shading computes it), a =
//! TEX_DEPTH_i as the *axial* distance dot(p - O_R, n_i) from O_R along the projection
//! direction n_i (linear in the ortho z of Fig. 16, in world units). Texels where no surface
//! was drawn hold the far plane's axial distance. The refraction pass picks the set of the
//! pixel's object by the G-buffer's object index (albedo.a).
//!
//! Recursion (§2.2.1, Fig. 24g; [`NearbyDesc::recursion_depth`]): "If OBJ_k in Fig. 12 is a
//! reflector or a refractor, we render TEX_k using the above method". A specular OBJ_k's TEX_k
//! shows it reflecting (mirror, conductor) or reflecting and refracting (dielectric) the
//! projection's view direction: the environment at level 0, at level n the impostors of level
//! n - 1 of OBJ_k's *own* rectangle set (which holds OBJ_R), so that OBJ_k needs a set of its
//! own even when it is a mirror (glsl/nearby/impostor_recursive.frag). One graph pass per level
//! ([`RECURSION_PASSES`]), ping-ponging between two arrays so that the last level lands in
//! [`NearbyImpostors::texture`]. Diffuse textures do not change between levels: level 0
//! renders them, [`COPY_PASS`] copies them into the other array, and the levels >= 1 render
//! only the specular ones. A dielectric TEX_k finds its exit point with §2.1's search in the
//! rectangle's projection (glsl/include/hu_qin_exit.glsl, shared with the main pass) on OBJ_k's
//! faces rendered there by [`BACK_PASS`]: `recursive_exit = "full"` renders the front and back
//! faces and runs Fig. 7's dividing-pixel search, Fig. 5's front/back test and Fig. 9's search;
//! `"back_facing"` (§4's acceleration) only the back faces and Fig. 9; `"bounding_sphere"`
//! (and wherever the search finds no face) uses where T1 leaves OBJ_k's bounding sphere
//! (O_k, d_k) (glsl/nearby/impostor_body.glsl).
//!
//! Limits (stated rules, not errors): at most [`MAX_NEARBY_RECTS`] rectangles per set; with
//! more objects the ones whose bounding spheres come closest to O_R are kept and the others
//! are seen through the environment map only (`prism passes` names them). At most
//! [`MAX_NEARBY_SETS`] sets: the dielectrics first (in scene order), then the specular objects
//! that recursion reaches; an object without a set sees the environment only (its refraction
//! in the main pass, its TEX_k at every level). Recursion depth at most [`MAX_RECURSION`].
//!
//! The photon-buffer caustics (Hu & Qin §3) use [`NearbyRect`], [`receiver_objects`] and
//! [`rect_for`] with their own O_R: keep those stable.
use crate::technique::scene_specialization;
use crate::technique::{record_kept, FrameInputs, Regeneration};
use std::sync::Arc;

use bytemuck::Zeroable;
use glam::{Mat4, Vec3};

use crate::frame::gpu_scene::GpuScene;
use crate::frame::targets::DEPTH_FORMAT;
use crate::gpu::{
    vk, Access, Buffer, Clear, DepthState, DescriptorSetLayout, GpuContext, GpuResult, GraphicsPipeline,
    GraphicsPipelineDesc, Image, ImageDesc, ImageViewKind, RenderTarget, Sampler, SamplerDesc, Spec, Specs,
};
use crate::graph::{Bindings, BoundSet, Frame, FrameGraph, ImageId};
use crate::scene::techniques::{NearbyLookup, RecursiveExit};
use crate::scene::{Material, Scene};
pub use crate::shader_structs::GpuNearbyRect;
use crate::shader_structs::{GpuNearbyHeader, NearbyImpostorPush};
use crate::{BINDING_NEARBY_BACK, BINDING_NEARBY_FRONT, BINDING_NEARBY_RECTS, BINDING_NEARBY_TEXTURE};
pub use crate::{MAX_NEARBY_RECTS, MAX_NEARBY_SETS};

/// The specialisation constant NEARBY_LOOKUP of glsl/include/nearby.glsl for `lookup`.
pub fn nearby_lookup_constant(lookup: NearbyLookup) -> u32 {
    match lookup {
        NearbyLookup::Paper => crate::NEARBY_LOOKUP_PAPER,
        NearbyLookup::Nearest => crate::NEARBY_LOOKUP_NEAREST,
    }
}

/// TEX_i (rgb radiance) and TEX_DEPTH_i (a: axial distance from O_R) in one layer.
pub const NEARBY_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// The ortho near and far planes sit this much beyond the bounding sphere (d_i), so that no
/// vertex is clipped and the cleared far value is never a surface's depth.
const DEPTH_MARGIN: f32 = 1.01;

/// One impostor rectangle RECT_i and the parallel projection of its texture TEX_i.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearbyRect {
    /// Index into `Scene::objects` of OBJ_i.
    pub object: usize,
    /// Layer of TEX_i in [`NearbyImpostors::texture`].
    pub layer: u32,
    /// O_i: mean of the object's vertices, the rectangle's centre.
    pub center: Vec3,
    /// Unit O_R -> O_i: the rectangle's normal and the direction of projection.
    pub axis: Vec3,
    /// Unit world direction in which the texture coordinate u grows (the camera's right).
    pub axis_u: Vec3,
    /// Unit world direction in which v grows (the "up vector" of Fig. 13; Vulkan's clip y).
    pub axis_v: Vec3,
    /// d_i: half the side of the square, the largest vertex distance from O_i.
    pub half_size: f32,
    /// Axial distances from O_R of the ortho near and far planes.
    pub near: f32,
    pub far: f32,
    /// World -> clip of `glOrtho(-d_i, d_i, -d_i, d_i, near, far)` looking from O_R at O_i:
    /// clip.xy * 0.5 + 0.5 = (u, v) of TEX_i, clip.z = (axial - near) / (far - near).
    pub view_proj: Mat4,
}

/// Where a ray meets a rectangle: distance along the (unit) ray and texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RectHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl NearbyRect {
    /// The square of side 2 `half_size` centred at O_i = `center`, perpendicular to O_R O_i,
    /// and the parallel projection from O_R towards O_i (Fig. 13).
    pub fn new(object: usize, layer: u32, origin_r: Vec3, center: Vec3, half_size: f32) -> Self {
        let to = center - origin_r;
        let dist = to.length();
        // O_i at O_R leaves O_R O_i undefined: look along -z (any direction is as good).
        let axis = if dist > 1e-6 * half_size { to / dist } else { -Vec3::Z };
        // The up vector shared by the rectangle and the texture: world y, or -z when the
        // projection looks (nearly) straight up or down.
        let up = if axis.y.abs() < 0.99 { Vec3::Y } else { -Vec3::Z };
        let axis_u = axis.cross(up).normalize();
        let axis_v = axis_u.cross(axis);
        let near = dist - DEPTH_MARGIN * half_size;
        let far = dist + DEPTH_MARGIN * half_size;
        let view = Mat4::look_at_rh(origin_r, origin_r + axis, axis_v);
        let proj = Mat4::orthographic_rh(-half_size, half_size, -half_size, half_size, near, far);
        NearbyRect { object, layer, center, axis, axis_u, axis_v, half_size, near, far, view_proj: proj * view }
    }

    /// Fig. 13's `intersect(startP, Ray, RECT_i, P_rect)` and `UV(P_rect, RECT_i)`: the hit of
    /// the ray `origin + t dir` (t > 0) with the square, or None when it misses the square, runs
    /// parallel to its plane or points away. glsl/include/nearby.glsl (`nearby_rect_hit`) is
    /// the same computation.
    pub fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<RectHit> {
        let cos = dir.dot(self.axis);
        // Parallel rays (and degenerate directions) never hit: no division by ~0.
        if cos.is_nan() || cos.abs() <= 1e-6 {
            return None;
        }
        let t = (self.center - origin).dot(self.axis) / cos;
        if !t.is_finite() || t <= 0.0 {
            return None;
        }
        let q = origin + t * dir - self.center;
        let (u, v) =
            (0.5 + q.dot(self.axis_u) / (2.0 * self.half_size), 0.5 + q.dot(self.axis_v) / (2.0 * self.half_size));
        ((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)).then_some(RectHit { t, u, v })
    }

    /// Fig. 16's projection of a point into TEX_DEPTH_i: (u, v, axial distance from O_R).
    pub fn project(&self, origin_r: Vec3, p: Vec3) -> Vec3 {
        let clip = self.view_proj * p.extend(1.0);
        Vec3::new(clip.x * 0.5 + 0.5, clip.y * 0.5 + 0.5, (p - origin_r).dot(self.axis))
    }

    /// The four corners, (u, v) = (0,0), (1,0), (1,1), (0,1).
    pub fn corners(&self) -> [Vec3; 4] {
        let (a, b) = (self.axis_u * self.half_size, self.axis_v * self.half_size);
        [self.center - a - b, self.center + a - b, self.center + a + b, self.center - a + b]
    }
}

/// O_i and d_i of an object: the mean of its vertices and the largest vertex distance from it.
pub fn object_center_extent(scene: &Scene, object: usize) -> Option<(Vec3, f32)> {
    let p = &scene.objects[object].mesh.positions;
    if p.is_empty() {
        return None;
    }
    let sum: glam::DVec3 = p.iter().map(|v| v.as_dvec3()).sum();
    let c = (sum / p.len() as f64).as_vec3();
    let d = p.iter().map(|v| v.distance(c)).fold(0.0, f32::max);
    Some((c, d))
}

fn is_dielectric(scene: &Scene, object: usize) -> bool {
    matches!(scene.materials[scene.objects[object].material], Material::Dielectric { .. })
}

/// Whether OBJ_k's texture shows it reflecting or refracting (§2.2.1's recursive case), so
/// that it needs a rectangle set of its own as a viewpoint.
fn is_specular(scene: &Scene, object: usize) -> bool {
    !scene.materials[scene.objects[object].material].is_diffuse()
}

/// The impostor rectangles around an eikonal volume (src/technique/eikonal/eikonal_nearby.rs):
/// every object but the dielectrics, nearest first (by the gap between O_R and their bounding
/// sphere), at most [`MAX_NEARBY_RECTS`]; and those left out by that limit. The refraction's
/// rectangle sets use [`set_objects`], the photon buffer's receivers [`receiver_objects`].
pub fn nearby_objects(scene: &Scene, origin_r: Vec3) -> (Vec<usize>, Vec<usize>) {
    nearest_first(scene, origin_r, |i| !is_dielectric(scene, i))
}

/// The photon-buffer caustics' receivers (Hu & Qin 2007 §3.2, "each rectangle that might
/// possibly receive photons"; src/technique/caustics/photon_buffer.rs): the diffuse objects
/// only, nearest first, at most [`MAX_NEARBY_RECTS`]; and those left out by that limit. A
/// mirror or conductor shows no caustic (deferred shading lights only diffuse surfaces with
/// it), so a rectangle for it would only cost its filter pass and steal photons.
pub fn receiver_objects(scene: &Scene, origin_r: Vec3) -> (Vec<usize>, Vec<usize>) {
    nearest_first(scene, origin_r, |i| scene.materials[scene.objects[i].material].is_diffuse())
}

/// The objects that get a rectangle in the set of OBJ_R = `viewer` (every object but OBJ_R
/// itself: diffuse ones, mirrors, conductors and the other dielectrics, §2.2.1), nearest first
/// (by the gap between O_R and their bounding sphere), at most [`MAX_NEARBY_RECTS`]; and those
/// left out by that limit.
pub fn set_objects(scene: &Scene, viewer: usize, origin_r: Vec3) -> (Vec<usize>, Vec<usize>) {
    nearest_first(scene, origin_r, |i| i != viewer)
}

/// The objects `include` accepts that have an extent, ordered by the gap between O_R and
/// their bounding sphere (ties by index): the first [`MAX_NEARBY_RECTS`] and the rest.
fn nearest_first(scene: &Scene, origin_r: Vec3, include: impl Fn(usize) -> bool) -> (Vec<usize>, Vec<usize>) {
    let mut all: Vec<(f32, usize)> = (0..scene.objects.len())
        .filter(|&i| include(i))
        .filter_map(|i| {
            object_center_extent(scene, i).filter(|(_, d)| *d > 0.0).map(|(c, d)| (c.distance(origin_r) - d, i))
        })
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut kept: Vec<usize> = all.into_iter().map(|(_, i)| i).collect();
    let dropped = kept.split_off(kept.len().min(MAX_NEARBY_RECTS as usize));
    (kept, dropped)
}

/// RECT_i for OBJ_i seen from O_R (Fig. 13, "Rendering Pass"), layer `layer`.
pub fn rect_for(scene: &Scene, object: usize, origin_r: Vec3, layer: u32) -> Option<NearbyRect> {
    let (center, half_size) = object_center_extent(scene, object)?;
    (half_size > 0.0).then(|| NearbyRect::new(object, layer, origin_r, center, half_size))
}

/// Another way to shade level 0 of the textures than glsl/nearby/impostor.frag (the
/// eikonal light volumes for the caustic under a volume, src/technique/eikonal/eikonal_nearby.rs): a
/// fragment shader including impostor_body.glsl with a third descriptor set (set 2, owned by
/// whose tracked resources level 0 reads) and its specialisation constants (ids from 6 on,
/// after impostor_body.glsl's 0..5).
pub struct ImpostorShading<'a> {
    pub fragment_shader: &'static str,
    pub set: BoundSet,
    pub specialization: Specs<'a>,
}

/// The rectangle set of one OBJ_R: its rectangles are `rects[first .. first + count]` of
/// [`NearbyLayout::rects`] (and the same layers of the texture array).
#[derive(Clone, Debug, PartialEq)]
pub struct NearbySet {
    /// Index into `Scene::objects` of OBJ_R.
    pub object: usize,
    /// O_R: the mean of OBJ_R's vertices.
    pub origin: Vec3,
    pub first: u32,
    pub count: u32,
    /// Objects left out of this set by [`MAX_NEARBY_RECTS`] (seen through the environment).
    pub dropped: Vec<usize>,
}

/// Every rectangle set of a scene, the rectangles, and the recursion levels they need.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NearbyLayout {
    pub sets: Vec<NearbySet>,
    /// All sets' rectangles; `NearbyRect::layer` is the index here.
    pub rects: Vec<NearbyRect>,
    /// Recursion levels beyond 0: `recursion_depth` (at most [`MAX_RECURSION`]) when a
    /// rectangle stands for a specular object, else 0 (nothing would change between levels).
    pub levels: u32,
    /// Specular objects that needed a set beyond [`MAX_NEARBY_SETS`] (environment only).
    pub without_set: Vec<usize>,
}

impl NearbyLayout {
    /// The set whose OBJ_R is `object`.
    pub fn set_of(&self, object: usize) -> Option<usize> {
        self.sets.iter().position(|s| s.object == object)
    }
}

/// The rectangle sets of `scene` (Fig. 13's initial pass, once per OBJ_R): one per dielectric
/// (the refraction pass looks them up), and with `recursion_depth` > 0 one per specular object
/// that has a rectangle in a set (its recursive TEX_k looks up its own set), in that order, at
/// most [`MAX_NEARBY_SETS`]. Empty without a dielectric.
pub fn nearby_layout(scene: &Scene, recursion_depth: u32) -> NearbyLayout {
    let mut viewers: Vec<usize> = (0..scene.objects.len()).filter(|&i| is_dielectric(scene, i)).collect();
    let mut layout = NearbyLayout::default();
    let mut next = 0;
    while next < viewers.len() {
        let viewer = viewers[next];
        next += 1;
        let Some((origin, extent)) = object_center_extent(scene, viewer) else { continue };
        if extent <= 0.0 {
            continue;
        }
        if layout.sets.len() == MAX_NEARBY_SETS as usize {
            layout.without_set.push(viewer);
            continue;
        }
        let (kept, dropped) = set_objects(scene, viewer, origin);
        let first = layout.rects.len() as u32;
        for i in kept {
            if let Some(r) = rect_for(scene, i, origin, layout.rects.len() as u32) {
                if recursion_depth > 0 && is_specular(scene, i) && !viewers.contains(&i) {
                    viewers.push(i);
                }
                layout.rects.push(r);
            }
        }
        let count = layout.rects.len() as u32 - first;
        layout.sets.push(NearbySet { object: viewer, origin, first, count, dropped });
    }
    if layout.rects.is_empty() {
        return NearbyLayout::default();
    }
    if layout.rects.iter().any(|r| is_specular(scene, r.object)) {
        layout.levels = recursion_depth.min(MAX_RECURSION);
    }
    layout
}

impl From<&NearbyRect> for GpuNearbyRect {
    fn from(r: &NearbyRect) -> Self {
        let v4 = |v: Vec3, w: f32| [v.x, v.y, v.z, w];
        GpuNearbyRect {
            view_proj: r.view_proj.to_cols_array_2d(),
            center: v4(r.center, r.half_size),
            axis: v4(r.axis, r.near),
            axis_u: v4(r.axis_u, r.far),
            axis_v: v4(r.axis_v, r.layer as f32),
        }
    }
}

/// Bytes of the uniform buffer `NearbyRects`: the header and MAX_NEARBY_SETS x
/// MAX_NEARBY_RECTS records, the rectangles first (the size glsl/include/nearby.glsl declares).
/// `see_through[i]`: rectangle i's TEX_i shows a dielectric refracting the environment only;
/// each set's `sets[k].w` holds those of its rectangles as bits (bit i - first), which
/// glsl/include/nearby.glsl's nearest lookup ranks after every other rectangle.
pub fn rect_buffer_bytes(layout: &NearbyLayout, see_through: &[bool]) -> Vec<u8> {
    let mut header = GpuNearbyHeader::zeroed();
    header.info = [layout.rects.len() as u32, layout.sets.len() as u32, 0, 0];
    for (k, set) in layout.sets.iter().enumerate().take(MAX_NEARBY_SETS as usize) {
        let bits = (0..set.count.min(MAX_NEARBY_RECTS))
            .filter(|&j| see_through.get((set.first + j) as usize).copied().unwrap_or(false))
            .fold(0u32, |b, j| b | 1 << j);
        header.sets[k] = [set.first, set.count, set.object as u32, bits];
        header.origins[k] = set.origin.extend(1.0).to_array();
    }
    let mut bytes = bytemuck::bytes_of(&header).to_vec();
    for r in &layout.rects {
        bytes.extend_from_slice(bytemuck::bytes_of(&GpuNearbyRect::from(r)));
    }
    let records = (MAX_NEARBY_SETS * MAX_NEARBY_RECTS) as usize;
    let size = std::mem::size_of::<GpuNearbyHeader>() + records * std::mem::size_of::<GpuNearbyRect>();
    bytes.resize(size.max(bytes.len()), 0);
    bytes
}

/// How the impostor textures are made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearbyDesc {
    /// Edge of each TEX_i in texels.
    pub resolution: u32,
    /// §2.2.1 recursion: 0 = mirrors, conductors and dielectrics in the textures reflect and
    /// refract the environment only; n = the impostors of level n - 1 of their own rectangle
    /// set (one extra pass per level).
    pub recursion_depth: u32,
    /// The lookup used by the recursive levels (as `[render.hu_qin]`'s).
    pub correction_iterations: u32,
    pub correction_tolerance: f32,
    pub seed_samples: u32,
    /// Which rectangle's surface the recursive levels' lookup keeps.
    pub lookup: NearbyLookup,
    /// A dielectric OBJ_k's second interface in its texture: §2.1's search on its front and
    /// back faces in the rectangle's projection ([`BACK_PASS`]), on its back faces only (§4),
    /// or its bounding sphere.
    pub exit: RecursiveExit,
    /// Fig. 7's halvings and Fig. 9's steps of that search (as the main pass's).
    pub search_steps: u32,
    pub max_iterations: u32,
}

/// The dielectric OBJ_k's back faces (and with `recursive_exit = "full"` their front faces) in
/// their rectangles' parallel projections (normal and axial depth), rendered with the textures
/// before level 0: the exit surfaces of §2.1's search.
pub const BACK_PASS: &str = "refraction_hu_qin_nearby_back";

/// Whether a rectangle of `layout` stands for a dielectric (whose texture refracts, so that
/// [`BACK_PASS`] renders its faces unless the exit is the bounding sphere).
pub fn has_dielectric_rect(scene: &Scene, layout: &NearbyLayout) -> bool {
    layout.rects.iter().any(|r| is_dielectric(scene, r.object))
}

/// With recursion levels: level 0's diffuse layers copied into the other array of the
/// ping-pong, with the textures. Diffuse TEX_i do not change between levels, so the levels >= 1
/// re-render only the specular layers (mirrors, conductors, dielectrics).
pub const COPY_PASS: &str = "refraction_hu_qin_nearby_copy";

/// Whether `layout` needs [`COPY_PASS`]: recursion levels and a diffuse rectangle.
pub fn needs_copy(scene: &Scene, layout: &NearbyLayout) -> bool {
    layout.levels > 0 && layout.rects.iter().any(|r| !is_specular(scene, r.object))
}

/// Passes of the recursion levels 1..=MAX_RECURSION (level 0 is `name` itself).
pub const RECURSION_PASSES: [&str; 3] =
    ["refraction_hu_qin_nearby_r1", "refraction_hu_qin_nearby_r2", "refraction_hu_qin_nearby_r3"];
/// Deepest recursion: each level is one more rendering of every texture.
pub const MAX_RECURSION: u32 = RECURSION_PASSES.len() as u32;

/// One array of textures (recursion levels ping-pong between two).
struct TextureArray {
    image: Image,
    id: ImageId,
    /// A framebuffer per layer.
    target: RenderTarget,
}

/// TEX_i / TEX_DEPTH_i of every rectangle, and the rectangle buffer the shading reads. The
/// paper renders the textures every frame (its "Rendering Pass": nothing is precomputed, so
/// the scene may change from frame to frame), and notes that a static scene needs them once
/// (§4): they are kept as [`Regeneration`] says.
pub struct NearbyImpostors {
    name: &'static str,
    /// The rectangle sets (one per OBJ_R) and all their rectangles.
    pub layout: NearbyLayout,
    /// Edge of each TEX_i in texels.
    pub resolution: u32,
    /// 2D array, one layer per rectangle (one cleared stand-in layer without rectangles): the
    /// last recursion level's.
    pub texture: Image,
    pub texture_id: ImageId,
    /// `NearbyRects` of glsl/include/nearby.glsl.
    pub rect_buffer: Buffer,
    /// Recursion levels beyond 0 actually rendered.
    pub levels: u32,
    /// The other array of the ping-pong (with recursion levels).
    other: Option<TextureArray>,
    /// A framebuffer per layer of `texture`.
    target: RenderTarget,
    _depth: Image,
    depth_id: ImageId,
    pipeline: GraphicsPipeline,
    /// The recursive levels' pipeline.
    recursive: Option<GraphicsPipeline>,
    _sampler: Sampler,
    /// Set 1 reading `texture` (level 0 binds it without reading the array), and with
    /// recursion levels one reading `other`.
    sets: BoundSet,
    _back: Image,
    back_id: ImageId,
    _front: Image,
    front_id: ImageId,
    back_pass: Option<BackPass>,
    draws: Vec<usize>,
    /// Per rectangle: OBJ_k reflects or refracts (recursive levels re-render it).
    specular: Vec<bool>,
    /// Layers of the diffuse rectangles: rendered at level 0 only, and copied into `other`.
    diffuse_layers: Vec<u32>,
    /// Per rectangle: OBJ_k's own set (u32::MAX: none).
    lookup_set: Vec<u32>,
    /// [`ImpostorShading`]'s set (level 0).
    extra: Option<BoundSet>,
    /// When the textures are rendered.
    pub regeneration: Regeneration,
}

/// [`BACK_PASS`]: the dielectric rectangles (indices into the rectangles), drawn into the
/// layers of the back faces and (full exit search) of the front faces.
struct BackPass {
    rects: Vec<usize>,
    back: (GraphicsPipeline, RenderTarget),
    front: Option<(GraphicsPipeline, RenderTarget)>,
}

/// The rectangles impostors are built over, and per rectangle whether its object is
/// specular and which set its object's own rectangles are (u32::MAX: none); `back`: the
/// rectangles whose dielectric back faces are rendered; `see_through`: per rectangle, whether
/// its texture shows a dielectric refracting the environment only (level 0 is the last
/// level), which the nearest lookup looks past ([`rect_buffer_bytes`]).
pub struct NearbyRects {
    layout: NearbyLayout,
    specular: Vec<bool>,
    lookup_set: Vec<u32>,
    back: Vec<usize>,
    see_through: Vec<bool>,
}

impl NearbyRects {
    /// No rectangles (the stand-in's).
    pub fn none() -> Self {
        NearbyRects {
            layout: NearbyLayout::default(),
            specular: Vec::new(),
            lookup_set: Vec::new(),
            back: Vec::new(),
            see_through: Vec::new(),
        }
    }

    /// One rectangle set around `origin` that belongs to no object (the eikonal volume's
    /// centre, src/technique/eikonal/eikonal_nearby.rs) over `objects`, without recursion or
    /// back faces (mirrors reflect the environment, dielectrics refract it): build it with
    /// `recursion_depth` 0 and the bounding-sphere exit.
    pub fn around(origin: Vec3, objects: &[usize], scene: &Scene) -> Self {
        let mut layout = NearbyLayout::default();
        for &i in objects.iter().take(MAX_NEARBY_RECTS as usize) {
            if let Some(r) = rect_for(scene, i, origin, layout.rects.len() as u32) {
                layout.rects.push(r);
            }
        }
        let dropped = objects.iter().skip(MAX_NEARBY_RECTS as usize).copied().collect();
        let count = layout.rects.len() as u32;
        layout.sets.push(NearbySet { object: usize::MAX, origin, first: 0, count, dropped });
        let n = layout.rects.len();
        // Without recursion every dielectric's texture refracts the environment only.
        let see_through = layout.rects.iter().map(|r| is_dielectric(scene, r.object)).collect();
        NearbyRects { layout, specular: vec![false; n], lookup_set: vec![u32::MAX; n], back: Vec::new(), see_through }
    }
}

impl NearbyImpostors {
    /// The rectangle sets of [`nearby_layout`] and their textures, made as `desc` says.
    pub fn with_desc(
        ctx: &Arc<GpuContext>,
        name: &'static str,
        desc: &NearbyDesc,
        scene: &Scene,
        gpu: &GpuScene,
        graph: &mut FrameGraph,
        frame_layout: &DescriptorSetLayout,
    ) -> GpuResult<Self> {
        let layout = nearby_layout(scene, desc.recursion_depth);
        // Every object has a draw (GpuScene uploads them all); a stale layout would index past it.
        debug_assert!(layout.rects.iter().all(|r| r.object < gpu.draws.len()), "impostor of an object without a draw");
        let specular = layout.rects.iter().map(|r| is_specular(scene, r.object)).collect();
        let lookup_set = layout.rects.iter().map(|r| layout.set_of(r.object).map_or(u32::MAX, |s| s as u32)).collect();
        // Each array holds every set's textures; lavapipe allocates at most 2 GiB at once.
        let bytes = layout.rects.len() as u64 * (desc.resolution as u64).pow(2) * 16;
        if bytes > 1 << 30 {
            return Err(crate::gpu::GpuError::Unsupported(format!(
                "the {} impostor textures of {} rectangle set(s) at render.hu_qin.impostor_resolution = {} need {} MiB \
                 per array (at most 1024): lower impostor_resolution",
                layout.rects.len(),
                layout.sets.len(),
                desc.resolution,
                bytes >> 20
            )));
        }
        let back: Vec<usize> = if desc.exit.uses_layers() {
            (0..layout.rects.len()).filter(|&i| is_dielectric(scene, layout.rects[i].object)).collect()
        } else {
            Vec::new()
        };
        // The refraction pass reads the last level's textures: with no level beyond 0 a
        // dielectric's TEX_k shows it refracting the environment only.
        let see_through = layout.rects.iter().map(|r| layout.levels == 0 && is_dielectric(scene, r.object)).collect();
        let rects = NearbyRects { layout, specular, lookup_set, back, see_through };
        Self::build(ctx, name, desc, rects, graph, frame_layout, None, &scene_specialization(scene))
    }

    /// No rectangles: a cleared 1x1 stand-in texture and an empty rectangle buffer, for
    /// shaders that bind them but are told (count 0) to use the environment only.
    pub fn stand_in(
        ctx: &Arc<GpuContext>,
        name: &'static str,
        _gpu: &GpuScene,
        graph: &mut FrameGraph,
        frame_layout: &DescriptorSetLayout,
    ) -> GpuResult<Self> {
        let desc = NearbyDesc {
            resolution: 1,
            recursion_depth: 0,
            correction_iterations: 0,
            correction_tolerance: 1e-3,
            seed_samples: 1,
            lookup: NearbyLookup::Paper,
            exit: RecursiveExit::BoundingSphere,
            search_steps: 8,
            max_iterations: 32,
        };
        Self::build(ctx, name, &desc, NearbyRects::none(), graph, frame_layout, None, &[])
    }

    /// Whether any rectangle exists (otherwise [`Self::record`] must not be called).
    pub fn is_empty(&self) -> bool {
        self.layout.rects.is_empty()
    }

    /// The impostors of `rects` (their textures, passes and buffers), shaded by `shading`
    /// when given; `scene_specs`: the scene's environment and lights for level 0's shading
    /// ([`crate::technique::scene_specialization`]).
    #[allow(clippy::too_many_arguments)] // The textures' resources and their two specialisations.
    pub fn build(
        ctx: &Arc<GpuContext>,
        name: &'static str,
        desc: &NearbyDesc,
        rects: NearbyRects,
        graph: &mut FrameGraph,
        frame_layout: &DescriptorSetLayout,
        shading: Option<ImpostorShading<'_>>,
        scene_specs: Specs<'_>,
    ) -> GpuResult<Self> {
        let NearbyRects { layout: nearby, specular, lookup_set, back: back_rects, see_through } = rects;
        let (rects, levels) = (&nearby.rects, nearby.levels);
        let layers_n = rects.len().max(1) as u32;
        let size = if rects.is_empty() { 1 } else { desc.resolution };
        use vk::ImageUsageFlags as U;
        let array = |label: String, format, size, layers, usage| {
            ImageDesc::square(&label, format, size, layers, ImageViewKind::D2Array, usage)
        };
        let array_usage = U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC | U::TRANSFER_DST;
        let (texture, texture_id) =
            graph.image(ctx, &array(format!("{name}_texture"), NEARBY_FORMAT, size, layers_n, array_usage))?;
        let depth_desc = array(format!("{name}_depth"), DEPTH_FORMAT, size, layers_n, U::DEPTH_STENCIL_ATTACHMENT);
        let (depth, depth_id) = graph.image(ctx, &depth_desc)?;
        // The dielectrics' back faces (a 1x1 stand-in when none is rendered), and their front
        // faces with the full exit search only (else a 1x1 stand-in).
        let with_back = !back_rects.is_empty();
        let with_front = with_back && desc.exit == RecursiveExit::Full;
        let faces = |label: String, rendered: bool| {
            let (size, layers) = if rendered { (size, layers_n) } else { (1, 1) };
            array(label, NEARBY_FORMAT, size, layers, U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_DST)
        };
        let (back, back_id) = graph.image(ctx, &faces(format!("{name}_back"), with_back))?;
        let (front, front_id) = graph.image(ctx, &faces(format!("{name}_front"), with_front))?;
        let stand_ins =
            [(&texture, texture_id, rects.is_empty()), (&back, back_id, !with_back), (&front, front_id, !with_front)];
        for (image, id, _) in stand_ins.into_iter().filter(|s| s.2) {
            // Nothing renders a stand-in: give it defined contents and the sampled layout.
            ctx.one_shot(|cmd| {
                graph.access_now(cmd, &[(id, Access::TransferWrite)], &[]);
                cmd.clear_color_image(image, [0.0; 4]);
                graph.access_now(cmd, &[(id, Access::FragmentSampled)], &[]);
            })?;
        }
        let other = if levels > 0 {
            Some(graph.image(ctx, &array(format!("{name}_texture_b"), NEARBY_FORMAT, size, layers_n, array_usage))?)
        } else {
            None
        };
        let rect_buffer = Buffer::with_data(
            ctx,
            &format!("{name}_rects"),
            &rect_buffer_bytes(&nearby, &see_through),
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        // A framebuffer per layer of `image` (the layer of each rectangle).
        let layered = |label: &str, image: &Image| {
            RenderTarget::layered(ctx, label, &[image], Some(&depth), true, image.layers())
        };
        let target = layered(name, &texture)?;
        let push_size = std::mem::size_of::<NearbyImpostorPush>() as u32;
        let pipeline_desc = |fragment_shader, specialization, cull| GraphicsPipelineDesc {
            cull,
            specialization,
            ..GraphicsPipelineDesc::mesh(name, "nearby/impostor.vert", fragment_shader, DepthState::LESS)
        };
        // Set 1 of both texture pipelines: the rectangles and the array of the level below
        // (read by the recursive levels only) and the dielectrics' back faces; one set
        // reading `texture`, one reading `other`.
        let sampler = Sampler::new(ctx, &format!("{name}_nearest"), SamplerDesc::NEAREST_CLAMP)?;
        let arrays = std::iter::once(&texture).chain(other.as_ref().map(|(image, _)| image));
        let set_reading = arrays.map(|array| {
            Bindings::new(vk::ShaderStageFlags::FRAGMENT)
                .uniform(BINDING_NEARBY_RECTS, &rect_buffer)
                .sampled(BINDING_NEARBY_TEXTURE, array, &sampler)
                .sampled(BINDING_NEARBY_BACK, &back, &sampler)
                .sampled(BINDING_NEARBY_FRONT, &front, &sampler)
        });
        let sets = Bindings::build_each(ctx, name, set_reading.collect())?;
        // Specialisation constants 0..5 of impostor_body.glsl (NEARBY_EXIT: 2 full, 1 back-facing,
        // 0 bounding sphere).
        let exit_mode = match desc.exit {
            _ if !with_back => 0,
            RecursiveExit::Full => 2,
            RecursiveExit::BackFacing => 1,
            RecursiveExit::BoundingSphere => 0,
        };
        let spec = [
            ("NEARBY_ITERATIONS", Spec::U32(desc.correction_iterations)),
            ("NEARBY_TOLERANCE", Spec::F32(desc.correction_tolerance)),
            ("NEARBY_SEEDS", Spec::U32(desc.seed_samples)),
            ("NEARBY_EXIT", Spec::U32(exit_mode)),
            ("NEARBY_LOOKUP", Spec::U32(nearby_lookup_constant(desc.lookup))),
            ("SEARCH_STEPS", Spec::U32(desc.search_steps)),
            ("MAX_ITERATIONS", Spec::U32(desc.max_iterations)),
        ];
        let shading_spec: Vec<_> = spec
            .iter()
            .chain(shading.as_ref().map_or(&[][..], |sh| sh.specialization))
            .chain(scene_specs)
            .copied()
            .collect();
        let mut layouts = vec![frame_layout, sets.layout()];
        layouts.extend(shading.as_ref().map(|sh| sh.set.layout()));
        let level_pipeline = |fragment_shader, specialization| {
            // Quads are one-sided; O_R may see either side.
            let desc = pipeline_desc(fragment_shader, specialization, vk::CullModeFlags::NONE);
            GraphicsPipeline::new(ctx, &desc, &layouts, push_size, &target.pass)
        };
        let pipeline = match &shading {
            Some(sh) => level_pipeline(sh.fragment_shader, &shading_spec[..])?,
            None => level_pipeline("nearby/impostor.frag", &spec[..])?,
        };
        let back_pass = if !with_back {
            None
        } else {
            // The nearest back faces. Meshes are wound counter-clockwise seen from outside
            // (src/technique/refraction/refractor_layers.rs), but this projection, unlike the camera's, is
            // not y-flipped: its back faces come out counter-clockwise, i.e. as the
            // pipeline's front faces, so BACK is the mode that culls the faces towards O_R.
            // The nearest front faces: the other cull mode (FRONT 1 flips the normal to face O_R).
            let faces_pass = |label: &str, image: &Image, side: Specs<'static>, cull| -> GpuResult<_> {
                let target = layered(label, image)?;
                let desc = pipeline_desc("nearby/impostor_back.frag", side, cull);
                let pipeline = GraphicsPipeline::new(ctx, &desc, &[frame_layout], push_size, &target.pass)?;
                Ok((pipeline, target))
            };
            let back_faces = faces_pass(BACK_PASS, &back, &[("FRONT", Spec::U32(0))], vk::CullModeFlags::BACK)?;
            let front_faces = if with_front {
                Some(faces_pass(
                    &format!("{BACK_PASS}_front"),
                    &front,
                    &[("FRONT", Spec::U32(1))],
                    vk::CullModeFlags::FRONT,
                )?)
            } else {
                None
            };
            Some(BackPass { rects: back_rects, back: back_faces, front: front_faces })
        };
        let (other, recursive) = match other {
            Some((image, id)) => {
                let target = layered(&format!("{name}_b"), &image)?;
                let pipeline = level_pipeline("nearby/impostor_recursive.frag", &spec[..])?;
                (Some(TextureArray { image, id, target }), Some(pipeline))
            }
            None => (None, None),
        };
        let draws = rects.iter().map(|r| r.object).collect();
        let diffuse_layers = rects.iter().zip(&specular).filter(|(_, &sp)| !sp).map(|(r, _)| r.layer).collect();
        Ok(NearbyImpostors {
            name,
            resolution: size,
            texture,
            texture_id,
            rect_buffer,
            levels,
            other,
            target,
            _depth: depth,
            depth_id,
            pipeline,
            recursive,
            _sampler: sampler,
            sets,
            _back: back,
            back_id,
            _front: front,
            front_id,
            back_pass,
            draws,
            specular,
            diffuse_layers,
            lookup_set,
            extra: shading.map(|sh| sh.set),
            layout: nearby,
            regeneration: Regeneration::default(),
        })
    }

    /// The graph passes [`Self::record`] adds, in order.
    fn pass_names(&self) -> Vec<&'static str> {
        let mut names = Vec::new();
        names.extend(self.back_pass.as_ref().map(|_| BACK_PASS));
        for level in 0..=self.levels {
            names.push(if level == 0 { self.name } else { RECURSION_PASSES[level as usize - 1] });
            if level == 0 && !self.diffuse_layers.is_empty() && self.other.is_some() {
                names.push(COPY_PASS);
            }
        }
        names
    }

    /// Render every TEX_i (after the shadow maps, which it reads through the frame set): level
    /// 0 as the graph pass `name`, then each recursion level l as `RECURSION_PASSES[l - 1]`.
    /// Levels ping-pong between two arrays so that the last one lands in `texture`. Diffuse
    /// layers are the same at every level: level 0 renders them, [`COPY_PASS`] copies them into
    /// the other array, and the levels >= 1 render the specular layers only.
    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        if !self.regeneration.rendering() {
            return record_kept(frame, &self.pass_names());
        }
        let (scene, frame_set, shadow_atlas) = (inputs.scene, inputs.frame_set, inputs.shadow_atlas);
        // Each rectangle's O_R: that of the set it belongs to.
        let mut origins = vec![[0.0; 4]; self.layout.rects.len()];
        for set in &self.layout.sets {
            for o in &mut origins[set.first as usize..(set.first + set.count) as usize] {
                *o = set.origin.extend(1.0).to_array();
            }
        }
        if let Some(bp) = &self.back_pass {
            let mut pass = frame.pass(BACK_PASS).write(self.back_id, Access::ColorAttachment);
            pass = pass.write(self.depth_id, Access::DepthAttachment);
            if bp.front.is_some() {
                pass = pass.write(self.front_id, Access::ColorAttachment);
            }
            let origins = origins.clone();
            pass.record(move |cmd| {
                for ((pipeline, target), i) in
                    std::iter::once(&bp.back).chain(&bp.front).flat_map(|p| bp.rects.iter().map(move |i| (p, i)))
                {
                    let r = &self.layout.rects[*i];
                    // Empty texels: no normal (the test for a surface), depth the far plane.
                    let clears = [Clear::Color([0.0, 0.0, 0.0, r.far]), Clear::Depth(1.0)];
                    cmd.in_target(target, r.layer as usize, &clears, |cmd| {
                        cmd.bind_graphics(pipeline, &[frame_set]);
                        cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                        let d = &scene.draws[self.draws[*i]];
                        let push = NearbyImpostorPush {
                            view_proj: r.view_proj.to_cols_array_2d(),
                            origin: origins[*i],
                            axis: r.axis.extend(0.0).to_array(),
                            material: [d.material, r.layer, self.lookup_set[*i], 0],
                            sphere: r.center.extend(r.half_size).to_array(),
                        };
                        cmd.push_graphics(pipeline, &push);
                        cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                    });
                }
            });
        }
        for level in 0..=self.levels {
            // Level `level` writes array (levels - level) % 2: 0 is `texture`, 1 `other`.
            let dst = ((self.levels - level) % 2) as usize;
            let (dst_id, dst_target) = match (dst, &self.other) {
                (1, Some(o)) => (o.id, &o.target),
                _ => (self.texture_id, &self.target),
            };
            let name = if level == 0 { self.name } else { RECURSION_PASSES[level as usize - 1] };
            let mut pass = frame.pass(name);
            pass = pass.write(dst_id, Access::ColorAttachment).write(self.depth_id, Access::DepthAttachment);
            pass = pass.read(self.back_id, Access::FragmentSampled).read(self.front_id, Access::FragmentSampled);
            if let Some(atlas) = shadow_atlas {
                pass = pass.read(atlas, Access::FragmentSampled);
            }
            if let (0, Some(set)) = (level, &self.extra) {
                pass = pass.uses(set);
            }
            let recursive = if level > 0 { self.recursive.as_ref() } else { None };
            if let (Some(_), Some(o)) = (recursive, &self.other) {
                pass = pass.read(if dst == 0 { o.id } else { self.texture_id }, Access::FragmentSampled);
            }
            let origins = origins.clone();
            pass.record(move |cmd| {
                for (i, r) in self.layout.rects.iter().enumerate() {
                    if level > 0 && !self.specular[i] {
                        // Kept from level 0 (rendered there or copied by COPY_PASS).
                        continue;
                    }
                    // Empty texels: TEX_DEPTH = the far plane (never a surface, see DEPTH_MARGIN).
                    let clears = [Clear::Color([0.0, 0.0, 0.0, r.far]), Clear::Depth(1.0)];
                    cmd.in_target(dst_target, r.layer as usize, &clears, |cmd| {
                        let pipeline = match recursive {
                            // Specular layers read the other array.
                            Some(rec) if self.specular[i] => {
                                cmd.bind_graphics(rec, &[frame_set, self.sets.sets()[1 - dst]]);
                                rec
                            }
                            // Level 0 reads no array: the set reading `texture` only fills set 1.
                            _ => {
                                match &self.extra {
                                    Some(set) => {
                                        cmd.bind_graphics(&self.pipeline, &[frame_set, self.sets.set(), set.set()])
                                    }
                                    None => cmd.bind_graphics(&self.pipeline, &[frame_set, self.sets.set()]),
                                }
                                &self.pipeline
                            }
                        };
                        cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                        let d = &scene.draws[self.draws[i]];
                        let push = NearbyImpostorPush {
                            view_proj: r.view_proj.to_cols_array_2d(),
                            origin: origins[i],
                            axis: r.axis.extend(0.0).to_array(),
                            material: [d.material, r.layer, self.lookup_set[i], 0],
                            sphere: r.center.extend(r.half_size).to_array(),
                        };
                        cmd.push_graphics(pipeline, &push);
                        cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                    });
                }
            });
            if level == 0 && !self.diffuse_layers.is_empty() {
                if let Some(o) = &self.other {
                    // Level 0 wrote array `dst`; the other array receives the diffuse layers
                    // that the levels writing it no longer render.
                    let (src, dst_image) = if dst == 0 { (&self.texture, &o.image) } else { (&o.image, &self.texture) };
                    let (src_id, copy_dst_id) =
                        if dst == 0 { (self.texture_id, o.id) } else { (o.id, self.texture_id) };
                    let pass = frame
                        .pass(COPY_PASS)
                        .read(src_id, Access::TransferRead)
                        .write(copy_dst_id, Access::TransferWrite);
                    pass.record(move |cmd| cmd.copy_image_layers(src, dst_image, &self.diffuse_layers));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(origin_r: Vec3, center: Vec3, half_size: f32) -> NearbyRect {
        NearbyRect::new(0, 0, origin_r, center, half_size)
    }

    /// Analytic case: the square at z = -4 seen from the origin, d = 2. A ray from (0.5, 1, 0)
    /// towards (x, y, -4) hits at t = |(x - 0.5, y - 1, -4)| with u = (x + 2) / 4 and
    /// v = (y + 2) / 4 (u grows along +x, v along +y, the up vector).
    #[test]
    fn ray_rectangle_hit_and_uv() {
        let r = rect(Vec3::ZERO, Vec3::new(0.0, 0.0, -4.0), 2.0);
        assert!((r.axis - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        assert!((r.axis_u - Vec3::X).length() < 1e-6 && (r.axis_v - Vec3::Y).length() < 1e-6);
        let o = Vec3::new(0.5, 1.0, 0.0);
        for (x, y) in [(0.0, 0.0), (1.5, -0.5), (-1.99, 1.99), (1.999, 1.999), (-1.999, -1.999)] {
            let target = Vec3::new(x, y, -4.0);
            let d = (target - o).normalize();
            let h = r.intersect(o, d).expect("inside the square");
            assert!((h.t - (target - o).length()).abs() < 1e-5, "{x},{y}: t {}", h.t);
            assert!((h.u - (x + 2.0) / 4.0).abs() < 1e-5 && (h.v - (y + 2.0) / 4.0).abs() < 1e-5, "{h:?}");
            // The parallel projection of the hit lands on the same (u, v) (Fig. 13: "the up
            // vectors of determining rectangle and rendering texture should be the same").
            let p = r.project(Vec3::ZERO, o + h.t * d);
            assert!((p.x - h.u).abs() < 1e-5 && (p.y - h.v).abs() < 1e-5, "{p} vs {h:?}");
            assert!((p.z - 4.0).abs() < 1e-5);
        }
        // Outside the square, behind the origin, parallel to the plane: no hit, no NaN.
        assert_eq!(r.intersect(o, (Vec3::new(2.6, 0.0, -4.0) - o).normalize()), None);
        assert_eq!(r.intersect(o, Vec3::new(0.0, 0.0, 1.0)), None);
        assert_eq!(r.intersect(o, Vec3::X), None);
        assert_eq!(r.intersect(o, Vec3::ZERO), None);
        assert_eq!(r.intersect(o, Vec3::splat(f32::NAN)), None);
        // Corners carry the paper's texture coordinates {0,0}, {1,0}, {1,1}, {0,1}.
        for (c, uv) in r.corners().iter().zip([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]) {
            let p = r.project(Vec3::ZERO, *c);
            assert!((p.x - uv.0).abs() < 1e-5 && (p.y - uv.1).abs() < 1e-5, "{c}: {p}");
        }
    }

    /// A tilted rectangle (O_R O_i not along an axis): the hit lies in the plane through O_i
    /// perpendicular to O_R O_i, within d of O_i along both axes, and the ortho projection's
    /// z is linear in the axial distance (Fig. 16 compares such depths).
    #[test]
    fn tilted_rectangle_is_perpendicular_and_ortho_is_linear() {
        let o_r = Vec3::new(0.3, -0.2, 0.1);
        let r = rect(o_r, Vec3::new(1.6, 0.1, -1.5), 0.7);
        assert!(r.axis.dot(r.axis_u).abs() < 1e-6 && r.axis.dot(r.axis_v).abs() < 1e-6);
        assert!(r.axis_u.dot(r.axis_v).abs() < 1e-6);
        let h = r.intersect(o_r, r.axis).expect("the axis hits the centre");
        assert!((h.u - 0.5).abs() < 1e-5 && (h.v - 0.5).abs() < 1e-5);
        assert!((h.t - r.center.distance(o_r)).abs() < 1e-5);
        for a in [r.near, 0.5 * (r.near + r.far), r.far] {
            let clip = r.view_proj * (o_r + a * r.axis + 0.3 * r.axis_u).extend(1.0);
            let expect = (a - r.near) / (r.far - r.near);
            assert!((clip.z / clip.w - expect).abs() < 1e-5, "{a}: {}", clip.z);
        }
        // Straight down (the floor below the refractor): the up vector switches to -z.
        let f = rect(Vec3::ZERO, Vec3::new(0.0, -1.0, 0.0), 7.0);
        assert!(f.axis_u.is_finite() && f.axis_v.is_finite() && (f.axis_u.length() - 1.0).abs() < 1e-5);
        let h = f.intersect(Vec3::ZERO, Vec3::new(0.6, -0.8, 0.0)).unwrap();
        assert!((h.t - 1.25).abs() < 1e-5);
    }
}
