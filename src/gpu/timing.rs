//! GPU timestamps: one query pool per frame in flight (../shared/DESIGN.md, rule 6).
//!
//! Each pass writes a start and an end timestamp. The pool is reset at the start of its
//! frame; results are read after that frame's fence has signalled (no WAIT flag, so reading
//! never stalls), scaled by `timestampPeriod` and masked by `timestampValidBits`.
use std::sync::Arc;

use ash::vk;

use super::context::GpuContext;
use super::error::{GpuResult, VkContext};

pub struct TimestampPool {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::QueryPool,
    pub(crate) capacity: u32,
    /// The driver reads the clock for a timestamp when it next flushes its binned work, not
    /// when the command executes: [`super::Cmd::write_timestamp`] then flushes at once.
    pub(crate) clock_on_flush: bool,
}

/// A timestamp pair written by a pass, in query indices.
#[derive(Clone, Debug)]
pub struct TimestampQuery {
    pub name: String,
    /// The pass's index in its frame: its query in a [`PipelineStatsPool`].
    pub pass: u32,
    pub start: u32,
    pub end: u32,
    /// Whether the pass recorded any device work ([`super::Cmd::work_recorded`]): a cached
    /// pass with nothing due this frame (a distance impostor's map between regenerations)
    /// records none, and its two timestamps then bracket nothing.
    pub ran: bool,
}

