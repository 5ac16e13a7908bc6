//! GPU timestamp and pipeline-statistics queries.
//!
//! Raw ticks are masked to `timestampValidBits` (higher bits are undefined)
//! and converted with `timestampPeriod` (nanoseconds per tick). Pipeline
//! statistics are exact counts of the work a pass made the device do, the
//! same on every run and every host.

use super::{Context, VkError};
use ash::vk;
use std::sync::Arc;

pub struct TimestampQueries {
    ctx: Arc<Context>,
    pub(crate) pool: vk::QueryPool,
    pub(crate) capacity: u32,
}

impl TimestampQueries {
    /// `None` when the queue cannot write timestamps.
    pub fn new(ctx: &Arc<Context>, capacity: u32) -> Result<Option<TimestampQueries>, VkError> {
        if ctx.device_info().timestamp_valid_bits == 0 {
            return Ok(None);
        }
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        // SAFETY: valid device.
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }?;
        Ok(Some(TimestampQueries {
            ctx: ctx.clone(),
            pool,
            capacity,
        }))
    }

    /// Waits for the timestamps and returns the time between consecutive
    /// ones in nanoseconds (`capacity - 1` intervals). Differences are taken
    /// modulo 2^validBits, so a counter that wrapped still gives the right
    /// interval.
    pub fn read_intervals_ns(&self) -> Result<Vec<f64>, VkError> {
        let mut ticks = vec![0u64; self.capacity as usize];
        // SAFETY: every query was written by the submission we waited for.
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }?;
        let info = self.ctx.device_info();
        Ok(intervals_ns(
            &ticks,
            info.timestamp_valid_bits,
            info.timestamp_period_ns as f64,
        ))
    }
}

/// The time between consecutive raw timestamps, in nanoseconds: each
/// difference is taken modulo 2^`valid_bits` (bits above those are
/// undefined, and the counter may wrap between two stamps), then scaled by
/// `period_ns`, the nanoseconds per tick.
pub(crate) fn intervals_ns(ticks: &[u64], valid_bits: u32, period_ns: f64) -> Vec<f64> {
    let mask = if valid_bits >= 64 {
        u64::MAX
    } else {
        (1u64 << valid_bits) - 1
    };
    ticks
        .windows(2)
        .map(|w| (w[1].wrapping_sub(w[0]) & mask) as f64 * period_ns)
        .collect()
}

impl Drop for TimestampQueries {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses the pool.
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}

/// What one pass made the device do, counted by a pipeline-statistics
/// query (`bench --metric work`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PipelineStats {
    /// Primitives the input assembler assembled (triangles of the draws).
    pub input_primitives: u64,
    pub vertex_invocations: u64,
    /// Primitives that left the clipper (what rasterisation set up).
    pub clipped_primitives: u64,
    pub fragment_invocations: u64,
    pub compute_invocations: u64,
    /// Samples that passed the depth test (an occlusion query): the
    /// fragments actually shaded and written. A driver may count fragment
    /// invocations before early depth testing (lavapipe counts 16 for each
    /// 4×4 block a triangle touches), so only this count shows what a depth
    /// pre-pass saves. Exact where the device has `occlusionQueryPrecise`.
    #[serde(default)]
    pub depth_passed: u64,
}

/// The counters asked for, in the order Vulkan writes them (ascending bit
/// order of the flags), matching [`PipelineStats`]'s fields.
const STATISTICS: [vk::QueryPipelineStatisticFlags; 5] = [
    vk::QueryPipelineStatisticFlags::INPUT_ASSEMBLY_PRIMITIVES,
    vk::QueryPipelineStatisticFlags::VERTEX_SHADER_INVOCATIONS,
    vk::QueryPipelineStatisticFlags::CLIPPING_PRIMITIVES,
    vk::QueryPipelineStatisticFlags::FRAGMENT_SHADER_INVOCATIONS,
    vk::QueryPipelineStatisticFlags::COMPUTE_SHADER_INVOCATIONS,
];

