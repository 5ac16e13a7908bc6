//! The exposure pass, for scenes with `[tone_map] exposure = "auto"`: a
//! compute dispatch between the render pass that draws the HDR image and
//! the one that tone-maps it. It samples the HDR attachment on a regular
//! grid of at most about 65k pixels and writes one float, the exposure
//! `0.18 / Lavg` (middle grey over the log-average Rec. 709 luminance,
//! clamped to [1e-6, 1e6]), into the frame's exposure buffer, which the
//! tone map's AUTO_EXPOSURE variant reads (`glsl/exposure.comp`).
//!
//! Sampling an attachment needs it out of the render pass, which is why
//! the frame splits there into two render passes (see
//! `FramePlan::subpass_slots`).

use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::render::plan::{attachment, FrameShape, PassIo};
use crate::render::RenderError;
use crate::scene::Exposure;
use crate::shader_ids::{EXPOSURE_BUFFER_BINDING, EXPOSURE_HDR_BINDING, SPEC_EXPOSURE_STEP};
use crate::shaders;
use crate::vk::{
    AccessFlags, CommandBuffer, ComputePipeline, DescriptorBinding, DescriptorPool, DescriptorSet,
    DescriptorSetLayout, DescriptorType, ImageUse, PipelineLayout, PipelineStageFlags, Sampler,
    SamplerFilter, ShaderModule, ShaderStageFlags,
};

/// At most this many pixels are sampled (about one per 14 at 1280x720).
pub const MAX_SAMPLES: u64 = 65536;

/// The grid step for a `width`×`height` image: every `step`-th pixel in x
/// and y, `max(1, ceil(sqrt(width * height / MAX_SAMPLES)))`, so at most
/// about [`MAX_SAMPLES`] samples. Integer arithmetic, so the CPU and the
/// tests agree on it exactly.
pub fn sample_step(width: u32, height: u32) -> u32 {
    let pixels = u64::from(width) * u64::from(height);
    // The smallest step whose square covers pixels / MAX_SAMPLES.
    let mut step = 1u64;
    while step * step * MAX_SAMPLES < pixels {
        step += 1;
    }
    step as u32
}

/// Fields drop in order: the pipeline before its layout, the set before
/// its pool, the set layout last.
pub struct ExposurePass {
    pipeline: ComputePipeline,
    layout: PipelineLayout,
    set: DescriptorSet,
    _pool: DescriptorPool,
    _set_layout: DescriptorSetLayout,
    _sampler: Sampler,
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "exposure"
    }

    /// Samples the HDR image, in frames whose scene asks for automatic
    /// exposure and that tone-map it.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        let scene = shape.scene?;
        let tone_mapped = super::tonemap::PASS.declare(shape).is_some();
        (scene.tone_map.exposure == Exposure::Auto && tone_mapped).then(|| PassIo::Compute {
            samples: vec![attachment::HDR],
        })
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        create(setup)
    }

    fn is_subpass(&self) -> bool {
        false
    }
}

fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let ctx = setup.ctx;
    let set_layout = DescriptorSetLayout::new(
        ctx,
        &[
            DescriptorBinding {
                binding: EXPOSURE_HDR_BINDING,
                kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
                stages: ShaderStageFlags::COMPUTE,
            },
            DescriptorBinding {
                binding: EXPOSURE_BUFFER_BINDING,
                kind: DescriptorType::STORAGE_BUFFER,
                stages: ShaderStageFlags::COMPUTE,
            },
        ],
    )?;
    let pool = DescriptorPool::for_layouts(ctx, &[&set_layout])?;
    let set = pool.allocate(&set_layout)?;
    // texelFetch ignores the filter; a combined sampler is still needed.
    let sampler = Sampler::new(ctx, SamplerFilter::Nearest, 1)?;
    let buffer = setup.frame.exposure()?;
    set.write_sampled_image(
        EXPOSURE_HDR_BINDING,
        setup.frame.attachments.get(attachment::HDR)?,
        &sampler,
    );
    set.write_buffer(
        EXPOSURE_BUFFER_BINDING,
        DescriptorType::STORAGE_BUFFER,
        buffer,
        buffer.size(),
    );
    let layout = PipelineLayout::new(ctx, &[&set_layout])?;
    let shader = ShaderModule::new(ctx, shaders::EXPOSURE_COMP.base())?;
    let step = sample_step(setup.plan.width, setup.plan.height);
    let pipeline = ComputePipeline::new(ctx, &layout, &shader, &[(SPEC_EXPOSURE_STEP, step)])?;
    Ok(Box::new(ExposurePass {
        pipeline,
        layout,
        set,
        _pool: pool,
        _set_layout: set_layout,
        _sampler: sampler,
    }))
}

impl RecordPass for ExposurePass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        // From what the render pass before left it in (the barrier comes
        // from the image's tracked state).
        cmd.transition(
            frame.attachments.get(attachment::HDR)?,
            ImageUse::ComputeSampled,
        );
        // The previous submission's tone map must have read the value
        // before it is written again (an execution dependency suffices for
        // a write after a read).
        cmd.memory_barrier(
            PipelineStageFlags::FRAGMENT_SHADER,
            AccessFlags::empty(),
            PipelineStageFlags::COMPUTE_SHADER,
            AccessFlags::empty(),
        );
        cmd.bind_compute_pipeline(&self.pipeline);
        cmd.bind_compute_descriptor_set(&self.layout, 0, &self.set);
        cmd.dispatch([1, 1, 1]);
        // The tone map reads the value in its fragment shader.
        cmd.memory_barrier(
            PipelineStageFlags::COMPUTE_SHADER,
            AccessFlags::SHADER_WRITE,
            PipelineStageFlags::FRAGMENT_SHADER,
            AccessFlags::SHADER_READ,
        );
        Ok(())
    }
}
