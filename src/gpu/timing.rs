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
}

/// A timestamp pair written by a pass, in query indices.
#[derive(Clone, Debug)]
pub struct TimestampQuery {
    pub name: String,
    pub start: u32,
    pub end: u32,
}

impl TimestampPool {
    pub fn new(ctx: &Arc<GpuContext>, name: &str, capacity: u32) -> GpuResult<TimestampPool> {
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
        // SAFETY: valid create info.
        let raw = unsafe { ctx.raw().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        ctx.set_name(raw, name);
        Ok(TimestampPool { ctx: ctx.clone(), raw, capacity })
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
        let mut data = vec![[0u64; 2]; count as usize];
        // SAFETY: the frame's fence has signalled; WITH_AVAILABILITY writes (value, available).
        let result = unsafe {
            self.ctx.raw().get_query_pool_results(
                self.raw,
                0,
                &mut data,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WITH_AVAILABILITY,
            )
        };
        match result {
            Ok(()) | Err(vk::Result::NOT_READY) => {}
            Err(e) => return Err(e).vk("vkGetQueryPoolResults"),
        }
        if data.iter().any(|d| d[1] == 0) {
            return Ok(None);
        }
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

destroy_on_drop!(TimestampPool => destroy_query_pool, OcclusionQueryPool => destroy_query_pool);

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
