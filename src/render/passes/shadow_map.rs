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
//! `FramePlan::shadow` (`render::shadow_view`); the casters do not follow
//! the view, so nothing here changes with it (`ShadowResources::set_view`
//! rewrites the views).

use super::depth_prepass::{depth_only_pipeline, DepthOnly, DepthOnlyDraws};
use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::render::plan::{attachment, Draw, FrameShape, PassIo};
use crate::render::scene_resources::SceneResources;
use crate::render::RenderError;
use crate::vk::{CommandBuffer, CompareOp, CullModeFlags, DepthUse, GraphicsPipeline};

/// The depth bias's constant part, in units of the map's depth precision.
const BIAS_CONSTANT: f32 = 1.0;
/// The depth bias's slope factor: depth the surface's own slope moves it
/// across two texels, so grazing surfaces stay off their own shadow.
const BIAS_SLOPE: f32 = 2.0;

pub struct ShadowPass {
    casters: Vec<Draw>,
    /// A view's tile, in texels across, and the tiles across and down
    /// (`ShadowView::tiles`).
    side: u32,
    tiles: (u32, u32),
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
    let (casters, side, tiles) = setup
        .plan
        .shadow
        .as_ref()
        .map_or((Vec::new(), 0, (1, 1)), |view| {
            (view.casters.clone(), view.side, view.tiles)
        });
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
        tiles,
        pipelines,
    }))
}

impl RecordPass for ShadowPass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let (Some(resources), Some(shadow)) = (frame.scene, frame.shadow) else {
            return Ok(());
        };
        // One tile of the map per view (cascade or cube face), each drawn
        // through its own frame set.
        let (across, _) = self.tiles;
        for (v, light_frame) in (0u32..).zip(&shadow.light_frame_sets) {
            if self.tiles != (1, 1) {
                let (x, y) = ((v % across) * self.side, (v / across) * self.side);
                cmd.set_viewport(x, y, self.side, self.side);
            }
            let casters = self
                .casters
                .iter()
                .map(|d| (d, d.pipeline.instanced as usize));
            let pipelines = DepthOnlyDraws {
                pipelines: &self.pipelines,
                frame_set: light_frame,
                pass: "shadow pass",
            };
            pipelines.record(cmd, resources, casters, SceneResources::draw_every_member)?;
        }
        Ok(())
    }
}
