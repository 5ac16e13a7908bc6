//! The tone-map subpass: reads the HDR colour of each pixel as an input
//! attachment and writes the display colour into the sRGB output (Reinhard
//! or ACES after exposure, or a clamp for LDR scenes read back with
//! `--hdr`). Operator and exposure are specialization constants.

use super::{FrameResources, PassSetup, RecordPass};
use crate::render::plan::attachment;
use crate::render::RenderError;
use crate::scene::ToneMapOperator;
use crate::shaders;
use crate::vk::{
    Blend, CommandBuffer, CullModeFlags, DescriptorBinding, DescriptorPool, DescriptorSet,
    DescriptorSetLayout, DescriptorType, GraphicsPipeline, GraphicsPipelineDesc, PipelineLayout,
    ShaderModule, ShaderStageFlags,
};

/// Fields drop in order: set before pool, pipeline before its layout.
pub struct ToneMapPass {
    set: DescriptorSet,
    _pool: DescriptorPool,
    pipeline: GraphicsPipeline,
    layout: PipelineLayout,
    _set_layout: DescriptorSetLayout,
}

pub fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let ctx = setup.ctx;
    let set_layout = DescriptorSetLayout::new(
        ctx,
        &[DescriptorBinding {
            binding: 0,
            kind: DescriptorType::INPUT_ATTACHMENT,
            stages: ShaderStageFlags::FRAGMENT,
        }],
    )?;
    let pool = DescriptorPool::for_layouts(ctx, &[&set_layout])?;
    let set = pool.allocate(&set_layout)?;
    set.write_input_attachment(0, setup.frame.attachments.get(attachment::HDR)?);
    let layout = PipelineLayout::new(ctx, &[&set_layout])?;
    let vert = ShaderModule::new(ctx, shaders::FULLSCREEN_VERT.base())?;
    let frag = ShaderModule::new(ctx, shaders::TONEMAP_FRAG.base())?;
    let tone_map = setup.scene.tone_map;
    let operator = match tone_map.operator {
        // A debug view shows its attribute as 0.5 + 0.5 v.
        _ if setup.scene.output.debug_view.is_some() => 3,
        ToneMapOperator::Reinhard => 0,
        ToneMapOperator::Aces => 1,
        ToneMapOperator::None => 2,
    };
    let pipeline = GraphicsPipeline::new(
        ctx,
        &layout,
        &setup.render_pass()?.render_pass,
        &GraphicsPipelineDesc {
            vertex_shader: &vert,
            fragment_shader: &frag,
            specialization: &[(0, operator), (1, tone_map.exposure.to_bits())],
            vertex_stride: 0,
            vertex_attributes: &[],
            cull_mode: CullModeFlags::NONE,
            depth_test: None,
            depth_write: false,
            blend: &[Blend::Replace],
            subpass: setup.subpass,
        },
    )?;
    Ok(Box::new(ToneMapPass {
        set,
        _pool: pool,
        pipeline,
        layout,
        _set_layout: set_layout,
    }))
}

impl RecordPass for ToneMapPass {
    fn record(&self, cmd: &CommandBuffer, _frame: &FrameResources<'_>) -> Result<(), RenderError> {
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_descriptor_set(&self.layout, 0, &self.set, &[]);
        cmd.draw(3);
        Ok(())
    }
}
