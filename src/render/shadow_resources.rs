//! What the shadow pass and the passes that look the shadow map up share:
//! the light's view as the shadow pass's frame block, and the shadow set
//! of the object pipelines (the map with its comparison sampler, and the
//! block saying where it looks from). Made only for frames with a shadow
//! map (`FramePlan::shadow`).

use super::gpu_types::{ShadowUniforms, ViewUniforms};
use super::plan::FramePlan;
use super::scene_resources::uniform_layout;
use super::shadow_view::ShadowView;
use super::RenderError;
use crate::scene::Scene;
use crate::shader_ids::{SHADOW_BLOCK_BINDING, SHADOW_MAP_BINDING};
use crate::vk::{
    Buffer, BufferUsage, Context, DescriptorBinding, DescriptorPool, DescriptorSet,
    DescriptorSetLayout, DescriptorType, Image, Sampler, ShaderStageFlags,
};
use std::sync::Arc;

/// Fields drop in order: sets before their pool, layouts after.
pub struct ShadowResources {
    /// The object pipelines' shadow set (`SHADOW_SET`).
    pub set: DescriptorSet,
    /// The shadow pass's frame set: the frame block with the light's
    /// view-projection, bound at `FRAME_SET`.
    pub light_frame_set: DescriptorSet,
    _pool: DescriptorPool,
    /// The shadow set's layout, in the object pipelines' layout.
    pub layout: DescriptorSetLayout,
    _frame_layout: DescriptorSetLayout,
    block: Buffer,
    light_frame: Buffer,
    _sampler: Sampler,
}

impl ShadowResources {
    /// The resources for `plan`'s shadow view of `scene`, looking up `map`
    /// (the shadow map attachment).
    pub fn new(
        ctx: &Arc<Context>,
        scene: &Scene,
        plan: &FramePlan,
        map: &Image,
    ) -> Result<ShadowResources, RenderError> {
        let view = shadow_view(plan)?;
        let (block, light_frame) = uniforms(scene, plan, view);
        let block = Buffer::with_data(
            ctx,
            "shadow block",
            bytemuck::bytes_of(&block),
            BufferUsage::Uniform,
        )?;
        let light_frame = Buffer::with_data(
            ctx,
            "light frame",
            bytemuck::bytes_of(&light_frame),
            BufferUsage::Uniform,
        )?;
        let layout = DescriptorSetLayout::new(
            ctx,
            &[
                DescriptorBinding {
                    binding: SHADOW_MAP_BINDING,
                    kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
                    stages: ShaderStageFlags::FRAGMENT,
                },
                DescriptorBinding {
                    binding: SHADOW_BLOCK_BINDING,
                    kind: DescriptorType::UNIFORM_BUFFER,
                    stages: ShaderStageFlags::FRAGMENT,
                },
            ],
        )?;
        // Defined as the object pipelines' frame layout is, so the light's
        // set binds where theirs does.
        let frame_layout = uniform_layout(ctx, DescriptorType::UNIFORM_BUFFER)?;
        let pool = DescriptorPool::for_layouts(ctx, &[&layout, &frame_layout])?;
        let sampler = Sampler::depth_comparison(ctx)?;
        let set = pool.allocate(&layout)?;
        set.write_sampled_image(SHADOW_MAP_BINDING, map, &sampler);
        set.write_buffer(
            SHADOW_BLOCK_BINDING,
            DescriptorType::UNIFORM_BUFFER,
            &block,
            std::mem::size_of::<ShadowUniforms>() as u64,
        );
        let light_frame_set = pool.allocate(&frame_layout)?;
        light_frame_set.write_buffer(
            0,
            DescriptorType::UNIFORM_BUFFER,
            &light_frame,
            std::mem::size_of::<ViewUniforms>() as u64,
        );
        Ok(ShadowResources {
            set,
            light_frame_set,
            _pool: pool,
            layout,
            _frame_layout: frame_layout,
            block,
            light_frame,
            _sampler: sampler,
        })
    }

    /// Rewrites the blocks for a new view (`plan`, of `scene`), between
    /// frames.
    pub fn set_view(&mut self, scene: &Scene, plan: &FramePlan) -> Result<(), RenderError> {
        let (block, light_frame) = uniforms(scene, plan, shadow_view(plan)?);
        self.block.write(0, bytemuck::bytes_of(&block));
        self.light_frame.write(0, bytemuck::bytes_of(&light_frame));
        Ok(())
    }
}

fn shadow_view(plan: &FramePlan) -> Result<&ShadowView, RenderError> {
    plan.shadow
        .as_ref()
        .ok_or_else(|| RenderError::Frame("the frame has no shadow view".into()))
}

/// The shadow block and the shadow pass's frame block (the camera's, with
/// the light's view-projection).
fn uniforms(scene: &Scene, plan: &FramePlan, view: &ShadowView) -> (ShadowUniforms, ViewUniforms) {
    let side = plan
        .attachment(super::plan::attachment::SHADOW_MAP)
        .map_or(1, |a| plan.attachment_extent(a).0);
    let view_projection = view.view_projection.as_mat4().to_cols_array_2d();
    let block = ShadowUniforms {
        view_projection,
        params: [
            1.0 / side as f32,
            view.texel as f32,
            if view.sun { 1.0 } else { 0.0 },
            0.0,
        ],
    };
    let mut light_frame = ViewUniforms::new(scene, plan.width, plan.height, scene.camera.eye);
    light_frame.view_projection = view_projection;
    (block, light_frame)
}
