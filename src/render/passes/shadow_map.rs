//! The shadow pass: the shadow-casting light's view of the casters, depth
//! only, into the shadow map (`shadow map`, [`PASS`]), for frames whose
//! scene has a light with `shadows = true` and an opaque object that casts
//! shadows.
//!
//! The map is its own size (`[output] shadow_map`), so the pass is a render
//! pass of its own, before the frame's others; the passes that light
//! surfaces sample it (`glsl/include/shadow_map.glsl`). Every caster is
//! drawn, in view or not (one behind the camera still shadows what is in
//! view), with both faces (a plane casts whichever side the light meets)
//! and a slope-scaled depth bias, so a lit surface's own depth does not
//! shadow it where the light grazes it. Where it looks from is
//! `FramePlan::shadow` (`render::shadow_view`).

use super::depth_prepass::{depth_only_pipeline, DepthOnly};
use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::render::plan::{attachment, Draw, FramePlan, FrameShape, PassIo};
use crate::render::scene_resources::SceneResources;
use crate::render::shadow_view;
use crate::render::RenderError;
use crate::scene::Scene;
use crate::shader_ids::{FRAME_SET, OBJECT_SET};
use crate::vk::{
    CommandBuffer, CompareOp, CullModeFlags, DepthUse, DescriptorSet, GraphicsPipeline,
};

/// The depth bias's constant part, in units of the map's depth precision.
const BIAS_CONSTANT: f32 = 1.0;
/// The depth bias's slope factor: depth the surface's own slope moves it
/// across two texels, so grazing surfaces stay off their own shadow.
const BIAS_SLOPE: f32 = 2.0;

pub struct ShadowPass {
    casters: Vec<Draw>,
    /// A cascade's tile, in texels across.
    side: u32,
    /// Indexed by whether the draw is an instance batch.
    pipelines: [Option<GraphicsPipeline>; 2],
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "shadow map"
    }

    /// Writes the shadow map's depth, in frames that have one.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        shape.shadow_map.map(|_| {
            PassIo::subpass(
                vec![],
                Some((attachment::SHADOW_MAP, DepthUse::Write)),
                vec![],
            )
        })
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        create(setup)
    }
}

fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let (casters, side) = setup
        .plan
        .shadow
        .as_ref()
        .map_or((Vec::new(), 0), |view| (view.casters.clone(), view.side));
    let mut pipelines = [None, None];
    for (slot, pipeline) in pipelines.iter_mut().enumerate() {
        let instanced = slot == 1;
        if !casters.iter().any(|d| d.pipeline.instanced == instanced) {
            continue;
        }
        *pipeline = Some(depth_only_pipeline(
            setup,
            DepthOnly {
                instanced,
                cull_mode: CullModeFlags::NONE,
                // Forward depth: nearer the light is smaller.
                depth_test: CompareOp::LESS,
                depth_bias: Some((BIAS_CONSTANT, BIAS_SLOPE)),
            },
        )?);
    }
    Ok(Box::new(ShadowPass {
        casters,
        side,
        pipelines,
    }))
}

impl ShadowPass {
    /// Every caster, seen through `light_frame` (a cascade's frame set).
    fn draw_casters(
        &self,
        cmd: &CommandBuffer,
        resources: &SceneResources,
        light_frame: &DescriptorSet,
    ) -> Result<(), RenderError> {
        let layout = &resources.layout;
        let mut bound: Option<usize> = None;
        for d in &self.casters {
            if resources.ranges[d.object].index_count == 0 {
                continue;
            }
            let slot = d.pipeline.instanced as usize;
            if bound != Some(slot) {
                let pipeline = self.pipelines[slot].as_ref().ok_or_else(|| {
                    RenderError::Frame("the shadow pass has no pipeline for a caster".into())
                })?;
                cmd.bind_pipeline(pipeline);
                if bound.is_none() {
                    cmd.bind_descriptor_set(layout, FRAME_SET, light_frame, &[]);
                }
                bound = Some(slot);
            }
            cmd.bind_descriptor_set(
                layout,
                OBJECT_SET,
                &resources.object_set,
                &[resources.block_offsets[d.object]],
            );
            resources.draw_every_member(cmd, d)?;
        }
        Ok(())
    }
}

impl RecordPass for ShadowPass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let (Some(resources), Some(shadow)) = (frame.scene, frame.shadow) else {
            return Ok(());
        };
        // One tile of the map per cascade, each drawn from its own view.
        let cascades = shadow.light_frame_sets.len() as u32;
        let (across, _) = shadow_view::tiles(cascades);
        for (c, light_frame) in shadow.light_frame_sets.iter().enumerate() {
            let c = c as u32;
            if cascades > 1 {
                cmd.set_viewport(
                    (c % across) * self.side,
                    (c / across) * self.side,
                    self.side,
                    self.side,
                );
            }
            self.draw_casters(cmd, resources, light_frame)?;
        }
        Ok(())
    }

    /// The casters do not follow the view (only the light's view does,
    /// which `ShadowResources::set_view` rewrites).
    fn set_view(&mut self, _scene: &Scene, _plan: &FramePlan) -> Result<(), RenderError> {
        Ok(())
    }
}
