//! Shader modules, pipeline layouts, graphics and compute pipelines.

use super::{Context, DescriptorSetLayout, RenderPass, VkError};
use ash::vk;
use std::sync::Arc;

pub struct ShaderModule {
    ctx: Arc<Context>,
    handle: vk::ShaderModule,
}

impl ShaderModule {
    /// `spirv` is the bytes of a SPIR-V binary (embedded at build time).
    pub fn new(ctx: &Arc<Context>, spirv: &[u8]) -> Result<ShaderModule, VkError> {
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .map_err(|e| VkError::Spirv(e.to_string()))?;
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: valid device; words is aligned SPIR-V.
        let handle = unsafe { ctx.device.create_shader_module(&info, None) }?;
        Ok(ShaderModule {
            ctx: ctx.clone(),
            handle,
        })
    }
}

impl Drop for ShaderModule {
    fn drop(&mut self) {
        // SAFETY: modules are only needed during pipeline creation.
        unsafe { self.ctx.device.destroy_shader_module(self.handle, None) };
    }
}

pub struct PipelineLayout {
    ctx: Arc<Context>,
    pub(crate) handle: vk::PipelineLayout,
}

impl PipelineLayout {
    pub fn new(
        ctx: &Arc<Context>,
        sets: &[&DescriptorSetLayout],
    ) -> Result<PipelineLayout, VkError> {
        let handles: Vec<_> = sets.iter().map(|s| s.handle).collect();
        let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&handles);
        // SAFETY: valid device and set layouts.
        let handle = unsafe { ctx.device.create_pipeline_layout(&info, None) }?;
        Ok(PipelineLayout {
            ctx: ctx.clone(),
            handle,
        })
    }
}

impl Drop for PipelineLayout {
    fn drop(&mut self) {
        // SAFETY: pipelines using it are idle.
        unsafe { self.ctx.device.destroy_pipeline_layout(self.handle, None) };
    }
}

/// One vertex attribute: shader location, format, byte offset.
#[derive(Clone, Copy, Debug)]
pub struct VertexAttribute {
    pub location: u32,
    pub format: vk::Format,
    pub offset: u32,
}

/// The vertex binding per-instance attributes are read from
/// ([`CommandBuffer::bind_instances`](super::CommandBuffer::bind_instances)).
pub const INSTANCE_BINDING: u32 = 1;

/// Everything that varies between the renderer's pipelines.
pub struct GraphicsPipelineDesc<'a> {
    pub vertex_shader: &'a ShaderModule,
    /// `None` for a depth-only pipeline (a depth pre-pass): a subpass
    /// without colour targets, nothing shaded per fragment, `blend` empty.
    pub fragment_shader: Option<&'a ShaderModule>,
    /// Specialization constants (id, value), given to both stages.
    pub specialization: &'a [(u32, u32)],
    /// Per-vertex stride and attributes; stride 0 means no vertex input
    /// (full-screen triangle generated from the vertex index).
    pub vertex_stride: u32,
    pub vertex_attributes: &'a [VertexAttribute],
    /// Per-instance stride and attributes, from vertex binding 1; stride 0
    /// means none.
    pub instance_stride: u32,
    pub instance_attributes: &'a [VertexAttribute],
    pub cull_mode: vk::CullModeFlags,
    /// The depth test's comparison, `None` for no test.
    pub depth_test: Option<vk::CompareOp>,
    pub depth_write: bool,
    /// Depth bias `(constant, slope)` added to each fragment's depth (a
    /// shadow map's), `None` for none.
    pub depth_bias: Option<(f32, f32)>,
    /// One blend state per colour target of the subpass, in order.
    pub blend: &'a [Blend],
    pub subpass: u32,
}

/// How a pipeline writes one colour target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// The fragment's colour replaces the target's.
    Replace,
    /// Straight alpha blending (src-alpha, one-minus-src-alpha).
    Alpha,
    /// Added to the target (light accumulation).
    Add,
}

pub struct GraphicsPipeline {
    ctx: Arc<Context>,
    pub(crate) handle: vk::Pipeline,
}

