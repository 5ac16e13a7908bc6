//! GPU timestamp queries.
//!
//! Raw ticks are masked to `timestampValidBits` (higher bits are undefined)
//! and converted with `timestampPeriod` (nanoseconds per tick).

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
        let bits = self.ctx.device_info().timestamp_valid_bits;
        let mask = if bits >= 64 {
            u64::MAX
        } else {
            (1u64 << bits) - 1
        };
        let period = self.ctx.device_info().timestamp_period_ns as f64;
        Ok(ticks
            .windows(2)
            .map(|w| (w[1].wrapping_sub(w[0]) & mask) as f64 * period)
            .collect())
    }
}

impl Drop for TimestampQueries {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses the pool.
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}
