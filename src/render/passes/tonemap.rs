//! The tone-map subpass: reads the HDR colour of each pixel as an input
//! attachment and writes the display colour, sRGB-encoded by the shader,
//! into the 8-bit output (Reinhard or ACES after exposure, or a clamp for
//! LDR scenes read back with `--hdr`). Operator and a fixed exposure are
//! specialization constants; with `exposure = "auto"` the AUTO_EXPOSURE
//! variant reads the exposure the exposure pass measured from the frame's
//! buffer instead (a second descriptor set).

use super::{
    fullscreen_pipeline, InputAttachments, PassResources, PassSetup, PassType, RecordPass,
};
use crate::render::plan::{attachment, FrameShape, PassIo};
use crate::render::RenderError;
use crate::scene::ToneMapOperator;
use crate::shader_ids::{EXPOSURE_SET, SPEC_TONEMAP_EXPOSURE, SPEC_TONEMAP_OPERATOR};
use crate::shaders::{self, TonemapFragFeatures};
use crate::vk::{
    CommandBuffer, DescriptorBinding, DescriptorPool, DescriptorSet, DescriptorSetLayout,
    DescriptorType, GraphicsPipeline, PipelineLayout, ShaderStageFlags,
};

/// Fields drop in order: pipeline before its layout and sets.
pub struct ToneMapPass {
    pipeline: GraphicsPipeline,
    layout: PipelineLayout,
    input: InputAttachments,
    exposure: Option<ExposureSet>,
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
    let layout = match &exposure {
        Some(e) => PipelineLayout::new(setup.ctx, &[&input.layout, &e.layout])?,
        None => PipelineLayout::new(setup.ctx, &[&input.layout])?,
    };
    let features =
        TonemapFragFeatures::NONE.with(TonemapFragFeatures::AUTO_EXPOSURE, exposure.is_some());
    let operator = match tone_map.operator {
        // A debug view shows its attribute as 0.5 + 0.5 v.
        _ if setup.scene.output.debug_view.is_some() => 3,
        ToneMapOperator::Reinhard => 0,
        ToneMapOperator::Aces => 1,
        ToneMapOperator::None => 2,
    };
    let pipeline = fullscreen_pipeline(
        setup.ctx,
        &layout,
        &setup.render_pass()?.render_pass,
        setup.subpass,
        shaders::TONEMAP_FRAG.spirv(features),
        &[
            (SPEC_TONEMAP_OPERATOR, operator),
            (
                SPEC_TONEMAP_EXPOSURE,
                tone_map.exposure.fixed().unwrap_or(1.0).to_bits(),
            ),
        ],
        None,
    )?;
    Ok(Box::new(ToneMapPass {
        pipeline,
        layout,
        input,
        exposure,
    }))
}

impl RecordPass for ToneMapPass {
    fn record(&self, cmd: &CommandBuffer, _frame: &PassResources<'_>) -> Result<(), RenderError> {
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_descriptor_set(&self.layout, 0, &self.input.set, &[]);
        if let Some(e) = &self.exposure {
            cmd.bind_descriptor_set(&self.layout, EXPOSURE_SET, &e.set, &[]);
        }
        cmd.draw(3);
        Ok(())
    }
}
