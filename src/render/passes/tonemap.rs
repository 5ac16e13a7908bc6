//! The tone-map subpass: reads the HDR colour of each pixel as an input
//! attachment and writes the display colour, sRGB-encoded by the shader,
//! into the 8-bit output (Reinhard or ACES after exposure, or a clamp for
//! LDR scenes read back with `--hdr`). Operator and exposure are
//! specialization constants.

use super::{
    fullscreen_pipeline, InputAttachments, PassResources, PassSetup, PassType, RecordPass,
};
use crate::render::plan::{attachment, FrameShape, PassIo};
use crate::render::RenderError;
use crate::scene::ToneMapOperator;
use crate::shader_ids::{SPEC_TONEMAP_EXPOSURE, SPEC_TONEMAP_OPERATOR};
use crate::shaders;
use crate::vk::{CommandBuffer, GraphicsPipeline, PipelineLayout};

/// Fields drop in order: pipeline before its layout and sets.
pub struct ToneMapPass {
    pipeline: GraphicsPipeline,
    layout: PipelineLayout,
    input: InputAttachments,
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
    let layout = PipelineLayout::new(setup.ctx, &[&input.layout])?;
    let tone_map = setup.scene.tone_map;
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
        shaders::TONEMAP_FRAG.base(),
        &[
            (SPEC_TONEMAP_OPERATOR, operator),
            (SPEC_TONEMAP_EXPOSURE, tone_map.exposure.to_bits()),
        ],
        None,
    )?;
    Ok(Box::new(ToneMapPass {
        pipeline,
        layout,
        input,
    }))
}

impl RecordPass for ToneMapPass {
    fn record(&self, cmd: &CommandBuffer, _frame: &PassResources<'_>) -> Result<(), RenderError> {
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_descriptor_set(&self.layout, 0, &self.input.set, &[]);
        cmd.draw(3);
        Ok(())
    }
}
