//! The depth pre-pass: the opaque draws, depth only, before the surface
//! pass that shades them (`depth_prepass`, [`PASS`]).
//!
//! Its pipelines have no fragment stage and its subpass no colour target,
//! so a fragment costs a depth test and write. The surface pass after it
//! tests EQUAL without writing, so each pixel's nearest opaque surface is
//! shaded once. That needs the two passes' depths equal bit for bit: the
//! pre-pass uses `object.vert`'s plainest variant (no maps, no per-vertex
//! lighting; its other outputs nothing reads), instanced for instance
//! batches, and every variant computes `gl_Position` by the same
//! expression from the same inputs (the model matrix from the object's
//! block or, in a batch, from the instance buffer, which holds the same
//! values), so the compiled arithmetic is the same. `invariant gl_Position` would promise
//! it, but glslang puts the decoration on a `gl_PerVertex` member, which
//! lavapipe (Mesa 22.3) reports as a warning and ignores; the test suite
//! checks instead that images with and without the pre-pass are equal and
//! that each covered pixel is shaded once (`tests/suite/depth_prepass.rs`).

use super::surface::{instance_attributes, instance_stride};
use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::mesh::Vertex;
use crate::render::plan::{attachment, Draw, FramePlan, FrameShape, PassIo};
use crate::render::scene_resources::SceneResources;
use crate::render::RenderError;
use crate::scene::Scene;
use crate::shader_ids::{FRAME_SET, OBJECT_SET};
use crate::shaders::{self, ObjectVertFeatures};
use crate::vk::{
    CommandBuffer, CompareOp, CullModeFlags, DepthUse, DescriptorSet, Format, GraphicsPipeline,
    GraphicsPipelineDesc, ShaderModule, VertexAttribute,
};

pub struct DepthPrepass {
    /// The opaque draws, in the plan's order (front to back within
    /// pipeline groups).
    draws: Vec<Draw>,
    /// Indexed by [`slot`]: back faces culled or both sides drawn, as the
    /// surface pass draws them, and one draw per object or per instance
    /// batch.
    pipelines: [Option<GraphicsPipeline>; 4],
}

/// The pipeline slot of a draw: whether it is two-sided and instanced.
fn slot(d: &Draw) -> usize {
    d.pipeline.two_sided as usize + 2 * d.pipeline.instanced as usize
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "depth prepass"
    }

    /// When the plan decided for it ([`FrameShape::prepass`]): writes depth
    /// only.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        shape
            .prepass
            .then(|| PassIo::subpass(vec![], Some((attachment::DEPTH, DepthUse::Write)), vec![]))
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        create(setup)
    }
}

/// How a depth-only pipeline tests and writes depth.
pub(super) struct DepthOnly {
    /// One draw per instance batch (`object.vert`'s INSTANCED variant).
    pub instanced: bool,
    pub cull_mode: CullModeFlags,
    pub depth_test: CompareOp,
    pub depth_bias: Option<(f32, f32)>,
}

/// A depth-only pipeline over `object.vert`'s plainest variant (position
/// and normal; no fragment stage) in `setup`'s subpass: the depth pre-pass
/// and the shadow pass draw with these.
pub(super) fn depth_only_pipeline(
    setup: &PassSetup<'_>,
    how: DepthOnly,
) -> Result<GraphicsPipeline, RenderError> {
    let resources = setup.scene_resources()?;
    let render_pass = setup.render_pass()?;
    let attributes = [
        VertexAttribute {
            location: 0,
            format: Format::R32G32B32_SFLOAT,
            offset: std::mem::offset_of!(Vertex, position) as u32,
        },
        VertexAttribute {
            location: 1,
            format: Format::R32G32B32_SFLOAT,
            offset: std::mem::offset_of!(Vertex, normal) as u32,
        },
    ];
    let instance = if how.instanced {
        instance_attributes()
    } else {
        Vec::new()
    };
    // The instanced variant reads its model matrix per instance;
    // `gl_Position` is the same expression of the same values.
    let features = ObjectVertFeatures::default().with(ObjectVertFeatures::INSTANCED, how.instanced);
    let vertex = ShaderModule::new(setup.ctx, shaders::OBJECT_VERT.spirv(features))?;
    Ok(GraphicsPipeline::new(
        setup.ctx,
        &resources.layout,
        &render_pass.render_pass,
        &GraphicsPipelineDesc {
            vertex_shader: &vertex,
            fragment_shader: None,
            specialization: &[],
            vertex_stride: std::mem::size_of::<Vertex>() as u32,
            vertex_attributes: &attributes,
            instance_stride: instance_stride(how.instanced),
            instance_attributes: &instance,
            cull_mode: how.cull_mode,
            depth_test: Some(how.depth_test),
            depth_write: true,
            depth_bias: how.depth_bias,
            blend: &[],
            subpass: setup.subpass,
        },
    )?)
}

