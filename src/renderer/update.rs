//! Live changes: a running renderer takes a changed scene and re-creates only what depends
//! on the change (../shared/DESIGN.md, "reacts to params_changed and scene_changed").
//!
//! What a change touches is decided by comparing fingerprints of the old and the new scene:
//!
//! - the **shared** fingerprint: everything the GPU scene, the targets and the frame set are
//!   built from (the objects' topology and materials' kinds, the number and kinds of lights,
//!   the environment, the volume, the image size, the shadow map size). It leaves out what
//!   is written in place: where objects and lights are (the vertices and the light uniforms,
//!   [`crate::technique::placement_hash`]), the camera, the exposure, the material values, the
//!   caustic atlas and photon-buffer textures (made anew and bound when the caustic technique
//!   changes), and every technique's own settings. When it changes, the whole renderer is
//!   re-created;
//! - a new image size makes new targets (and atlases, bound in the frame sets), and every
//!   technique is re-created on them; [`crate::technique::Cache`] keeps what does not
//!   depend on the size (the eikonal light simulation);
//! - each technique's fingerprint: its steps in the frame recipe (passes, stages and
//!   reasons) and its [`crate::technique::Registration::inputs`]. A technique whose
//!   fingerprint is unchanged keeps running; one whose fingerprint changed is re-created;
//!   one that appears or disappears from the recipe is created or dropped.
//!
//! A test renders every change both ways, live and freshly loaded, and requires equal
//! images (tests/live.rs).
use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::time::Instant;

use crate::gpu::TimestampPool;
use crate::graph::Bindings;
use crate::scene::techniques::{CausticsMapParams, PhotonBufferParams};
use crate::scene::{Environment, Material, Scene};
use crate::technique::caustics::photon_buffer::PhotonCaustics;
use crate::technique::{params, recipe, Recipe, Setup, TECHNIQUES};

use super::{
    bind_caustic_atlas, bind_photon_caustics, clear_caustic_atlas, set_camera_uniforms, RenderError, Renderer,
    FRAMES_IN_FLIGHT, FRAME_STAGES,
};
use crate::frame::gpu_scene::gpu_material;
use crate::frame::heightfield::HeightfieldAnimation;
use crate::frame::targets::Targets;

/// What [`Renderer::update`] did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Update {
    /// The shared resources changed: the whole renderer was re-created.
    pub rebuilt: bool,
    /// Keys of the techniques re-created (or newly created), in registration order.
    pub recreated: Vec<&'static str>,
    /// Keys of the techniques the new scene no longer needs.
    pub dropped: Vec<&'static str>,
    /// The material values were written into the materials buffer.
    pub materials: bool,
    /// Objects, lights or the camera position moved: the vertices were rewritten in place.
    pub moved: bool,
    /// The image size changed: new image-sized targets, and the techniques with passes at
    /// the image's size re-created on them.
    pub resized: bool,
    /// The re-created techniques' pipelines: made anew, or kept because the same one was
    /// still live (src/gpu/pipeline.rs).
    pub pipelines: crate::gpu::PipelineCounts,
    /// Wall-clock time of the update, in ms.
    pub ms: u64,
}

impl Update {
    /// One line for a log: what was re-created.
    pub fn describe(&self) -> String {
        if self.rebuilt {
            return "re-created the whole renderer (geometry, lights, environment, volume or image size changed)"
                .to_string();
        }
        let mut parts = Vec::new();
        if self.resized {
            parts.push("made the targets at the new size".to_string());
        }
        if !self.recreated.is_empty() {
            parts.push(format!("re-created {}", self.recreated.join(", ")));
        }
        if !self.dropped.is_empty() {
            parts.push(format!("dropped {}", self.dropped.join(", ")));
        }
        if self.moved {
            parts.push("rewrote the vertices and lights".to_string());
        }
        if self.materials {
            parts.push("rewrote the materials buffer".to_string());
        }
        if parts.is_empty() {
            parts.push("updated the uniforms only".to_string());
        }
        parts.join("; ")
    }

    /// Its time for a log, and the pipelines its re-created techniques kept and made:
    /// `(3 ms; pipelines: 7 kept, 0 made)`.
    pub fn cost(&self) -> String {
        let crate::gpu::PipelineCounts { made, reused } = self.pipelines;
        match made + reused {
            0 => format!("({} ms)", self.ms),
            _ => format!("({} ms; pipelines: {reused} kept, {made} made)", self.ms),
        }
    }
}

