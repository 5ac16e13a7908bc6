//! The bloom pass, for scenes with `[tone_map] bloom = { ... }`: physically
//! based bloom in the manner of Jimenez (2014). One compute pass between
//! the render pass that draws the HDR image and the one that tone-maps it
//! records the whole chain: level 0 (a quarter of the output's size, the
//! mean of each 4x4 HDR texels) downsampled from the HDR attachment, each
//! next level from the one above with the
//! 13-tap filter (`glsl/bloom_down.comp`), then from the smallest level
//! back up, each level replaced by the mean of its own downsample and the
//! level below blurred up with a 2x2 box (`glsl/bloom_up.comp`). The tone
//! map's BLOOM variant samples level 0 and mixes it in with the scene's
//! intensity, before exposure and the curve.
//!
//! The chain is one RGBA16F image with a mip level per level, created by
//! the renderer with the frame (`PassResources::bloom`), because the tone
//! map reads it too; the pass owns what only it uses (a view of each level,
//! one descriptor set and pipeline per dispatch).

use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::render::plan::{attachment, FrameShape, PassIo};
use crate::render::RenderError;
use crate::scene::Bloom;
use crate::shader_ids::{
    BLOOM_GROUP_SIZE, BLOOM_SOURCE_BINDING, BLOOM_TARGET_BINDING, SPEC_BLOOM_OWN_WEIGHT,
    SPEC_BLOOM_RADIUS,
};
use crate::shaders::{self, BloomDownCompFeatures};
use crate::vk::{
    CommandBuffer, ComputePipeline, DescriptorBinding, DescriptorPool, DescriptorSet,
    DescriptorSetLayout, DescriptorType, ImageUse, MipView, PipelineLayout, Sampler, SamplerFilter,
    ShaderModule, ShaderStageFlags,
};

/// The size of level `level` of the chain of a `width`×`height` frame:
/// `width >> (level + 2)` by `height >> (level + 2)` (level 0 is a
/// quarter of the frame: the HDR image is read once, in 2x2 boxes).
pub fn level_size(width: u32, height: u32, level: u32) -> (u32, u32) {
    (width >> (level + 2), height >> (level + 2))
}

/// The scene's bloom and the levels its chain has in a frame of the
/// scene's output size, when the frame holds the pass.
pub fn chain(shape: &FrameShape<'_>) -> Option<(Bloom, u32)> {
    let scene = shape.scene?;
    let bloom = scene.tone_map.bloom?;
    let levels = bloom.chain_levels(scene.output.width, scene.output.height);
    // A debug view shows attributes, not light.
    (levels > 0 && scene.output.debug_view.is_none()).then_some((bloom, levels))
}

/// One dispatch of the chain.
struct Step {
    /// Index into `BloomPass::pipelines`.
    pipeline: usize,
    set: DescriptorSet,
    /// The level it writes.
    level: u32,
    groups: [u32; 3],
}

