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
    /// The shadow pass's frame sets, one per cascade: the frame block with
    /// the cascade's view-projection, bound at `FRAME_SET`.
    pub light_frame_sets: Vec<DescriptorSet>,
    _pool: DescriptorPool,
    /// The shadow set's layout, in the object pipelines' layout.
    pub layout: DescriptorSetLayout,
    _frame_layout: DescriptorSetLayout,
    block: Buffer,
    light_frames: Vec<Buffer>,
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
        let (block, light_frames) = uniforms(scene, plan, view);
        let block = Buffer::with_data(
            ctx,
            "shadow block",
            bytemuck::bytes_of(&block),
            BufferUsage::Storage,
        )?;
        let light_frames = light_frames
            .iter()
            .map(|frame| {
                Buffer::with_data(
                    ctx,
                    "light frame",
                    bytemuck::bytes_of(frame),
                    BufferUsage::Uniform,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
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
                    kind: DescriptorType::STORAGE_BUFFER,
                    stages: ShaderStageFlags::FRAGMENT,
                },
            ],
        )?;
        // Defined as the object pipelines' frame layout is, so the light's
        // set binds where theirs does.
        let frame_layout = uniform_layout(ctx, DescriptorType::UNIFORM_BUFFER)?;
        let mut pool_layouts = vec![&layout];
        pool_layouts.extend(std::iter::repeat_n(&frame_layout, light_frames.len()));
        let pool = DescriptorPool::for_layouts(ctx, &pool_layouts)?;
        let sampler = Sampler::depth_comparison(ctx)?;
        let set = pool.allocate(&layout)?;
        set.write_sampled_image(SHADOW_MAP_BINDING, map, &sampler);
        set.write_buffer(
            SHADOW_BLOCK_BINDING,
            DescriptorType::STORAGE_BUFFER,
            &block,
            std::mem::size_of::<ShadowUniforms>() as u64,
        );
        let light_frame_sets = light_frames
            .iter()
            .map(|buffer| {
                let set = pool.allocate(&frame_layout)?;
                set.write_buffer(
                    0,
                    DescriptorType::UNIFORM_BUFFER,
                    buffer,
                    std::mem::size_of::<ViewUniforms>() as u64,
                );
                Ok(set)
            })
            .collect::<Result<Vec<_>, RenderError>>()?;
        Ok(ShadowResources {
            set,
            light_frame_sets,
            _pool: pool,
            layout,
            _frame_layout: frame_layout,
            block,
            light_frames,
            _sampler: sampler,
        })
    }

    /// Rewrites the blocks for a new view (`plan`, of `scene`), between
    /// frames.
    pub fn set_view(&mut self, scene: &Scene, plan: &FramePlan) -> Result<(), RenderError> {
        let (block, light_frames) = uniforms(scene, plan, shadow_view(plan)?);
        if light_frames.len() != self.light_frames.len() {
            return Err(RenderError::Frame(
                "the new view has another number of shadow cascades".into(),
            ));
        }
        self.block.write(0, bytemuck::bytes_of(&block));
        for (buffer, frame) in self.light_frames.iter_mut().zip(&light_frames) {
            buffer.write(0, bytemuck::bytes_of(frame));
        }
        Ok(())
    }
}

fn shadow_view(plan: &FramePlan) -> Result<&ShadowView, RenderError> {
    plan.shadow
        .as_ref()
        .ok_or_else(|| RenderError::Frame("the frame has no shadow view".into()))
}

/// The shadow block and the shadow pass's frame blocks (the camera's,
/// with each cascade's view-projection).
fn uniforms(
    scene: &Scene,
    plan: &FramePlan,
    view: &ShadowView,
) -> (ShadowUniforms, Vec<ViewUniforms>) {
    let light = match view.point {
        Some(p) => (p - scene.camera.eye).as_vec3().extend(1.0).to_array(),
        None => [0.0; 4],
    };
    let [scale, r, rn] = view.face_projection.map(|x| x as f32);
    let mut block = ShadowUniforms {
        light,
        face: [scale, r, rn, 0.0],
        view_projection: [[[0.0; 4]; 4]; 6],
        reach: [f32::MAX; 4],
        texel: [0.0; 4],
    };
    let mut frames = Vec::with_capacity(view.cascades.len());
    for (c, cascade) in view.cascades.iter().enumerate().take(6) {
        let view_projection = cascade.view_projection.as_mat4().to_cols_array_2d();
        block.view_projection[c] = view_projection;
        if c < 4 {
            block.texel[c] = cascade.texel as f32;
            if cascade.reach.is_finite() {
                block.reach[c] = cascade.reach as f32;
            }
        }
        let mut frame = ViewUniforms::new(scene, plan.width, plan.height, scene.camera.eye);
        frame.view_projection = view_projection;
        frames.push(frame);
    }
    (block, frames)
}
