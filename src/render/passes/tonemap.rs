//! The tone-map subpass: reads the HDR colour of each pixel as an input
//! attachment and writes the display colour, sRGB-encoded by the shader,
//! into the 8-bit output (Reinhard or ACES after exposure, or a clamp for
//! LDR scenes read back with `--hdr`). Operator and a fixed exposure are
//! specialization constants; with `exposure = "auto"` the AUTO_EXPOSURE
//! variant reads the exposure the exposure pass measured from the frame's
//! buffer instead (a second descriptor set). With bloom, the BLOOM
//! variant samples level 0 of the bloom pass's chain (a set of its own,
//! after the exposure's) and mixes it in before exposure.

use super::{
    fullscreen_pipeline, InputAttachments, PassResources, PassSetup, PassType, RecordPass,
};
use crate::render::plan::{attachment, FrameShape, PassIo};
use crate::render::RenderError;
use crate::scene::ToneMapOperator;
use crate::shader_ids::{
    EXPOSURE_SET, SPEC_TONEMAP_BLOOM_INTENSITY, SPEC_TONEMAP_EXPOSURE, SPEC_TONEMAP_OPERATOR,
};
use crate::shaders::{self, TonemapFragFeatures};
use crate::vk::{
    CommandBuffer, DescriptorBinding, DescriptorPool, DescriptorSet, DescriptorSetLayout,
    DescriptorType, GraphicsPipeline, PipelineLayout, Sampler, SamplerFilter, ShaderStageFlags,
};

/// Fields drop in order: pipeline before its layout and sets.
pub struct ToneMapPass {
    pipeline: GraphicsPipeline,
    layout: PipelineLayout,
    input: InputAttachments,
    exposure: Option<ExposureSet>,
    bloom: Option<BloomSet>,
}

/// The set holding level 0 of the bloom chain, for the BLOOM variant.
/// Fields drop in order: the set before its pool, the layout last.
struct BloomSet {
    set: DescriptorSet,
    _pool: DescriptorPool,
    layout: DescriptorSetLayout,
    _sampler: Sampler,
}

impl BloomSet {
    fn new(setup: &PassSetup<'_>) -> Result<BloomSet, RenderError> {
        let layout = DescriptorSetLayout::new(
            setup.ctx,
            &[DescriptorBinding {
                binding: 0,
                kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
                stages: ShaderStageFlags::FRAGMENT,
            }],
        )?;
        let pool = DescriptorPool::for_layouts(setup.ctx, &[&layout])?;
        let set = pool.allocate(&layout)?;
        let sampler = Sampler::clamped(setup.ctx, SamplerFilter::Bilinear)?;
        set.write_sampled_image(0, setup.frame.bloom()?, &sampler);
        Ok(BloomSet {
            set,
            _pool: pool,
            layout,
            _sampler: sampler,
        })
    }
}

/// The set holding the exposure buffer, for the AUTO_EXPOSURE variant.
/// Fields drop in order: the set before its pool, the layout last.
struct ExposureSet {
    set: DescriptorSet,
    _pool: DescriptorPool,
    layout: DescriptorSetLayout,
}

impl ExposureSet {
    fn new(setup: &PassSetup<'_>) -> Result<ExposureSet, RenderError> {
        let layout = DescriptorSetLayout::new(
            setup.ctx,
            &[DescriptorBinding {
                binding: 0,
                kind: DescriptorType::STORAGE_BUFFER,
                stages: ShaderStageFlags::FRAGMENT,
            }],
        )?;
        let pool = DescriptorPool::for_layouts(setup.ctx, &[&layout])?;
        let set = pool.allocate(&layout)?;
        let buffer = setup.frame.exposure()?;
        set.write_buffer(0, DescriptorType::STORAGE_BUFFER, buffer, buffer.size());
        Ok(ExposureSet {
            set,
            _pool: pool,
            layout,
        })
    }
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "tonemap"
    }

    /// HDR to the output, unless the frame draws straight into it.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        (!shape.direct)
            .then(|| PassIo::subpass(vec![attachment::OUTPUT], None, vec![attachment::HDR]))
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        create(setup)
    }
}

fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let input = InputAttachments::declared(setup)?;
    let tone_map = setup.scene.tone_map;
    // The measured exposure whenever the plan measures it.
    let exposure = if setup.plan.has(super::exposure::PASS) {
        Some(ExposureSet::new(setup)?)
    } else {
        None
    };
    // Bloom mixed in whenever the plan blurs it.
    let bloom = if setup.plan.has(super::bloom::PASS) {
        Some(BloomSet::new(setup)?)
    } else {
        None
    };
    // The input attachment, then the exposure's set and the bloom's, each
    // when present (the shader numbers the bloom's set the same way).
    let set_layouts: Vec<&DescriptorSetLayout> = std::iter::once(&input.layout)
        .chain(exposure.as_ref().map(|e| &e.layout))
        .chain(bloom.as_ref().map(|b| &b.layout))
        .collect();
    let layout = PipelineLayout::new(setup.ctx, &set_layouts)?;
    let features = TonemapFragFeatures::NONE
        .with(TonemapFragFeatures::AUTO_EXPOSURE, exposure.is_some())
        .with(TonemapFragFeatures::BLOOM, bloom.is_some());
    let operator = match tone_map.operator {
        // A debug view shows its attribute as 0.5 + 0.5 v.
        _ if setup.scene.output.debug_view.is_some() => 3,
        ToneMapOperator::Reinhard => 0,
        ToneMapOperator::Aces => 1,
        ToneMapOperator::None => 2,
    };
    let mut specialization = vec![
        (SPEC_TONEMAP_OPERATOR, operator),
        (
            SPEC_TONEMAP_EXPOSURE,
            tone_map.exposure.fixed().unwrap_or(1.0).to_bits(),
        ),
    ];
    if let (Some(_), Some(settings)) = (&bloom, tone_map.bloom) {
        specialization.push((SPEC_TONEMAP_BLOOM_INTENSITY, settings.intensity.to_bits()));
    }
    let pipeline = fullscreen_pipeline(
        setup.ctx,
        &layout,
        &setup.render_pass()?.render_pass,
        setup.subpass,
        shaders::TONEMAP_FRAG.spirv(features),
        &specialization,
        None,
    )?;
    Ok(Box::new(ToneMapPass {
        pipeline,
        layout,
        input,
        exposure,
        bloom,
    }))
}

impl RecordPass for ToneMapPass {
    fn record(&self, cmd: &CommandBuffer, _frame: &PassResources<'_>) -> Result<(), RenderError> {
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_descriptor_set(&self.layout, 0, &self.input.set, &[]);
        if let Some(e) = &self.exposure {
            cmd.bind_descriptor_set(&self.layout, EXPOSURE_SET, &e.set, &[]);
        }
        if let Some(b) = &self.bloom {
            // After the exposure's set, or in its place.
            let index = EXPOSURE_SET + u32::from(self.exposure.is_some());
            cmd.bind_descriptor_set(&self.layout, index, &b.set, &[]);
        }
        cmd.draw(3);
        Ok(())
    }
}
