//! The HistoPyramid (Ziegler et al. 2006) with data expansion, as the eikonal light simulator
//! reorganizes its patch list after every step (Ihrke et al. 2007, section 5.2.3,
//! ../shared/papers/ihrke2007-eikonal-rendering.md): every input patch is classified 0
//! (eliminate), 1 (retain) or 4 (tessellate); the pyramid of partial sums gives the output
//! count, and each output slot finds its input patch and its index among that patch's
//! outputs by descending the pyramid. The output generator (glsl/eikonal/light_expand.comp)
//! turns index 0..3 of a tessellated patch into its four sub-patches, not copies.
//!
//! The pyramid is 1D and 4-ary (glsl/eikonal/histopyramid.glsl says why), built by one
//! dispatch per level. The total is written by the device into the arguments of
//! `vkCmdDispatchIndirect`, so a batch of simulation steps runs without the CPU.
//! [`cpu_expand`] is the same algorithm on the CPU; tests/eikonal_light.rs checks that the
//! GPU agrees exactly ([`gpu_expand`] runs only the HistoPyramid on given classes).
use std::sync::Arc;

use crate::gpu::{
    vk, Access, Buffer, ComputePipeline, DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, MemoryLocation,
    Spec,
};
use crate::graph::{Bindings, BoundSet, BufferId, Frame, FrameGraph};
pub use crate::shader_structs::HpState;
use crate::{
    LIGHT_BINDING_CLASSES, LIGHT_BINDING_HISTORY, LIGHT_BINDING_LEVELS, LIGHT_BINDING_PAIRS, LIGHT_BINDING_STATE,
    LIGHT_GROUP,
};

/// Lengths of levels 0 (the classes), 1, ..., top (length 1) for `capacity` entries.
pub fn level_lengths(capacity: u32) -> Vec<u32> {
    let mut lens = vec![capacity];
    while *lens.last().unwrap() > 1 {
        let n = *lens.last().unwrap();
        lens.push(n.div_ceil(4));
    }
    lens
}

/// The indirect arguments of the reductions (level k + 1 in entry k) over the entries that an
/// input list of `count` makes live, as glsl/eikonal/histopyramid.glsl `hp_write_level_args`.
pub fn level_args(count: u32) -> [[u32; 4]; crate::HP_MAX_LEVELS as usize] {
    let mut n = count;
    std::array::from_fn(|_| {
        n = n.div_ceil(4);
        [n.div_ceil(LIGHT_GROUP), 1, 1, 0]
    })
}

/// The bookkeeping of a fresh build over an input list of `count` entries whose first step
/// is dispatched over `count` too.
pub fn initial_state(count: u32) -> HpState {
    HpState {
        args: [count.div_ceil(LIGHT_GROUP), 1, 1, 0],
        count,
        next: count,
        level_args: level_args(count),
        ..HpState::default()
    }
}

/// The pyramid on the CPU: level 0 is `classes[..count]` padded with zeros to `capacity`.
pub fn cpu_levels(classes: &[u32], count: usize, capacity: u32) -> Vec<Vec<u32>> {
    let lens = level_lengths(capacity);
    let mut levels = vec![(0..capacity as usize).map(|i| if i < count { classes[i] } else { 0 }).collect::<Vec<_>>()];
    for &len in &lens[1..] {
        let below = levels.last().unwrap();
        let value = |i: usize| below.get(i).copied().unwrap_or(0);
        levels.push((0..len as usize).map(|i| (0..4).map(|c| value(4 * i + c)).sum()).collect());
    }
    levels
}

/// Compaction and expansion on the CPU: for every output slot (at most `capacity`, the
/// clamp), its input entry and its index among that entry's outputs, by the same descent as
/// glsl/eikonal/histopyramid_traverse.comp; and the unclamped total.
pub fn cpu_expand(classes: &[u32], count: usize, capacity: u32) -> (Vec<(u32, u32)>, u32) {
    let levels = cpu_levels(classes, count, capacity);
    let top = levels.len() - 1;
    let total = levels[top][0];
    let next = total.min(capacity);
    let value = |k: usize, i: usize| levels[k].get(i).copied().unwrap_or(0);
    let pairs = (0..next)
        .map(|j| {
            let (mut node, mut rest) = (0usize, j);
            for k in (1..=top).rev() {
                let mut child = 4 * node;
                for c in 0..4 {
                    let v = value(k - 1, 4 * node + c);
                    child = 4 * node + c;
                    if rest < v {
                        break;
                    }
                    rest -= v;
                }
                node = child;
            }
            (node as u32, rest)
        })
        .collect();
    (pairs, total)
}