impl TimestampPool {
    pub fn new(ctx: &Arc<GpuContext>, name: &str, capacity: u32) -> GpuResult<TimestampPool> {
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
        // SAFETY: valid create info.
        let raw = unsafe { ctx.raw().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        ctx.set_name(raw, name);
        // llvmpipe (Mesa 22.3, lp_setup_end_query) bins a timestamp into its current scene and
        // reads the clock when the scene is rasterized: once a render pass has set a
        // framebuffer, the timestamps around a compute dispatch are both read at the next
        // flush after it, and the dispatch's time falls between passes (measured: a light
        // simulation after a rendered frame timed 7.5 ms of its 179 ms).
        let clock_on_flush = ctx.info.driver_name == "llvmpipe";
        Ok(TimestampPool { ctx: ctx.clone(), raw, capacity, clock_on_flush })
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Read `count` timestamps (ticks masked to the valid bits) after the frame's fence.
    /// Returns `None` if any is not available (which would mean the fence was not waited).
    pub fn read_ticks(&self, count: u32) -> GpuResult<Option<Vec<u64>>> {
        if count == 0 {
            return Ok(Some(Vec::new()));
        }
        let Some(data) = read_available::<2>(&self.ctx, self.raw, count)? else {
            return Ok(None);
        };
        let bits = self.ctx.info.timestamp_valid_bits;
        let mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        Ok(Some(data.iter().map(|d| d[0] & mask).collect()))
    }

    /// Milliseconds between two masked tick values (handles wrap-around of the valid bits).
    pub fn ticks_to_ms(&self, start: u64, end: u64) -> f64 {
        let bits = self.ctx.info.timestamp_valid_bits;
        let delta = if bits >= 64 { end.wrapping_sub(start) } else { end.wrapping_sub(start) & ((1u64 << bits) - 1) };
        delta as f64 * self.ctx.info.timestamp_period_ns as f64 * 1e-6
    }
}

destroy_on_drop!(
    TimestampPool => destroy_query_pool,
    OcclusionQueryPool => destroy_query_pool,
    PipelineStatsPool => destroy_query_pool,
);

/// Occlusion queries (samples that pass the depth test), for the visible area V of Shah et
/// al. 2007 Eq. 6. Results are never read on the host: [`Cmd::copy_occlusion_results`]
/// copies them into a buffer on the GPU timeline, which later passes read in the same
/// frame, so the frame does not stall and needs no previous frame's value.
///
/// [`Cmd::copy_occlusion_results`]: super::Cmd::copy_occlusion_results
pub struct OcclusionQueryPool {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::QueryPool,
    pub(crate) capacity: u32,
    /// PRECISE control flag when the device supports exact counts.
    pub(crate) flags: vk::QueryControlFlags,
}

impl OcclusionQueryPool {
    pub fn new(ctx: &Arc<GpuContext>, name: &str, capacity: u32) -> GpuResult<OcclusionQueryPool> {
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::OCCLUSION).query_count(capacity.max(1));
        // SAFETY: valid create info.
        let raw = unsafe { ctx.raw().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        ctx.set_name(raw, name);
        let flags = if ctx.info.occlusion_query_precise {
            vk::QueryControlFlags::PRECISE
        } else {
            vk::QueryControlFlags::empty()
        };
        Ok(OcclusionQueryPool { ctx: ctx.clone(), raw, capacity: capacity.max(1), flags })
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Whether the counts are exact (occlusionQueryPrecise).
    pub fn precise(&self) -> bool {
        self.flags.contains(vk::QueryControlFlags::PRECISE)
    }
}

/// What one pass made the pipeline do, from a pipeline-statistics query around it
/// (Vulkan 1.3, §17.4 "Pipeline Statistics Queries"). These tell shading waste (fragment
/// invocations beyond the pixels that need them) from geometry cost (vertices, primitives).
/// Some drivers count in blocks: lavapipe's rasterizer adds 16 fragment invocations for every
/// 4x4 block that any primitive touches, before the depth test.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct PassCounts {
    pub input_vertices: u64,
    pub input_primitives: u64,
    pub vertex_invocations: u64,
    pub geometry_invocations: u64,
    pub geometry_primitives: u64,
    pub clipping_invocations: u64,
    pub clipping_primitives: u64,
    pub fragment_invocations: u64,
    /// `None` where the device is not asked for it: lavapipe (Mesa 22.3) crashes in its
    /// queue thread when a query counting compute invocations begins (it emits the compute
    /// state then, bound or not).
    pub compute_invocations: Option<u64>,
}

/// The graphics counters [`PassCounts`] holds, in the order of their bits: the order in
/// which vkGetQueryPoolResults writes them; compute invocations (the highest bit) follow.
const GRAPHICS_STATISTICS: vk::QueryPipelineStatisticFlags = vk::QueryPipelineStatisticFlags::from_raw(
    vk::QueryPipelineStatisticFlags::INPUT_ASSEMBLY_VERTICES.as_raw()
        | vk::QueryPipelineStatisticFlags::INPUT_ASSEMBLY_PRIMITIVES.as_raw()
        | vk::QueryPipelineStatisticFlags::VERTEX_SHADER_INVOCATIONS.as_raw()
        | vk::QueryPipelineStatisticFlags::GEOMETRY_SHADER_INVOCATIONS.as_raw()
        | vk::QueryPipelineStatisticFlags::GEOMETRY_SHADER_PRIMITIVES.as_raw()
        | vk::QueryPipelineStatisticFlags::CLIPPING_INVOCATIONS.as_raw()
        | vk::QueryPipelineStatisticFlags::CLIPPING_PRIMITIVES.as_raw()
        | vk::QueryPipelineStatisticFlags::FRAGMENT_SHADER_INVOCATIONS.as_raw(),
);
const GRAPHICS_COUNTERS: usize = 8;

/// Pipeline-statistics queries, one per pass of a frame; one pool per frame in flight, read
/// after the frame's fence like [`TimestampPool`]. Needs `pipelineStatisticsQuery`.
pub struct PipelineStatsPool {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::QueryPool,
    pub(crate) capacity: u32,
    /// Whether compute invocations are counted ([`PassCounts::compute_invocations`]).
    compute: bool,
}

impl PipelineStatsPool {
    /// `None` when the device lacks `pipelineStatisticsQuery`.
    pub fn new(ctx: &Arc<GpuContext>, name: &str, capacity: u32) -> GpuResult<Option<PipelineStatsPool>> {
        if !ctx.info.pipeline_statistics {
            return Ok(None);
        }
        let compute = ctx.info.driver_name != "llvmpipe";
        let statistics = if compute {
            GRAPHICS_STATISTICS | vk::QueryPipelineStatisticFlags::COMPUTE_SHADER_INVOCATIONS
        } else {
            GRAPHICS_STATISTICS
        };
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::PIPELINE_STATISTICS)
            .query_count(capacity.max(1))
            .pipeline_statistics(statistics);
        // SAFETY: valid create info; the feature is enabled (checked above).
        let raw = unsafe { ctx.raw().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        ctx.set_name(raw, name);
        Ok(Some(PipelineStatsPool { ctx: ctx.clone(), raw, capacity: capacity.max(1), compute }))
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// The first `count` queries' counters after the frame's fence; `None` if any is not
    /// available.
    pub fn read(&self, count: u32) -> GpuResult<Option<Vec<PassCounts>>> {
        if count == 0 {
            return Ok(Some(Vec::new()));
        }
        if self.compute {
            self.read_words::<{ GRAPHICS_COUNTERS + 2 }>(count)
        } else {
            self.read_words::<{ GRAPHICS_COUNTERS + 1 }>(count)
        }
    }

    /// Each query as N words: its counters, then its availability.
    fn read_words<const N: usize>(&self, count: u32) -> GpuResult<Option<Vec<PassCounts>>> {
        let Some(data) = read_available::<N>(&self.ctx, self.raw, count)? else {
            return Ok(None);
        };
        Ok(Some(
            data.iter()
                .map(|d| PassCounts {
                    input_vertices: d[0],
                    input_primitives: d[1],
                    vertex_invocations: d[2],
                    geometry_invocations: d[3],
                    geometry_primitives: d[4],
                    clipping_invocations: d[5],
                    clipping_primitives: d[6],
                    fragment_invocations: d[7],
                    compute_invocations: self.compute.then_some(d[GRAPHICS_COUNTERS]),
                })
                .collect(),
        ))
    }
}

/// The first `count` queries of `pool` as N words each: the query's N - 1 values, then its
/// availability. `None` if any query is not yet available (its frame's fence was not waited).
fn read_available<const N: usize>(
    ctx: &GpuContext,
    pool: vk::QueryPool,
    count: u32,
) -> GpuResult<Option<Vec<[u64; N]>>> {
    let mut data = vec![[0u64; N]; count as usize];
    // SAFETY: the caller's frame fence has signalled; with WITH_AVAILABILITY each query writes
    // its values and then its availability word, and NOT_READY only leaves that word 0.
    let result = unsafe {
        ctx.raw().get_query_pool_results(
            pool,
            0,
            &mut data,
            vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WITH_AVAILABILITY,
        )
    };
    match result {
        Ok(()) | Err(vk::Result::NOT_READY) => {}
        Err(e) => return Err(e).vk("vkGetQueryPoolResults"),
    }
    Ok(data.iter().all(|d| d[N - 1] != 0).then_some(data))
}
