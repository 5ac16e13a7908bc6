//! The deferred lighting subpass: for each group of screen tiles lit by the
//! same lights (`render::tiles`), one draw of the group's tiles whose
//! fragment shader reads the G-buffer and depth as input attachments,
//! rebuilds the position from depth and adds exactly those lights to the
//! colour target (additive blending over the ambient term the G-buffer
//! pass wrote). As for forward draws, the light count is a specialization
//! constant, so each group's loop has a fixed trip count, and so are the
//! lights themselves where they fit (`render::static_lights`): one pipeline
//! per group then, instead of one per light count.
//!
//! The tiles are drawn at the far plane with a LESS test against the
//! stored (reversed-Z) depth, so pixels without a surface are never shaded.

use super::{InputAttachments, PassResources, PassSetup, PassType, RecordPass};
use crate::render::gpu_types::GpuLight;
use crate::render::plan::{attachment, FrameShape, PassIo};
use crate::render::scene_resources::{pack_blocks, scene_light, SceneResources};
use crate::render::static_lights;
use crate::render::RenderError;
use crate::shader_ids::{SPEC_LIGHT_ARRAY_LENGTH, SPEC_LIGHT_COUNT};
use crate::shaders;
use crate::vk::{
    Blend, Buffer, BufferUsage, CommandBuffer, CullModeFlags, DescriptorBinding, DescriptorPool,
    DescriptorSet, DescriptorSetLayout, DescriptorType, Format, GraphicsPipeline,
    GraphicsPipelineDesc, PipelineLayout, ShaderModule, ShaderStageFlags, VertexAttribute,
};
use crate::vk::{CompareOp, DepthUse};
use std::collections::BTreeMap;

/// One draw: a tile group's vertices and lights.
struct GroupDraw {
    /// Indices into the scene's lights.
    lights: Vec<usize>,
    /// Index into `DeferredLightingPass::pipelines`.
    pipeline: usize,
    vertex_offset: u64,
    vertex_count: u32,
    block_offset: u32,
}

/// Fields drop in order: pipelines before their layout, sets before their
/// pool and layouts.
pub struct DeferredLightingPass {
    groups: Vec<GroupDraw>,
    pipelines: Vec<GraphicsPipeline>,
    layout: PipelineLayout,
    lights_set: DescriptorSet,
    _pool: DescriptorPool,
    _lights_layout: DescriptorSetLayout,
    inputs: InputAttachments,
    vertices: Buffer,
    /// Written again when the view moves: light positions are relative to
    /// the camera.
    light_blocks: Buffer,
}

/// A tile group's lights as the shader reads them, for `scene`'s camera.
fn group_block(scene: &crate::scene::Scene, lights: &[usize]) -> Vec<u8> {
    let lights: Vec<GpuLight> = lights
        .iter()
        .map(|&l| scene_light(scene, l, scene.camera.eye))
        .collect();
    bytemuck::cast_slice(&lights).to_vec()
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "lighting"
    }

    /// With deferred lighting: the G-buffer and depth lit into the target.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        use attachment::*;
        shape.deferred.then(|| {
            PassIo::subpass(
                vec![shape.target],
                Some((DEPTH, DepthUse::Test)),
                vec![ALBEDO, NORMAL, MATERIAL, DEPTH],
            )
        })
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        create(setup)
    }
}

fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let ctx = setup.ctx;
    let resources = setup.scene_resources()?;
    let TileGroups {
        vertices: mut vertex_data,
        blocks,
        mut groups,
    } = tile_groups(setup);
    let (block_bytes, offsets, block_range) =
        pack_blocks(ctx, &blocks, 0, |i| format!("screen tile group {i}"))?;
    for (g, offset) in groups.iter_mut().zip(offsets) {
        g.block_offset = offset;
    }
    if vertex_data.is_empty() {
        // Buffers cannot be empty; with no lit tile there is nothing to draw.
        vertex_data.push([0.0; 2]);
    }
    let vertices = Buffer::with_data(
        ctx,
        "light tiles",
        bytemuck::cast_slice(&vertex_data),
        BufferUsage::Geometry,
    )?;
    let light_blocks = Buffer::with_data(ctx, "tile lights", &block_bytes, BufferUsage::Uniform)?;

    let lights_layout = DescriptorSetLayout::new(
        ctx,
        &[DescriptorBinding {
            binding: 0,
            kind: DescriptorType::UNIFORM_BUFFER_DYNAMIC,
            stages: ShaderStageFlags::FRAGMENT,
        }],
    )?;
    let inputs = InputAttachments::declared(setup)?;
    let pool = DescriptorPool::for_layouts(ctx, &[&lights_layout])?;
    let lights_set = pool.allocate(&lights_layout)?;
    lights_set.write_buffer(
        0,
        DescriptorType::UNIFORM_BUFFER_DYNAMIC,
        &light_blocks,
        block_range,
    );
    let layout = PipelineLayout::new(
        ctx,
        &[&resources.frame_layout, &lights_layout, &inputs.layout],
    )?;
    let pipelines = create_pipelines(setup, resources, &layout, &mut groups)?;
    Ok(Box::new(DeferredLightingPass {
        groups,
        pipelines,
        layout,
        lights_set,
        _pool: pool,
        _lights_layout: lights_layout,
        inputs,
        vertices,
        light_blocks,
    }))
}