/// The GPU HistoPyramid over a list of `capacity` entries: the buffers, the descriptor set
/// (set 0 of every light-simulation kernel) and the build/traversal pipelines.
pub struct HistoPyramid {
    pub capacity: u32,
    /// Entries of the spill list past the capacity (0: outputs past it are dropped).
    pub spill_capacity: u32,
    pub history_len: u32,
    top: u32,
    /// Set 0 of every light-simulation kernel.
    set: BoundSet,
    reduce: ComputePipeline,
    total: ComputePipeline,
    traverse: ComputePipeline,
    /// [`HpState`], host-visible (read after each batch); also the indirect arguments.
    pub state: Buffer,
    /// Level 0: one count per input entry, written by the classifier.
    pub classes: Buffer,
    _levels: Buffer,
    /// (input entry, output index) per output slot.
    pub pairs: Buffer,
    /// `next` after every build, host-visible.
    pub history: Buffer,
    pub state_id: BufferId,
    pub classes_id: BufferId,
    levels_id: BufferId,
    pub pairs_id: BufferId,
    history_id: BufferId,
}

impl HistoPyramid {
    /// Buffers for `capacity` entries (at least 4, so that the pyramid has a level above the
    /// classes), `spill_capacity` outputs past them, and a history of `history_len` builds.
    pub fn new(
        ctx: &Arc<GpuContext>,
        capacity: u32,
        spill_capacity: u32,
        history_len: u32,
        graph: &mut FrameGraph,
    ) -> GpuResult<Self> {
        let capacity = capacity.max(4);
        let history_len = history_len.max(1);
        let lens = level_lengths(capacity);
        let top = (lens.len() - 1) as u32;
        assert!(top <= crate::HP_MAX_LEVELS, "a HistoPyramid of {capacity} entries has more than HP_MAX_LEVELS levels");
        let level_words: u64 = lens[1..].iter().map(|&n| n as u64).sum();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        // The per-entry buffers are written and read by every step on the device (tests copy
        // them through staging buffers); the host reads only the state and the history.
        let device = MemoryLocation::GpuOnly;
        let host = MemoryLocation::GpuToCpu;
        let state = Buffer::new(
            ctx,
            "histopyramid_state",
            std::mem::size_of::<HpState>() as u64,
            storage | vk::BufferUsageFlags::INDIRECT_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let classes = Buffer::new(ctx, "histopyramid_classes", 4 * capacity as u64, storage, device)?;
        let levels = Buffer::new(ctx, "histopyramid_levels", 4 * level_words, storage, MemoryLocation::GpuOnly)?;
        let pairs = Buffer::new(ctx, "histopyramid_pairs", 8 * (capacity + spill_capacity) as u64, storage, device)?;
        let history = Buffer::new(ctx, "histopyramid_history", 4 * history_len as u64, storage, host)?;
        let set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .storage(LIGHT_BINDING_STATE, &state)
            .storage(LIGHT_BINDING_CLASSES, &classes)
            .storage(LIGHT_BINDING_LEVELS, &levels)
            .storage(LIGHT_BINDING_PAIRS, &pairs)
            .storage(LIGHT_BINDING_HISTORY, &history)
            .build(ctx, "histopyramid")?;
        let spec = [
            ("CAPACITY", Spec::U32(capacity)),
            ("HISTORY_LEN", Spec::U32(history_len)),
            ("SPILL_CAPACITY", Spec::U32(spill_capacity)),
        ];
        let pipeline = |name: &str, shader: &str| ComputePipeline::new(ctx, name, shader, &[set.layout()], 4, &spec);
        let reduce = pipeline("histopyramid_reduce", "eikonal/histopyramid_reduce.comp")?;
        let total = pipeline("histopyramid_total", "eikonal/histopyramid_total.comp")?;
        let traverse = pipeline("histopyramid_traverse", "eikonal/histopyramid_traverse.comp")?;
        let (state_id, classes_id, levels_id, pairs_id, history_id) = (
            graph.register_buffer(&state),
            graph.register_buffer(&classes),
            graph.register_buffer(&levels),
            graph.register_buffer(&pairs),
            graph.register_buffer(&history),
        );
        Ok(HistoPyramid {
            capacity,
            spill_capacity,
            history_len,
            top,
            set,
            reduce,
            total,
            traverse,
            state,
            classes,
            _levels: levels,
            pairs,
            history,
            state_id,
            classes_id,
            levels_id,
            pairs_id,
            history_id,
        })
    }

    /// The set-0 layout that the light kernels share.
    pub fn set_layout(&self) -> &DescriptorSetLayout {
        self.set.layout()
    }

    /// Set 0 of the light kernels.
    pub fn set(&self) -> DescriptorSet {
        self.set.set()
    }

    /// Reset the bookkeeping for an input list of `count` entries (host write; call while
    /// the device is idle).
    pub fn reset(&mut self, count: u32) {
        let s = HpState { count, level_args: level_args(count), ..HpState::default() };
        self.state.write(0, bytemuck::bytes_of(&s));
    }

    /// The bookkeeping after the last submitted batch (device idle).
    pub fn read_state(&self) -> HpState {
        bytemuck::pod_read_unaligned(&self.state.read()[..std::mem::size_of::<HpState>()])
    }

    /// `next` after each of the first `n` builds.
    pub fn read_history(&self, n: usize) -> Vec<u32> {
        let words: &[u32] = bytemuck::cast_slice(&self.history.read()[..4 * self.history_len as usize]);
        words[..n.min(words.len())].to_vec()
    }

    /// Record the build (one pass per level), the total and the traversal into `frame`; the
    /// classes must be written by an earlier pass of the frame.
    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>) {
        let set = self.set.set();
        let state = &self.state;
        for level in 1..=self.top {
            let pipeline = &self.reduce;
            // Over the live entries only: the groups were written with the count.
            let offset = (std::mem::offset_of!(HpState, level_args) + 16 * (level as usize - 1)) as u64;
            frame
                .pass("histopyramid_reduce")
                .read(self.state_id, Access::IndirectArgs)
                .read(self.state_id, Access::ComputeRead)
                .read(self.classes_id, Access::ComputeRead)
                .write(self.levels_id, Access::ComputeWrite)
                .record(move |cmd| {
                    cmd.compute_indirect(pipeline, &[set], &level, state, offset);
                });
        }
        let total = &self.total;
        frame
            .pass("histopyramid_total")
            .read(self.levels_id, Access::ComputeRead)
            .write(self.state_id, Access::ComputeWrite)
            .write(self.history_id, Access::ComputeWrite)
            .record(move |cmd| {
                cmd.bind_compute(total, &[set]);
                cmd.dispatch(1, 1, 1);
            });
        let traverse = &self.traverse;
        frame
            .pass("histopyramid_traverse")
            .read(self.state_id, Access::IndirectArgs)
            .read(self.state_id, Access::ComputeRead)
            .read(self.classes_id, Access::ComputeRead)
            .read(self.levels_id, Access::ComputeRead)
            .write(self.pairs_id, Access::ComputeWrite)
            .record(move |cmd| {
                cmd.bind_compute(traverse, &[set]);
                cmd.dispatch_indirect(state, std::mem::offset_of!(HpState, out_args) as u64);
            });
    }
}

