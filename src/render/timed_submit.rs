//! A frame recorded once and submitted many times, with a GPU timestamp
//! between its passes (and, on a context with pipeline statistics, a
//! statistics query around each): what the scene renderer and the
//! empty-pass benchmark share.

use super::{FrameTiming, RenderError};
use crate::vk::{
    AccessFlags, CommandBuffer, Context, Fence, PipelineStageFlags, PipelineStatsQueries,
    TimestampQueries,
};
use std::cell::Cell;
use std::sync::Arc;
use std::time::Instant;

/// A frame that can also be submitted with only its first passes
/// recorded, so that each pass's work can be counted as the difference of
/// two prefixes (`bench --metric instructions`).
pub trait PrefixFrames {
    /// The passes of the whole frame.
    fn pass_count(&self) -> usize;
    /// Submits the frame with only its first `recorded` passes (all of
    /// them from [`Self::pass_count`] on) and waits for it.
    fn render_prefix(&mut self, recorded: usize) -> Result<FrameTiming, RenderError>;
}

/// The command buffer of a frame, its fence and its timestamp queries.
pub(crate) struct TimedCommands {
    command_buffer: CommandBuffer,
    fence: Fence,
    queries: Option<TimestampQueries>,
    /// One per pass, when the context counts pipeline statistics.
    stats: Option<PipelineStatsQueries>,
    /// The next timestamp index while recording.
    next_stamp: Cell<u32>,
}

impl TimedCommands {
    /// Begins recording a frame of `passes` timed passes: resets the
    /// queries, orders this submission's copies into readback buffers after
    /// the previous submission's, and writes the first timestamp.
    pub(crate) fn begin(ctx: &Arc<Context>, passes: u32) -> Result<TimedCommands, RenderError> {
        let frame = TimedCommands {
            command_buffer: CommandBuffer::new(ctx)?,
            fence: Fence::new(ctx)?,
            queries: TimestampQueries::new(ctx, passes + 1)?,
            stats: if ctx.pipeline_statistics() && passes > 0 {
                Some(PipelineStatsQueries::new(ctx, passes)?)
            } else {
                None
            },
            next_stamp: Cell::new(0),
        };
        let cmd = &frame.command_buffer;
        cmd.begin()?;
        if let Some(q) = &frame.queries {
            cmd.reset_queries(q);
        }
        if let Some(q) = &frame.stats {
            cmd.reset_stats_queries(q);
        }
        cmd.memory_barrier(
            PipelineStageFlags::TRANSFER,
            AccessFlags::TRANSFER_WRITE,
            PipelineStageFlags::TRANSFER,
            AccessFlags::TRANSFER_WRITE,
        );
        frame.stamp();
        Ok(frame)
    }

    /// The command buffer being recorded.
    pub(crate) fn cmd(&self) -> &CommandBuffer {
        &self.command_buffer
    }

    /// Starts counting the current pass's pipeline statistics; call inside
    /// its subpass, before its commands.
    pub(crate) fn begin_pass(&self) {
        if let Some(q) = &self.stats {
            self.command_buffer
                .begin_stats_query(q, self.next_stamp.get() - 1);
        }
    }

    /// Stops counting the current pass's pipeline statistics; call in the
    /// same subpass, after its commands and before [`Self::stamp`].
    pub(crate) fn end_pass(&self) {
        if let Some(q) = &self.stats {
            self.command_buffer
                .end_stats_query(q, self.next_stamp.get() - 1);
        }
    }

    /// Ends the pass recorded since the last timestamp.
    pub(crate) fn stamp(&self) {
        let index = self.next_stamp.get();
        if let Some(q) = &self.queries {
            self.command_buffer.write_timestamp(q, index);
        }
        self.next_stamp.set(index + 1);
    }

    /// Makes the readback buffers' copies visible to the host and ends
    /// recording.
    pub(crate) fn finish(self) -> Result<TimedCommands, RenderError> {
        self.command_buffer.memory_barrier(
            PipelineStageFlags::TRANSFER,
            AccessFlags::TRANSFER_WRITE,
            PipelineStageFlags::HOST,
            AccessFlags::HOST_READ,
        );
        self.command_buffer.end()?;
        Ok(self)
    }

    /// Submits the frame, waits for it, and returns the GPU time of each
    /// pass (empty without timestamp support) and the CPU time from submit
    /// to fence.
    pub(crate) fn submit(&mut self) -> Result<FrameTiming, RenderError> {
        let start = Instant::now();
        self.command_buffer.submit(&self.fence)?;
        self.fence.wait_and_reset()?;
        let cpu_ms = start.elapsed().as_secs_f64() * 1e3;
        let pass_ms = match &self.queries {
            Some(q) => q.read_intervals_ns()?.iter().map(|ns| ns * 1e-6).collect(),
            None => Vec::new(),
        };
        let work = match &self.stats {
            Some(q) => q.read()?,
            None => Vec::new(),
        };
        Ok(FrameTiming {
            pass_ms,
            cpu_ms,
            work,
        })
    }
}