/// One pipeline-statistics query per pass. Needs a context created with
/// [`super::ContextOptions::pipeline_statistics`].
pub struct PipelineStatsQueries {
    ctx: Arc<Context>,
    pub(crate) pool: vk::QueryPool,
    /// An occlusion query beside each statistics query.
    pub(crate) occlusion: vk::QueryPool,
    pub(crate) capacity: u32,
}

impl PipelineStatsQueries {
    pub fn new(ctx: &Arc<Context>, capacity: u32) -> Result<PipelineStatsQueries, VkError> {
        let flags = STATISTICS
            .iter()
            .fold(vk::QueryPipelineStatisticFlags::empty(), |a, f| a | *f);
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::PIPELINE_STATISTICS)
            .pipeline_statistics(flags)
            .query_count(capacity);
        // SAFETY: valid device; the feature was enabled at device creation
        // (ContextOptions::pipeline_statistics), or creation fails cleanly.
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }?;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::OCCLUSION)
            .query_count(capacity);
        // SAFETY: valid device; occlusion queries need no feature.
        let occlusion = match unsafe { ctx.device.create_query_pool(&info, None) } {
            Ok(occlusion) => occlusion,
            Err(e) => {
                // SAFETY: created above, used by nothing yet.
                unsafe { ctx.device.destroy_query_pool(pool, None) };
                return Err(e.into());
            }
        };
        Ok(PipelineStatsQueries {
            ctx: ctx.clone(),
            pool,
            occlusion,
            capacity,
        })
    }

    /// Waits for the queries and returns one [`PipelineStats`] per query.
    pub fn read(&self) -> Result<Vec<PipelineStats>, VkError> {
        let mut raw = vec![[0u64; STATISTICS.len()]; self.capacity as usize];
        // SAFETY: every query was begun and ended by the submission waited for;
        // each element holds the five counters of one query.
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }?;
        let mut passed = vec![0u64; self.capacity as usize];
        // SAFETY: as above; one counter per query.
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.occlusion,
                0,
                &mut passed,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }?;
        Ok(raw
            .iter()
            .zip(passed)
            .map(|(r, depth_passed)| PipelineStats {
                input_primitives: r[0],
                vertex_invocations: r[1],
                clipped_primitives: r[2],
                fragment_invocations: r[3],
                compute_invocations: r[4],
                depth_passed,
            })
            .collect())
    }
}

impl Drop for PipelineStatsQueries {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses the pools.
        unsafe {
            self.ctx.device.destroy_query_pool(self.pool, None);
            self.ctx.device.destroy_query_pool(self.occlusion, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::intervals_ns;

    const BITS: u32 = 36;
    const PERIOD_NS: f64 = 2.5;

    /// Ticks as a device with 36 valid bits may return them: the counter
    /// near its top, then wrapped, with garbage in the undefined high bits.
    fn raw(counter: u64, garbage: u64) -> u64 {
        assert!(counter < 1 << BITS);
        (garbage << BITS) | counter
    }

    #[test]
    fn intervals_are_masked_wrapped_and_scaled() {
        let top = 1u64 << BITS;
        let ticks = [
            raw(top - 100, 0xabc),
            raw(top - 40, 0x123),
            raw(60, 0xfff_ffff), // wrapped: 100 ticks after the previous
            raw(1_060, 0),
        ];
        let got = intervals_ns(&ticks, BITS, PERIOD_NS);
        // By hand: 60, 100 and 1000 ticks of 2.5 ns.
        assert_eq!(got, vec![150.0, 250.0, 2_500.0]);
    }

    #[test]
    fn all_64_bits_valid_and_a_unit_period() {
        let got = intervals_ns(&[u64::MAX - 1, 3], 64, 1.0);
        assert_eq!(got, vec![5.0]);
    }

    #[test]
    fn fewer_than_two_stamps_give_no_interval() {
        assert!(intervals_ns(&[42], BITS, PERIOD_NS).is_empty());
        assert!(intervals_ns(&[], BITS, PERIOD_NS).is_empty());
    }
}
