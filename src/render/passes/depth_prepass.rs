//! The depth pre-pass: the opaque draws, depth only, before the surface
//! pass that shades them (`depth_prepass`, `PassKind::DepthPrepass`).
//!
//! Its pipelines have no fragment stage and its subpass no colour target,
//! so a fragment costs a depth test and write. The surface pass after it
//! tests EQUAL without writing, so each pixel's nearest opaque surface is
//! shaded once. That needs the two passes' depths equal bit for bit: the
//! pre-pass uses `object.vert`'s plainest variant (no maps, no per-vertex
//! lighting; its other outputs nothing reads), and every variant computes
//! `gl_Position` by the same expression from the same inputs, so the
//! compiled arithmetic is the same. `invariant gl_Position` would promise
//! it, but glslang puts the decoration on a `gl_PerVertex` member, which
//! lavapipe (Mesa 22.3) reports as a warning and ignores; the test suite
//! checks instead that images with and without the pre-pass are equal and
//! that each covered pixel is shaded once (`tests/suite/depth_prepass.rs`).

use super::{PassResources, PassSetup, RecordPass};
use crate::mesh::Vertex;
use crate::render::plan::{Draw, FramePlan};
use crate::render::RenderError;
use crate::scene::Scene;
use crate::shader_ids::{FRAME_SET, OBJECT_SET};
use crate::shaders;
use crate::vk::{
    CommandBuffer, CompareOp, CullModeFlags, DepthOnlyPipelineDesc, Format, GraphicsPipeline,
    ShaderModule, VertexAttribute,
};

pub struct DepthPrepass {
    /// The opaque draws, in the plan's order (front to back within
    /// pipeline groups).
    draws: Vec<Draw>,
    /// Indexed by `two_sided`: back faces culled, or both sides drawn, as
    /// the surface pass draws them.
    pipelines: [Option<GraphicsPipeline>; 2],
}

pub fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let draws = setup.plan.opaque.clone();
    let mut pipelines = [None, None];
    if !draws.is_empty() {
        let resources = setup.scene_resources()?;
        let render_pass = setup.render_pass()?;
        let vertex = ShaderModule::new(setup.ctx, shaders::OBJECT_VERT.base())?;
        // The plainest variant reads the position and the normal.
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
        for two_sided in [false, true] {
            if !draws.iter().any(|d| d.pipeline.two_sided == two_sided) {
                continue;
            }
            pipelines[two_sided as usize] = Some(GraphicsPipeline::depth_only(
                setup.ctx,
                &resources.layout,
                &render_pass.render_pass,
                &DepthOnlyPipelineDesc {
                    vertex_shader: &vertex,
                    specialization: &[],
                    vertex_stride: std::mem::size_of::<Vertex>() as u32,
                    vertex_attributes: &attributes,
                    cull_mode: if two_sided {
                        CullModeFlags::NONE
                    } else {
                        CullModeFlags::BACK
                    },
                    // Reversed-Z: nearer surfaces have larger depth.
                    depth_test: CompareOp::GREATER,
                    subpass: setup.subpass,
                },
            )?);
        }
    }
    Ok(Box::new(DepthPrepass { draws, pipelines }))
}

impl RecordPass for DepthPrepass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let Some(resources) = frame.scene else {
            return Ok(());
        };
        let layout = &resources.layout;
        let mut bound: Option<bool> = None;
        for d in &self.draws {
            let range = &resources.ranges[d.object];
            // Draws without triangles are skipped, as the surface pass does.
            if range.index_count == 0 {
                continue;
            }
            let two_sided = d.pipeline.two_sided;
            if bound != Some(two_sided) {
                let pipeline = self.pipelines[two_sided as usize].as_ref().ok_or_else(|| {
                    RenderError::Frame("the depth pre-pass has no pipeline for a draw".into())
                })?;
                cmd.bind_pipeline(pipeline);
                if bound.is_none() {
                    cmd.bind_descriptor_set(layout, FRAME_SET, &resources.frame_set, &[]);
                }
                bound = Some(two_sided);
            }
            cmd.bind_descriptor_set(
                layout,
                OBJECT_SET,
                &resources.object_set,
                &[resources.block_offsets[d.object]],
            );
            cmd.bind_geometry(&resources.geometry, range.vertex_offset, range.index_offset);
            cmd.draw_indexed(range.index_count);
        }
        Ok(())
    }

    /// Takes the new view's draw order (the same draws, sorted from the
    /// new camera).
    fn set_view(&mut self, _scene: &Scene, plan: &FramePlan) -> Result<(), RenderError> {
        if plan
            .opaque
            .iter()
            .any(|d| self.pipelines[d.pipeline.two_sided as usize].is_none())
        {
            return Err(RenderError::Frame(
                "an opaque draw needs a depth pre-pass pipeline that was not created".into(),
            ));
        }
        self.draws = plan.opaque.clone();
        Ok(())
    }
}