/// The tile groups' draws (their pipelines and block offsets not yet
/// set), vertices and light blocks.
struct TileGroups {
    /// Each group's tiles as two triangles per rectangle, in NDC.
    vertices: Vec<[f32; 2]>,
    /// Each group's lights as one block.
    blocks: Vec<Vec<u8>>,
    groups: Vec<GroupDraw>,
}

fn tile_groups(setup: &PassSetup<'_>) -> TileGroups {
    let plan = setup.plan;
    let (w, h) = (plan.width as f32, plan.height as f32);
    let mut vertex_data: Vec<[f32; 2]> = Vec::new();
    let mut blocks = Vec::new();
    let mut groups = Vec::new();
    for group in &plan.tile_groups {
        let first = vertex_data.len();
        for r in &group.rects {
            let x0 = r.x0 as f32 / w * 2.0 - 1.0;
            let x1 = r.x1 as f32 / w * 2.0 - 1.0;
            let y0 = r.y0 as f32 / h * 2.0 - 1.0;
            let y1 = r.y1 as f32 / h * 2.0 - 1.0;
            vertex_data.extend([[x0, y0], [x1, y0], [x1, y1], [x0, y0], [x1, y1], [x0, y1]]);
        }
        blocks.push(group_block(setup.scene, &group.lights));
        groups.push(GroupDraw {
            lights: group.lights.clone(),
            pipeline: 0,
            vertex_offset: (first * std::mem::size_of::<[f32; 2]>()) as u64,
            vertex_count: (vertex_data.len() - first) as u32,
            block_offset: 0,
        });
    }
    TileGroups {
        vertices: vertex_data,
        blocks,
        groups,
    }
}

/// The groups' pipelines, each group's index into them set.
fn create_pipelines(
    setup: &PassSetup<'_>,
    resources: &SceneResources,
    layout: &PipelineLayout,
    groups: &mut [GroupDraw],
) -> Result<Vec<GraphicsPipeline>, RenderError> {
    let ctx = setup.ctx;
    let vert = ShaderModule::new(ctx, shaders::TILES_VERT.base())?;
    let frag = ShaderModule::new(ctx, shaders::DEFERRED_LIGHTING_FRAG.base())?;
    let attributes = [VertexAttribute {
        location: 0,
        format: Format::R32G32_SFLOAT,
        offset: 0,
    }];
    // Static lights give each group that fits its own pipeline; past the
    // limit, and for groups too large for them, groups share one per light
    // count.
    let fitting = groups.iter().filter(|g| static_lights::fits(&g.lights));
    let static_lights = static_lights::enabled(setup.scene, fitting.count());
    let mut pipelines = Vec::new();
    let mut by_count: BTreeMap<usize, usize> = BTreeMap::new();
    for g in groups.iter_mut() {
        let count = g.lights.len();
        let carried = static_lights && static_lights::fits(&g.lights);
        if !carried {
            if let Some(&p) = by_count.get(&count) {
                g.pipeline = p;
                continue;
            }
            by_count.insert(count, pipelines.len());
        }
        g.pipeline = pipelines.len();
        let mut specialization = vec![
            (SPEC_LIGHT_COUNT, count as u32),
            (SPEC_LIGHT_ARRAY_LENGTH, count.max(1) as u32),
        ];
        specialization.extend(static_lights::constants(
            setup.scene,
            resources.light_anchor,
            carried.then_some(&g.lights[..]),
        ));
        let pipeline = GraphicsPipeline::new(
            ctx,
            layout,
            &setup.render_pass()?.render_pass,
            &GraphicsPipelineDesc {
                vertex_shader: &vert,
                fragment_shader: Some(&frag),
                specialization: &specialization,
                vertex_stride: std::mem::size_of::<[f32; 2]>() as u32,
                vertex_attributes: &attributes,
                instance_stride: 0,
                instance_attributes: &[],
                cull_mode: CullModeFlags::NONE,
                // Tiles at depth 0 (the far plane): only pixels whose stored
                // depth is nearer, i.e. that hold a surface, pass.
                depth_test: Some(CompareOp::LESS),
                depth_write: false,
                depth_bias: None,
                blend: &[Blend::Add],
                subpass: setup.subpass,
            },
        )?;
        pipelines.push(pipeline);
    }
    Ok(pipelines)
}

impl RecordPass for DeferredLightingPass {
    /// Rewrites the tile groups' lights for the new camera (the plan keeps
    /// the same tile groups, or the renderer is built again).
    fn set_view(
        &mut self,
        scene: &crate::scene::Scene,
        _plan: &crate::render::FramePlan,
    ) -> Result<(), RenderError> {
        for g in &self.groups {
            let block = group_block(scene, &g.lights);
            self.light_blocks.write(g.block_offset as usize, &block);
        }
        Ok(())
    }

    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let Some(resources) = frame.scene else {
            return Ok(());
        };
        let mut bound = None;
        for g in &self.groups {
            if bound != Some(g.pipeline) {
                cmd.bind_pipeline(&self.pipelines[g.pipeline]);
                if bound.is_none() {
                    cmd.bind_descriptor_set(&self.layout, 0, &resources.frame_set, &[]);
                    cmd.bind_descriptor_set(&self.layout, 2, &self.inputs.set, &[]);
                }
                bound = Some(g.pipeline);
            }
            cmd.bind_descriptor_set(&self.layout, 1, &self.lights_set, &[g.block_offset]);
            cmd.bind_vertex_buffer(&self.vertices, g.vertex_offset);
            cmd.draw(g.vertex_count);
        }
        Ok(())
    }
}