/// Draws recorded with depth-only pipelines: each draw's pipeline by its
/// slot, the frame block from `frame_set`, the object's block bound per
/// draw.
pub(super) struct DepthOnlyDraws<'a> {
    pub pipelines: &'a [Option<GraphicsPipeline>],
    pub frame_set: &'a DescriptorSet,
    /// The pass's name, for the error of a missing pipeline.
    pub pass: &'static str,
}

impl DepthOnlyDraws<'_> {
    /// Records `draws` (each with its pipeline slot) by `draw` (one of
    /// `SceneResources`' ways to draw), binding a pipeline only when the
    /// slot changes. Draws without triangles are skipped, as the surface
    /// pass skips them.
    pub fn record<'d>(
        &self,
        cmd: &CommandBuffer,
        resources: &SceneResources,
        draws: impl Iterator<Item = (&'d Draw, usize)>,
        draw: fn(&SceneResources, &CommandBuffer, &Draw) -> Result<(), RenderError>,
    ) -> Result<(), RenderError> {
        let layout = &resources.layout;
        let mut bound: Option<usize> = None;
        for (d, slot) in draws {
            if resources.ranges[d.object].index_count == 0 {
                continue;
            }
            if bound != Some(slot) {
                let pipeline = self.pipelines[slot].as_ref().ok_or_else(|| {
                    RenderError::Frame(format!("the {} has no pipeline for a draw", self.pass))
                })?;
                cmd.bind_pipeline(pipeline);
                if bound.is_none() {
                    cmd.bind_descriptor_set(layout, FRAME_SET, self.frame_set, &[]);
                }
                bound = Some(slot);
            }
            cmd.bind_descriptor_set(
                layout,
                OBJECT_SET,
                &resources.object_set,
                &[resources.block_offsets[d.object]],
            );
            draw(resources, cmd, d)?;
        }
        Ok(())
    }
}

fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let draws = setup.plan.opaque.clone();
    // Pipelines for the opaque draws out of view too, so a view that
    // brings them in keeps the pass.
    let every: Vec<&Draw> = draws
        .iter()
        .chain(setup.plan.hidden.iter().filter(|d| !d.pipeline.blended))
        .collect();
    let mut pipelines = [None, None, None, None];
    for (i, pipeline) in pipelines.iter_mut().enumerate() {
        let Some(d) = every.iter().find(|d| slot(d) == i) else {
            continue;
        };
        *pipeline = Some(depth_only_pipeline(
            setup,
            DepthOnly {
                instanced: d.pipeline.instanced,
                cull_mode: if d.pipeline.two_sided {
                    CullModeFlags::NONE
                } else {
                    CullModeFlags::BACK
                },
                // Reversed-Z: nearer surfaces have larger depth.
                depth_test: CompareOp::GREATER,
                depth_bias: None,
            },
        )?);
    }
    Ok(Box::new(DepthPrepass { draws, pipelines }))
}

impl RecordPass for DepthPrepass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let Some(resources) = frame.scene else {
            return Ok(());
        };
        let draws = self.draws.iter().map(|d| (d, slot(d)));
        let pipelines = DepthOnlyDraws {
            pipelines: &self.pipelines,
            frame_set: &resources.frame_set,
            pass: "depth pre-pass",
        };
        pipelines.record(cmd, resources, draws, SceneResources::draw)
    }

    /// Takes the new view's draw order (the same draws, sorted from the
    /// new camera).
    fn set_view(&mut self, _scene: &Scene, plan: &FramePlan) -> Result<(), RenderError> {
        if plan
            .opaque
            .iter()
            .any(|d| self.pipelines[slot(d)].is_none())
        {
            return Err(RenderError::Frame(
                "an opaque draw needs a depth pre-pass pipeline that was not created".into(),
            ));
        }
        self.draws = plan.opaque.clone();
        Ok(())
    }
}