/// Everything the shared resources are built from (see the module doc).
pub(super) fn shared_fingerprint(scene: &Scene, recipe: &Recipe) -> u64 {
    let mut h = DefaultHasher::new();
    // The effective scene file without what is only uniform data or a technique's own.
    let mut table: toml::Table = scene.canonical.parse().unwrap_or_default();
    if let Some(toml::Value::Table(camera)) = table.get_mut("camera") {
        for key in ["position", "target", "up", "vfov_deg", "width", "height"] {
            camera.remove(key);
        }
    }
    if let Some(toml::Value::Table(render)) = table.get_mut("render") {
        render.retain(|k, _| k == "shadow_map_size" || k == "sphere_segments");
    }
    // Objects and lights by what they are, not where: moving them is a placement change.
    for key in ["materials", "objects", "lights"] {
        table.remove(key);
    }
    table.to_string().hash(&mut h);
    for o in &scene.objects {
        (&o.name, o.material, o.shape, o.mesh.positions.len(), o.mesh.checker_uv.len(), &o.mesh.indices).hash(&mut h);
    }
    for l in &scene.lights {
        std::mem::discriminant(l).hash(&mut h);
    }
    // Material kinds, and dispersion: caustics mapping draws one grid per channel for it;
    // an ior below 1 decides Hu & Qin's exit search (refraction_hu_qin::assumes_back_facing).
    for m in &scene.materials {
        m.kind_name().hash(&mut h);
        if let Material::Dielectric { ior, .. } = m {
            (ior.x != ior.y || ior.y != ior.z).hash(&mut h);
            (ior.min_element() < 1.0).hash(&mut h);
        }
    }
    // What the environment file holds (the file text only names it).
    if let Environment::Image { width, height, texels, .. } = &scene.environment {
        (width, height).hash(&mut h);
        for t in texels {
            t.map(f32::to_bits).hash(&mut h);
        }
    }
    // Which lights have shadow (and caustic) atlas layers.
    crate::technique::has(&recipe.passes, crate::technique::baseline::shadow_map::SHADOW_MAP).hash(&mut h);
    h.finish()
}

/// The caustic atlas's edge when caustics mapping runs (else the 1x1 stand-in).
pub(super) fn caustic_size(scene: &Scene, recipe: &Recipe) -> Result<Option<u32>, RenderError> {
    if !crate::technique::has(&recipe.passes, crate::technique::caustics::caustics_map::CAUSTICS_MAP) {
        return Ok(None);
    }
    Ok(Some(params("caustics_map", CausticsMapParams::from_settings(&scene.render))?.map_size))
}

/// The photon-buffer parameters when the technique runs (else the stand-in's `None`).
pub(super) fn photon_params(scene: &Scene, recipe: &Recipe) -> Result<Option<PhotonBufferParams>, RenderError> {
    if !crate::technique::has(&recipe.passes, crate::technique::caustics::photon_buffer::PHOTON_BUFFER) {
        return Ok(None);
    }
    Ok(Some(params("photon_buffer", PhotonBufferParams::from_settings(&scene.render))?))
}

/// Technique `index`'s steps in `recipe` and its inputs; `None` when it is not in the recipe.
/// Technique `index`'s fingerprint: its steps in `recipe` and its inputs, with `placement`
/// ([`crate::technique::placement_hash`] of `scene`) when it is built from positions.
pub(super) fn technique_fingerprint(scene: &Scene, recipe: &Recipe, index: usize, placement: u64) -> Option<u64> {
    if !recipe.uses(index) {
        return None;
    }
    let mut h = DefaultHasher::new();
    for step in recipe.steps.iter().filter(|s| s.technique == index) {
        step.stage.hash(&mut h);
        for p in &recipe.passes[step.passes.clone()] {
            (p.name, &p.reason).hash(&mut h);
        }
    }
    let inputs = (TECHNIQUES[index].inputs)(scene);
    inputs.settings.hash(&mut h);
    if inputs.placement {
        placement.hash(&mut h);
    }
    Some(h.finish())
}

/// For settings compared against each other (`prism bench --versus`), each one's own
/// technique passes: the passes of every technique that is not the same in all of them,
/// i.e. whose fingerprint (its steps, its inputs, the placement) differs between the scenes
/// or which only some of them plan. What all of them share (the shading and the tone map,
/// unless a setting changes those) is left out, and so is the G-buffer: every setting
/// rasterises the same surfaces, and what Wyman's technique adds to that pass (d_N, one
/// vertex attribute) costs no measurable time (docs/BENCHMARKS.md, "Wyman's front faces
/// drawn once"). Pure CPU.
pub fn technique_passes(scenes: &[&Scene]) -> Vec<Vec<&'static str>> {
    let recipes: Vec<Recipe> = scenes.iter().map(|s| recipe(s)).collect();
    let prints: Vec<Vec<Option<u64>>> = scenes
        .iter()
        .zip(&recipes)
        .map(|(s, r)| {
            let placement = crate::technique::placement_hash(s);
            (0..TECHNIQUES.len()).map(|i| technique_fingerprint(s, r, i, placement)).collect()
        })
        .collect();
    let surfaces = |i: usize| TECHNIQUES[i].key == crate::technique::baseline::gbuffer::GBUFFER;
    let varied = |i: usize| !surfaces(i) && prints.iter().any(|p| p[i] != prints[0][i]);
    recipes
        .iter()
        .map(|r| {
            r.steps
                .iter()
                .filter(|s| varied(s.technique))
                .flat_map(|s| r.passes[s.passes.clone()].iter().map(|p| p.name))
                .collect()
        })
        .collect()
}

