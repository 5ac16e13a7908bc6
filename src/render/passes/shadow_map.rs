//! The shadow pass: the shadow-casting light's view of the casters, depth
//! only, into the shadow map (`shadow map`, [`PASS`]), for frames whose
//! scene has a light with `shadows = true` and an opaque object that casts
//! shadows.
//!
//! The map is its own size (`[output] shadow_map`), so the pass is a render
//! pass of its own, before the frame's others; the passes that light
//! surfaces sample it (`glsl/include/shadow_map.glsl`). Every caster is
//! drawn, in view or not (one behind the camera still shadows what is in
//! view), with a slope-scaled depth bias, so a lit surface's own depth
//! does not shadow it where the light grazes it. Open surfaces are drawn
//! with both faces (a plane casts whichever side the light meets); closed
//! ones (spheres and tori not mirrored) with their faces towards the light
//! only: the nearest depth is the same, and the far side's fill (half of
//! a closed caster's texels) is left out. Where it looks from is
//! `FramePlan::shadow` (`render::shadow_view`); the casters do not follow
//! the view, so nothing here changes with it (`ShadowResources::set_view`
//! rewrites the views).

use super::depth_prepass::{depth_only_pipeline, DepthOnly, DepthOnlyDraws};
use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::render::plan::{attachment, Draw, FrameShape, PassIo};
use crate::render::scene_resources::SceneResources;
use crate::render::shadow_view::ShadowView;
use crate::render::RenderError;
use crate::scene::{Scene, Shape};
use crate::vk::{CommandBuffer, CompareOp, CullModeFlags, DepthUse, GraphicsPipeline};

/// The depth bias's constant part, in units of the map's depth precision.
const BIAS_CONSTANT: f32 = 1.0;
/// The depth bias's slope factor: depth the surface's own slope moves it
/// across two texels, so grazing surfaces stay off their own shadow.
const BIAS_SLOPE: f32 = 2.0;

pub struct ShadowPass {
    casters: Vec<Draw>,
    /// Each caster's index into `pipelines`.
    slots: Vec<usize>,
    /// Per view, the indices of the casters drawn into it
    /// (`Cascade::drawn`, every caster where it has no list).
    drawn: Vec<Vec<usize>>,
    /// A view's tile, in texels across, and the tiles across and down
    /// (`ShadowView::tiles`).
    side: u32,
    tiles: (u32, u32),
    /// Indexed by whether the draw is an instance batch plus 2 if its
    /// objects are closed ([`closed`]).
    pipelines: [Option<GraphicsPipeline>; 4],
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
    let towards_light = setup
        .plan
        .shadow
        .as_ref()
        .map_or(CullModeFlags::NONE, |view| back_of_light(setup.scene, view));
    let slots: Vec<usize> = casters.iter().map(|d| slot_of(setup.scene, d)).collect();
    let mut pipelines = [None, None, None, None];
    for (slot, pipeline) in pipelines.iter_mut().enumerate() {
        if !slots.contains(&slot) {
            continue;
        }
        *pipeline = Some(depth_only_pipeline(
            setup,
            DepthOnly {
                instanced: slot % 2 == 1,
                cull_mode: if slot >= 2 {
                    towards_light
                } else {
                    CullModeFlags::NONE
                },
                // Forward depth: nearer the light is smaller.
                depth_test: CompareOp::LESS,
                depth_bias: Some((BIAS_CONSTANT, BIAS_SLOPE)),
            },
        )?);
    }
    let drawn = setup.plan.shadow.as_ref().map_or(Vec::new(), |view| {
        view.cascades
            .iter()
            .map(|c| {
                c.drawn
                    .clone()
                    .unwrap_or_else(|| (0..casters.len()).collect())
            })
            .collect()
    });
    Ok(Box::new(ShadowPass {
        slots,
        drawn,
        casters,
        side,
        tiles,
        pipelines,
    }))
}

/// A caster's pipeline slot: 1 for an instance batch, plus 2 when closed.
fn slot_of(scene: &Scene, draw: &Draw) -> usize {
    usize::from(draw.pipeline.instanced) + 2 * usize::from(closed(scene, draw.objects()))
}

/// Whether every one of `objects` is a closed surface whose triangles
/// wind as modelled (a mirroring transform reverses them): a sphere or a
/// torus. Its faces turned from the light are behind its faces turned
/// towards it, so they cannot be the nearest depth.
fn closed(scene: &Scene, objects: &[usize]) -> bool {
    objects.iter().all(|&o| {
        let object = &scene.objects[o];
        matches!(object.shape, Shape::Sphere { .. } | Shape::Torus { .. })
            && object.transform.matrix_f64().determinant() > 0.0
    })
}

/// The cull mode that leaves out the faces turned from the light. The
/// pipelines take counter-clockwise triangles as front faces, as the
/// camera's do, and a face turned towards a viewer winds as the sign of
/// the determinant of its view-projection (that of the projective map's
/// Jacobian) times +1 if depth grows towards the viewer (the camera's
/// reversed Z) or -1 if it shrinks (the light's).
fn back_of_light(scene: &Scene, view: &ShadowView) -> CullModeFlags {
    let camera = scene.camera.projection_f64(1.0).determinant();
    let light = view.cascades[0].view_projection.determinant();
    if (camera > 0.0) == (light < 0.0) {
        CullModeFlags::BACK
    } else {
        CullModeFlags::FRONT
    }
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
            let drawn = self.drawn.get(v as usize).map_or(&[][..], Vec::as_slice);
            let casters = drawn.iter().map(|&i| (&self.casters[i], self.slots[i]));
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