/// Test entry point: run only the GPU HistoPyramid (build, total, traversal) over
/// `classes[..count]` with a list capacity of `capacity`, and return what
/// [`cpu_expand`] returns.
pub fn gpu_expand(
    ctx: &Arc<GpuContext>,
    classes: &[u32],
    count: usize,
    capacity: u32,
) -> GpuResult<(Vec<(u32, u32)>, u32)> {
    let mut graph = FrameGraph::new();
    let mut hp = HistoPyramid::new(ctx, capacity, 0, 1, &mut graph)?;
    let n = count.min(classes.len()).min(hp.capacity as usize);
    let mut words = vec![0xdead_beefu32; hp.capacity as usize];
    words[..classes.len().min(hp.capacity as usize)]
        .copy_from_slice(&classes[..classes.len().min(hp.capacity as usize)]);
    graph.upload_buffer(ctx, &hp.classes, hp.classes_id, bytemuck::cast_slice(&words))?;
    hp.reset(n as u32);
    ctx.one_shot(|cmd| {
        let mut frame = graph.frame();
        hp.record(&mut frame);
        frame.execute(cmd, None);
        graph.access_now(cmd, &[], &[(hp.state_id, Access::HostRead)]);
    })?;
    let state = hp.read_state();
    let pairs = graph.read_back_buffer(ctx, &hp.pairs, hp.pairs_id, 8 * state.next as u64)?;
    let all: Vec<[u32; 2]> = bytemuck::pod_collect_to_vec(&pairs);
    Ok((all[..state.next as usize].iter().map(|p| (p[0], p[1])).collect(), state.requested))
}