impl Renderer {
    /// Take the changed `scene` into the running renderer, re-creating only what depends on
    /// the change (module doc). Waits for the frames in flight first. On an error the
    /// renderer goes on rendering with its previous techniques. After
    /// [`Renderer::move_object`] the next update rewrites every vertex from `scene`.
    pub fn update(&mut self, scene: &Scene) -> Result<Update, RenderError> {
        self.update_with(scene, &[])
    }

    /// Shaders changed (the window's hot reload, after [`crate::gpu::GpuContext::set_shader`]):
    /// re-create the techniques whose pipelines load any of `shaders`, as
    /// [`Renderer::update`] would for a change of their settings.
    pub fn reload_shaders(&mut self, scene: &Scene, shaders: &[String]) -> Result<Update, RenderError> {
        let force: Vec<bool> =
            self.technique_shaders.iter().map(|loaded| loaded.iter().any(|s| shaders.contains(s))).collect();
        self.update_with(scene, &force)
    }

    /// [`Renderer::update`], re-creating technique `i` also when `force[i]`.
    fn update_with(&mut self, scene: &Scene, force: &[bool]) -> Result<Update, RenderError> {
        let start = Instant::now();
        let new_recipe = recipe(scene);
        let mut update = Update::default();
        self.finish()?;
        if shared_fingerprint(scene, &new_recipe) != self.shared_fingerprint {
            let ctx = self.ctx.clone();
            // Built before the old one is dropped: if it fails, the old one keeps running.
            *self = Renderer::new(&ctx, scene)?;
            update.rebuilt = true;
            update.ms = start.elapsed().as_millis() as u64;
            return Ok(update);
        }
        // Moved objects or lights (same topology): the vertices are rewritten in place and the
        // techniques built from positions have changed fingerprints.
        let placement = crate::technique::placement_hash(scene);
        if Some(placement) != self.placement {
            self.scene.update_placement(scene, scene.render.shadow_map_size);
            for (o, i) in self.objects.iter_mut().zip(0..) {
                use crate::technique::impostor::distance_impostor::{object_bounds, object_box, tight_object_bounds};
                o.bounds = object_bounds(scene, i);
                o.tight_radius = tight_object_bounds(scene, i).1;
                o.half_extent = object_box(scene, i).1;
            }
            for (i, l) in self.scene.lights.iter().enumerate() {
                self.uniforms.lights[i] = *l;
            }
            self.placement = Some(placement);
            // The heightfields' waves may have changed with them.
            self.animation = HeightfieldAnimation::new(&self.ctx, scene, &self.scene)?;
            self.animated = false;
            update.moved = true;
        }
        // Everything new is made first, then swapped in: a failure leaves the old state.
        let caustic_size = caustic_size(scene, &new_recipe)?;
        // A new image size: the image-sized targets made anew around the same atlases, and
        // the techniques with passes at the image's size re-created on them.
        let (width, height) = (scene.camera.width, scene.camera.height);
        let targets = match (width, height) != (self.targets.width, self.targets.height) {
            true => Some(self.targets.resized(&self.ctx, &mut self.graph, width, height)?),
            false => None,
        };
        let atlas = match caustic_size != self.caustic_size {
            true => Some(Targets::caustic_atlas(&self.ctx, &mut self.graph, self.targets.shadow_lights, caustic_size)?),
            false => None,
        };
        let photon_params = photon_params(scene, &new_recipe)?;
        // The photon buffer's receiver rectangles are fitted to where the receivers are.
        let photon = match photon_params != self.photon_params || (update.moved && photon_params.is_some()) {
            true => Some(PhotonCaustics::new(&self.ctx, &mut self.graph, scene, photon_params.as_ref())?),
            false => None,
        };
        let mut targets = targets;
        let old_atlas = atlas.map(|a| match targets.as_mut() {
            Some(t) => t.swap_caustic_atlas(a),
            None => self.targets.swap_caustic_atlas(a),
        });
        let fingerprints: Vec<Option<u64>> =
            (0..TECHNIQUES.len()).map(|i| technique_fingerprint(scene, &new_recipe, i, placement)).collect();
        let forced = |i: usize| force.get(i).copied().unwrap_or(false);
        let resized = targets.is_some();
        let changed = |i: usize| {
            fingerprints[i].is_some()
                && (fingerprints[i] != self.technique_fingerprints[i]
                    || forced(i)
                    || (resized && new_recipe.is_image_space(i)))
        };
        let mut setup = Setup {
            ctx: &self.ctx,
            scene,
            gpu: &self.scene,
            graph: &mut self.graph,
            frame_layout: self.frame_sets.layout(),
            targets: targets.as_ref().unwrap_or(&self.targets),
            nearest: &self._samplers[0],
            photon_caustics: photon.as_ref().unwrap_or(&self.photon_caustics),
            plan: &new_recipe.passes,
            slots: FRAMES_IN_FLIGHT,
            cache: &mut self.cache,
        };
        setup.cache.begin();
        setup.ctx.take_pipeline_counts();
        let mut created = Vec::new();
        for i in (0..TECHNIQUES.len()).filter(|&i| changed(i)) {
            self.ctx.take_shader_log();
            match (TECHNIQUES[i].create)(&mut setup) {
                Ok(t) => created.push((i, t, self.ctx.take_shader_log())),
                Err(e) => {
                    drop(created);
                    if let (Some(old), None) = (old_atlas, &targets) {
                        self.targets.swap_caustic_atlas(old);
                    }
                    return Err(e);
                }
            }
        }
        update.pipelines = self.ctx.take_pipeline_counts();
        // More passes than the timestamp pools were sized for: larger pools.
        if new_recipe.passes.len() > self.recipe.passes.len() {
            let pairs = new_recipe.passes.len() + super::EXTRA_TIMED_PASSES;
            for (i, pool) in self.timestamps.iter_mut().enumerate() {
                *pool = TimestampPool::new(&self.ctx, &format!("timestamps_{i}"), 2 * pairs as u32)?;
            }
        }

        // Commit. The GPU is idle: the old resources can go, the frame sets can be rewritten.
        self.cache.end();
        let old_targets = targets.map(|t| std::mem::replace(&mut self.targets, t));
        update.resized = old_targets.is_some();
        if old_atlas.is_some() {
            self.clear_and_bind_caustic_atlas()?;
            self.caustic_size = caustic_size;
        }
        let photon_rebuilt = photon.is_some();
        if let Some(p) = photon {
            self.photon_caustics = p;
            self.bind_photon_caustics();
            self.photon_params = photon_params;
        }
        for i in 0..TECHNIQUES.len() {
            if fingerprints[i].is_none() && self.techniques[i].take().is_some() {
                update.dropped.push(TECHNIQUES[i].key);
            }
        }
        for (i, t, shaders) in created {
            self.techniques[i] = Some(t);
            self.technique_shaders[i] = shaders;
            update.recreated.push(TECHNIQUES[i].key);
        }
        // What the kept techniques show may have moved with the vertices, or lost its target.
        if update.moved || old_atlas.is_some() || photon_rebuilt {
            for t in self.techniques.iter_mut().flatten() {
                t.contents_changed();
            }
        }
        self.every_frame = scene.render.update == "every_frame";
        // After the techniques whose framebuffers held their views.
        drop(old_atlas);
        drop(old_targets);
        self.technique_fingerprints = fingerprints;
        self.recipe = new_recipe;
        // Uniform data: the materials, the camera, the exposure.
        let materials: Vec<_> = scene.materials.iter().map(gpu_material).collect();
        if !materials.is_empty() {
            let bytes: &[u8] = bytemuck::cast_slice(&materials);
            if bytes != &self.scene.materials.read()[..bytes.len()] {
                self.scene.materials.write(0, bytes);
                update.materials = true;
                for t in self.techniques.iter_mut().flatten() {
                    t.contents_changed();
                }
            }
        }
        set_camera_uniforms(&mut self.uniforms, &scene.camera, scene.render.exposure, &self.scene);
        // What the kept techniques vary from frame to frame starts again with the new scene,
        // so that the next frame is the one a renderer created for it renders first.
        for t in self.techniques.iter_mut().flatten() {
            t.restart();
        }
        update.ms = start.elapsed().as_millis() as u64;
        Ok(update)
    }

    /// "No caustic light" in a new caustic atlas, bound in every frame set.
    fn clear_and_bind_caustic_atlas(&mut self) -> Result<(), RenderError> {
        clear_caustic_atlas(&self.ctx, &mut self.graph, &self.targets.caustic)?;
        let set = bind_caustic_atlas(Bindings::new(FRAME_STAGES), &self.targets.caustic, &self._samplers[0]);
        self.frame_sets.rewrite(&self.ctx, set);
        Ok(())
    }

    /// The photon-buffer caustic textures and rectangles, bound in every frame set.
    fn bind_photon_caustics(&self) {
        let set = bind_photon_caustics(Bindings::new(FRAME_STAGES), &self.photon_caustics, &self._samplers[0]);
        self.frame_sets.rewrite(&self.ctx, set);
    }
}