impl GraphicsPipeline {
    pub fn new(
        ctx: &Arc<Context>,
        layout: &PipelineLayout,
        pass: &RenderPass,
        desc: &GraphicsPipelineDesc<'_>,
    ) -> Result<GraphicsPipeline, VkError> {
        let (entries, data) = specialization_data(desc.specialization);
        let spec = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(&data);
        let stage = |flags, module: &ShaderModule| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(flags)
                .module(module.handle)
                .name(c"main")
                .specialization_info(&spec)
        };
        let mut stages = vec![stage(vk::ShaderStageFlags::VERTEX, desc.vertex_shader)];
        if let Some(fragment) = desc.fragment_shader {
            stages.push(stage(vk::ShaderStageFlags::FRAGMENT, fragment));
        }
        let mut bindings = vec![vk::VertexInputBindingDescription {
            binding: 0,
            stride: desc.vertex_stride,
            input_rate: vk::VertexInputRate::VERTEX,
        }];
        if desc.instance_stride != 0 {
            bindings.push(vk::VertexInputBindingDescription {
                binding: INSTANCE_BINDING,
                stride: desc.instance_stride,
                input_rate: vk::VertexInputRate::INSTANCE,
            });
        }
        let attribute = |binding: u32| {
            move |a: &VertexAttribute| vk::VertexInputAttributeDescription {
                location: a.location,
                binding,
                format: a.format,
                offset: a.offset,
            }
        };
        let attributes: Vec<_> = desc
            .vertex_attributes
            .iter()
            .map(attribute(0))
            .chain(
                desc.instance_attributes
                    .iter()
                    .map(attribute(INSTANCE_BINDING)),
            )
            .collect();
        let vertex_input = if desc.vertex_stride == 0 {
            vk::PipelineVertexInputStateCreateInfo::default()
        } else {
            vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&bindings)
                .vertex_attribute_descriptions(&attributes)
        };
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull_mode)
            // Counter-clockwise in framebuffer space (y down after the
            // projection's flip) is front.
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let raster = match desc.depth_bias {
            Some((constant, slope)) => raster
                .depth_bias_enable(true)
                .depth_bias_constant_factor(constant)
                .depth_bias_slope_factor(slope),
            None => raster,
        };
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_test.is_some())
            .depth_write_enable(desc.depth_write)
            .depth_compare_op(desc.depth_test.unwrap_or(vk::CompareOp::ALWAYS));
        let blend_attachments: Vec<_> = desc.blend.iter().map(blend_state).collect();
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout.handle)
            .render_pass(pass.handle)
            .subpass(desc.subpass);
        // SAFETY: all state structs are locals alive for the call; the
        // shaders, layout, pass and pipeline cache are valid objects of
        // this device (the cache is internally synchronised by the driver).
        let handle = unsafe {
            ctx.device
                .create_graphics_pipelines(ctx.pipeline_cache(), &[info], None)
        }
        .map_err(|(_, e)| VkError::Api(e))?[0];
        Ok(GraphicsPipeline {
            ctx: ctx.clone(),
            handle,
        })
    }
}

/// The colour-blend state of one target written as `blend` says.
fn blend_state(blend: &Blend) -> vk::PipelineColorBlendAttachmentState {
    let state = vk::PipelineColorBlendAttachmentState::default()
        .color_write_mask(vk::ColorComponentFlags::RGBA);
    match blend {
        Blend::Replace => state,
        Blend::Alpha => state
            .blend_enable(true)
            .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .alpha_blend_op(vk::BlendOp::ADD),
        Blend::Add => state
            .blend_enable(true)
            .src_color_blend_factor(vk::BlendFactor::ONE)
            .dst_color_blend_factor(vk::BlendFactor::ONE)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ZERO)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE)
            .alpha_blend_op(vk::BlendOp::ADD),
    }
}

impl Drop for GraphicsPipeline {
    fn drop(&mut self) {
        // SAFETY: no pending command buffer uses it.
        unsafe { self.ctx.device.destroy_pipeline(self.handle, None) };
    }
}

/// Map entries and data for specialization constants `(id, value)`, each
/// a 32-bit value at its index's offset.
fn specialization_data(constants: &[(u32, u32)]) -> (Vec<vk::SpecializationMapEntry>, Vec<u8>) {
    let entries = constants
        .iter()
        .enumerate()
        .map(|(i, (id, _))| vk::SpecializationMapEntry {
            constant_id: *id,
            offset: (i * 4) as u32,
            size: 4,
        })
        .collect();
    let data = constants
        .iter()
        .flat_map(|(_, v)| v.to_ne_bytes())
        .collect();
    (entries, data)
}

pub struct ComputePipeline {
    ctx: Arc<Context>,
    pub(crate) handle: vk::Pipeline,
}

impl ComputePipeline {
    /// The compute pipeline of `shader` (entry point `main`) with
    /// specialization constants `(id, value)`.
    pub fn new(
        ctx: &Arc<Context>,
        layout: &PipelineLayout,
        shader: &ShaderModule,
        specialization: &[(u32, u32)],
    ) -> Result<ComputePipeline, VkError> {
        let (entries, data) = specialization_data(specialization);
        let spec = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(&data);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(shader.handle)
            .name(c"main")
            .specialization_info(&spec);
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout.handle);
        // SAFETY: the stage and specialization structs are locals alive
        // for the call; shader, layout and pipeline cache are valid objects
        // of this device (the cache is internally synchronised by the
        // driver).
        let handle = unsafe {
            ctx.device
                .create_compute_pipelines(ctx.pipeline_cache(), &[info], None)
        }
        .map_err(|(_, e)| VkError::Api(e))?[0];
        Ok(ComputePipeline {
            ctx: ctx.clone(),
            handle,
        })
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        // SAFETY: no pending command buffer uses it.
        unsafe { self.ctx.device.destroy_pipeline(self.handle, None) };
    }
}