/// Fields drop in order: the pipelines before their layout, the sets
/// before their pool, the set layout, then the views the sets point at.
pub struct BloomPass {
    pipelines: Vec<ComputePipeline>,
    layout: PipelineLayout,
    steps: Vec<Step>,
    _pool: DescriptorPool,
    _set_layout: DescriptorSetLayout,
    _views: Vec<MipView>,
    _sampler: Sampler,
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "bloom"
    }

    /// Samples the HDR image, in frames whose scene asks for bloom and
    /// that tone-map it.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        let tone_mapped = super::tonemap::PASS.declare(shape).is_some();
        (tone_mapped && chain(shape).is_some()).then(|| PassIo::Compute {
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
    let image = setup.frame.bloom()?;
    let hdr = setup.frame.attachments.get(attachment::HDR)?;
    let levels = image.desc.mip_levels;
    let bloom = setup
        .scene
        .tone_map
        .bloom
        .ok_or_else(|| RenderError::Frame("the bloom pass in a scene without bloom".into()))?;
    let set_layout = DescriptorSetLayout::new(
        ctx,
        &[
            DescriptorBinding {
                binding: BLOOM_SOURCE_BINDING,
                kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
                stages: ShaderStageFlags::COMPUTE,
            },
            DescriptorBinding {
                binding: BLOOM_TARGET_BINDING,
                kind: DescriptorType::STORAGE_IMAGE,
                stages: ShaderStageFlags::COMPUTE,
            },
        ],
    )?;
    // Down to every level, then up to every level but the smallest.
    let step_count = 2 * levels as usize - 1;
    let pool = DescriptorPool::for_layouts(ctx, &vec![&set_layout; step_count])?;
    let layout = PipelineLayout::new(ctx, &[&set_layout])?;
    // Bilinear, clamped at the edges: a box at the border repeats the
    // edge texels, like the HDR image's clamped texel fetches.
    let sampler = Sampler::clamped(ctx, SamplerFilter::Bilinear)?;
    let views = (0..levels)
        .map(|level| image.mip_view(level))
        .collect::<Result<Vec<_>, _>>()?;

    let down = ShaderModule::new(ctx, shaders::BLOOM_DOWN_COMP.base())?;
    // Level 0 reads the HDR image in bilinear 2x2 boxes where the device
    // filters its format (always for RGBA16F; RGBA32F is optional).
    let from_hdr = BloomDownCompFeatures::FROM_HDR.with(
        BloomDownCompFeatures::FETCH_TEXELS,
        !crate::vk::supports_linear_sampling(ctx, hdr.desc.format),
    );
    let down_hdr = ShaderModule::new(ctx, shaders::BLOOM_DOWN_COMP.spirv(from_hdr))?;
    let up = ShaderModule::new(ctx, shaders::BLOOM_UP_COMP.base())?;
    let mut pipelines = vec![ComputePipeline::new(ctx, &layout, &down_hdr, &[])?];
    if levels > 1 {
        pipelines.push(ComputePipeline::new(ctx, &layout, &down, &[])?);
    }
    let (width, height) = (setup.plan.width, setup.plan.height);
    let groups = |level: u32| {
        let (w, h) = level_size(width, height, level);
        [
            w.div_ceil(BLOOM_GROUP_SIZE),
            h.div_ceil(BLOOM_GROUP_SIZE),
            1,
        ]
    };
    let mut steps = Vec::with_capacity(step_count);
    for level in 0..levels {
        let set = pool.allocate(&set_layout)?;
        if level == 0 {
            set.write_sampled_image(BLOOM_SOURCE_BINDING, hdr, &sampler);
        } else {
            set.write_sampled_mip(BLOOM_SOURCE_BINDING, &views[level as usize - 1], &sampler);
        }
        set.write_storage_mip(BLOOM_TARGET_BINDING, &views[level as usize]);
        steps.push(Step {
            pipeline: usize::from(level > 0),
            set,
            level,
            groups: groups(level),
        });
    }
    for level in (0..levels - 1).rev() {
        let set = pool.allocate(&set_layout)?;
        set.write_sampled_mip(BLOOM_SOURCE_BINDING, &views[level as usize + 1], &sampler);
        set.write_storage_mip(BLOOM_TARGET_BINDING, &views[level as usize]);
        // This level's downsample is one of the `levels - level` it ends
        // as the mean of.
        let own_weight = 1.0 / (levels - level) as f32;
        pipelines.push(ComputePipeline::new(
            ctx,
            &layout,
            &up,
            &[
                (SPEC_BLOOM_RADIUS, bloom.radius.to_bits()),
                (SPEC_BLOOM_OWN_WEIGHT, own_weight.to_bits()),
            ],
        )?);
        steps.push(Step {
            pipeline: pipelines.len() - 1,
            set,
            level,
            groups: groups(level),
        });
    }
    Ok(Box::new(BloomPass {
        pipelines,
        layout,
        steps,
        _pool: pool,
        _set_layout: set_layout,
        _views: views,
        _sampler: sampler,
    }))
}

impl RecordPass for BloomPass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let image = frame.bloom()?;
        // From what the render pass before left it in.
        cmd.transition(
            frame.attachments.get(attachment::HDR)?,
            ImageUse::ComputeSampled,
        );
        // Every level is written before it is read; the barrier waits for
        // the previous submission's tone map to have read level 0.
        cmd.transition_discarding(image, ImageUse::ComputeWrite);
        for (i, step) in self.steps.iter().enumerate() {
            cmd.bind_compute_pipeline(&self.pipelines[step.pipeline]);
            cmd.bind_compute_descriptor_set(&self.layout, 0, &step.set);
            cmd.dispatch(step.groups);
            if i + 1 < self.steps.len() {
                cmd.compute_level_barrier(image, step.level);
            }
        }
        // The tone map samples level 0 in its fragment shader.
        cmd.transition(image, ImageUse::FragmentSampled);
        Ok(())
    }
}
