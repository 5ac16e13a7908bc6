//! GPU resources for one scene and the recorded frame.
//!
//! Data flows one way: `Scene` → `FramePlan` → the resources built here →
//! one command buffer recorded once → submitted per frame → images read back.

use super::frame::TimedFrame;
use super::gpu_types::{FrameUniforms, GpuLight, ObjectHeader};
use super::plan::{Draw, FramePlan, Pass, PipelineKey};
use super::RenderError;
use crate::mesh::{Mesh, Vertex};
use crate::scene::{HdrFormat, Light, Scene, TextureFilter, ToneMap, ToneMapOperator};
use crate::shaders;
use crate::vk::{
    self, AccessFlags, Buffer, BufferUsage, CommandBuffer, Context, CullModeFlags,
    DescriptorBinding, DescriptorPool, DescriptorSet, DescriptorSetLayout, DescriptorType, Format,
    GraphicsPipeline, GraphicsPipelineDesc, Image, ImageAspectFlags, ImageBarrier, ImageDesc,
    ImageLayout, ImageUsageFlags, PipelineLayout, PipelineStageFlags, RenderPass, RenderPassDesc,
    Sampler, SamplerFilter, ShaderModule, ShaderStageFlags, VertexAttribute,
};
use std::collections::BTreeMap;
use std::sync::Arc;

const OUTPUT_FORMAT: Format = Format::R8G8B8A8_SRGB;
const DEPTH_FORMAT: Format = Format::D32_SFLOAT;
const TEXTURE_FORMAT: Format = Format::R8G8B8A8_SRGB;

/// Timing of one submitted frame.
#[derive(Clone, Debug)]
pub struct FrameTiming {
    /// GPU time per pass (in `FramePlan::passes` order), in milliseconds;
    /// empty when the device has no timestamps.
    pub pass_ms: Vec<f64>,
    /// CPU time from submit to fence signalled, in milliseconds.
    pub cpu_ms: f64,
}

/// A read-back image, row-major, top row first, RGBA.
#[derive(Clone, Debug)]
pub struct Pixels<T> {
    pub width: u32,
    pub height: u32,
    pub data: Vec<T>,
}

/// One geometry range inside the shared geometry buffer.
struct GeometryRange {
    vertex_offset: u64,
    index_offset: u64,
    index_count: u32,
}

/// Everything on the GPU for one scene. Fields drop in declaration order;
/// the command buffer goes first, the context (inside each wrapper) last.
pub struct Renderer {
    frame: TimedFrame,
    output_readback: Buffer,
    hdr_readback: Option<Buffer>,
    _descriptor_sets: Vec<DescriptorSet>,
    _descriptor_pool: DescriptorPool,
    _pipelines: Vec<GraphicsPipeline>,
    _pipeline_layouts: Vec<PipelineLayout>,
    _set_layouts: Vec<DescriptorSetLayout>,
    _framebuffer: vk::Framebuffer,
    _render_pass: RenderPass,
    _attachments: Vec<Image>,
    _textures: Vec<Image>,
    _sampler: Option<Sampler>,
    _buffers: Vec<Buffer>,
    plan: FramePlan,
    ctx: Arc<Context>,
}

impl Renderer {
    /// The renderer for `scene`; `keep_hdr` reads back the linear HDR
    /// image as well as the tone-mapped output.
    pub fn new(ctx: &Arc<Context>, scene: &Scene, keep_hdr: bool) -> Result<Renderer, RenderError> {
        let meshes: Vec<Mesh> = (0..scene.objects.len())
            .map(|i| scene.object_mesh(i))
            .collect();
        let plan = FramePlan::new(scene, &meshes, keep_hdr);
        Renderer::build(ctx, scene, &meshes, plan, None)
    }

    /// A renderer that tone-maps `image` (linear RGBA, any values,
    /// including Inf, NaN and negatives) with the scene's tone-map subpass.
    pub fn for_hdr_image(
        ctx: &Arc<Context>,
        tone_map: ToneMap,
        image: &Pixels<f32>,
    ) -> Result<Renderer, RenderError> {
        let expected = image.width as usize * image.height as usize * 4;
        if image.width == 0 || image.height == 0 || image.data.len() != expected {
            return Err(RenderError::InvalidImage(format!(
                "{}x{} RGBA needs {expected} values, got {}",
                image.width,
                image.height,
                image.data.len()
            )));
        }
        let plan = FramePlan::for_hdr_image(image.width, image.height, true);
        let scene = Scene::empty(tone_map, image.width, image.height);
        Renderer::build(ctx, &scene, &[], plan, Some(image))
    }

    fn build(
        ctx: &Arc<Context>,
        scene: &Scene,
        meshes: &[Mesh],
        plan: FramePlan,
        hdr_input: Option<&Pixels<f32>>,
    ) -> Result<Renderer, RenderError> {
        let keep_hdr = plan.keep_hdr;
        let (width, height) = (plan.width, plan.height);

        // Attachments.
        let hdr_format = match plan.hdr_format {
            HdrFormat::Rgba16F => Format::R16G16B16A16_SFLOAT,
            HdrFormat::Rgba32F => Format::R32G32B32A32_SFLOAT,
        };
        let attachment = |name, format, usage, aspect| {
            Image::new(
                ctx,
                name,
                ImageDesc {
                    width,
                    height,
                    format,
                    usage,
                    mip_levels: 1,
                    aspect,
                },
            )
        };
        let mut hdr_usage = ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::INPUT_ATTACHMENT;
        if keep_hdr {
            hdr_usage |= ImageUsageFlags::TRANSFER_SRC;
        }
        if plan.loads_hdr() {
            hdr_usage |= ImageUsageFlags::TRANSFER_DST;
        }
        let hdr = attachment("hdr", hdr_format, hdr_usage, ImageAspectFlags::COLOR)?;
        let depth = attachment(
            "depth",
            DEPTH_FORMAT,
            ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            ImageAspectFlags::DEPTH,
        )?;
        let output = attachment(
            "output",
            OUTPUT_FORMAT,
            ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::TRANSFER_SRC,
            ImageAspectFlags::COLOR,
        )?;
        let render_pass = RenderPass::new(
            ctx,
            RenderPassDesc {
                hdr_format,
                depth_format: DEPTH_FORMAT,
                output_format: OUTPUT_FORMAT,
                keep_hdr,
                load_hdr: plan.loads_hdr(),
            },
        )?;
        let framebuffer = vk::Framebuffer::new(ctx, &render_pass, [&hdr, &depth, &output])?;

        // Geometry: every mesh in one buffer, vertices then indices.
        let (geometry, ranges) = upload_geometry(ctx, meshes)?;
        let hdr_upload = match hdr_input {
            Some(image) => Some(Buffer::with_data(
                ctx,
                "hdr upload",
                bytemuck::cast_slice(&image.data),
                BufferUsage::Upload,
            )?),
            None => None,
        };

        // Per-frame uniforms.
        let aspect = width as f32 / height as f32;
        let frame = FrameUniforms {
            view_projection: scene.camera.view_projection(aspect).to_cols_array_2d(),
            camera_position: scene.camera.eye.extend(1.0).to_array(),
            ambient: scene.ambient.extend(0.0).to_array(),
        };
        let frame_buffer = Buffer::with_data(
            ctx,
            "frame",
            bytemuck::bytes_of(&frame),
            BufferUsage::Uniform,
        )?;

        // Per-object blocks, each at an aligned offset, all read through one
        // dynamic storage descriptor whose range fits the largest block.
        let blocks: Vec<Vec<u8>> = (0..scene.objects.len())
            .map(|i| object_block(scene, i, plan.draws().find(|d| d.object == i)))
            .collect();
        let alignment = ctx.uniform_offset_alignment().max(16);
        // Every block is padded to room for at least one light, the
        // shortest array the shaders can declare.
        let min_block =
            (std::mem::size_of::<ObjectHeader>() + std::mem::size_of::<GpuLight>()) as u64;
        let block_range = blocks
            .iter()
            .map(|b| b.len() as u64)
            .max()
            .unwrap_or(0)
            .max(min_block);
        if block_range > ctx.max_uniform_range() {
            return Err(RenderError::TooManyLights {
                lights: blocks
                    .iter()
                    .map(|b| {
                        (b.len() - std::mem::size_of::<ObjectHeader>())
                            / std::mem::size_of::<GpuLight>()
                    })
                    .max()
                    .unwrap_or(0),
                max: (ctx.max_uniform_range() as usize - std::mem::size_of::<ObjectHeader>())
                    / std::mem::size_of::<GpuLight>(),
            });
        }
        let mut block_offsets = Vec::with_capacity(blocks.len());
        let mut object_bytes = Vec::new();
        for b in &blocks {
            block_offsets.push(object_bytes.len() as u32);
            object_bytes.extend_from_slice(b);
            object_bytes.resize(
                (object_bytes.len() as u64).next_multiple_of(alignment) as usize,
                0,
            );
        }
        // The last block's descriptor range must still fit in the buffer.
        let last = block_offsets.last().copied().unwrap_or(0) as u64;
        object_bytes.resize(object_bytes.len().max((last + block_range) as usize), 0);
        let object_buffer = Buffer::with_data(ctx, "objects", &object_bytes, BufferUsage::Uniform)?;

        // Textures, only if some material has one.
        let sampler = if plan.textures.is_empty() {
            None
        } else {
            Some(Sampler::new(
                ctx,
                match scene.output.texture_filter {
                    TextureFilter::Nearest => SamplerFilter::Nearest,
                    TextureFilter::Bilinear => SamplerFilter::Bilinear,
                    TextureFilter::Trilinear => SamplerFilter::Trilinear,
                },
                16,
            )?)
        };
        let textures = plan
            .textures
            .iter()
            .map(|p| load_texture(ctx, p))
            .collect::<Result<Vec<_>, _>>()?;

        // Descriptor set layouts: frame (0), object (1), texture (2, only
        // when used), tone-map input.
        let all_stages = ShaderStageFlags::VERTEX | ShaderStageFlags::FRAGMENT;
        let frame_layout = DescriptorSetLayout::new(
            ctx,
            &[DescriptorBinding {
                binding: 0,
                kind: DescriptorType::UNIFORM_BUFFER,
                stages: all_stages,
            }],
        )?;
        let object_layout = DescriptorSetLayout::new(
            ctx,
            &[DescriptorBinding {
                binding: 0,
                kind: DescriptorType::UNIFORM_BUFFER_DYNAMIC,
                stages: all_stages,
            }],
        )?;
        let tonemap_layout = DescriptorSetLayout::new(
            ctx,
            &[DescriptorBinding {
                binding: 0,
                kind: DescriptorType::INPUT_ATTACHMENT,
                stages: ShaderStageFlags::FRAGMENT,
            }],
        )?;
        let texture_layout = if textures.is_empty() {
            None
        } else {
            Some(DescriptorSetLayout::new(
                ctx,
                &[DescriptorBinding {
                    binding: 0,
                    kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
                    stages: ShaderStageFlags::FRAGMENT,
                }],
            )?)
        };

        let mut pool_layouts = vec![&frame_layout, &object_layout, &tonemap_layout];
        if let Some(t) = &texture_layout {
            pool_layouts.extend(std::iter::repeat_n(t, textures.len()));
        }
        let pool = DescriptorPool::for_layouts(ctx, &pool_layouts)?;
        let frame_set = pool.allocate(&frame_layout)?;
        frame_set.write_buffer(
            0,
            DescriptorType::UNIFORM_BUFFER,
            &frame_buffer,
            std::mem::size_of::<FrameUniforms>() as u64,
        );
        let object_set = pool.allocate(&object_layout)?;
        object_set.write_buffer(
            0,
            DescriptorType::UNIFORM_BUFFER_DYNAMIC,
            &object_buffer,
            block_range,
        );
        let tonemap_set = pool.allocate(&tonemap_layout)?;
        tonemap_set.write_input_attachment(0, &hdr);
        let mut texture_sets = Vec::new();
        if let (Some(layout), Some(sampler)) = (&texture_layout, &sampler) {
            for t in &textures {
                let set = pool.allocate(layout)?;
                set.write_sampled_image(0, t, sampler);
                texture_sets.push(set);
            }
        }

        // Pipeline layouts and pipelines.
        let plain_layout = PipelineLayout::new(ctx, &[&frame_layout, &object_layout])?;
        let textured_layout = match &texture_layout {
            Some(t) => Some(PipelineLayout::new(
                ctx,
                &[&frame_layout, &object_layout, t],
            )?),
            None => None,
        };
        let tonemap_pipeline_layout = PipelineLayout::new(ctx, &[&tonemap_layout])?;

        // The shader pair without texture, and with it only when needed.
        let plain_shaders = (
            ShaderModule::new(ctx, shaders::OBJECT_VERT)?,
            ShaderModule::new(ctx, shaders::OBJECT_FRAG)?,
        );
        let textured_shaders = if textures.is_empty() {
            None
        } else {
            Some((
                ShaderModule::new(ctx, shaders::OBJECT_VERT_TEXTURED)?,
                ShaderModule::new(ctx, shaders::OBJECT_FRAG_TEXTURED)?,
            ))
        };
        let mut pipelines: BTreeMap<PipelineKey, GraphicsPipeline> = BTreeMap::new();
        for key in plan.pipelines() {
            let (layout, (vert, frag)) = if key.textured {
                (
                    textured_layout
                        .as_ref()
                        .expect("textured layout exists when a draw is textured"),
                    textured_shaders
                        .as_ref()
                        .expect("textured shaders exist when a draw is textured"),
                )
            } else {
                (&plain_layout, &plain_shaders)
            };
            let attributes = vertex_attributes(key.textured);
            let pipeline = GraphicsPipeline::new(
                ctx,
                layout,
                &render_pass,
                &GraphicsPipelineDesc {
                    vertex_shader: vert,
                    fragment_shader: frag,
                    specialization: &[
                        (0, key.shading as u32),
                        (1, key.lights),
                        (2, key.lights.max(1)),
                    ],
                    vertex_stride: std::mem::size_of::<Vertex>() as u32,
                    vertex_attributes: &attributes,
                    cull_mode: CullModeFlags::BACK,
                    depth_test: true,
                    // Transparent surfaces test against opaque depth but do
                    // not hide each other; they are sorted instead.
                    depth_write: !key.blended,
                    alpha_blend: key.blended,
                    subpass: 0,
                },
            )?;
            pipelines.insert(key, pipeline);
        }
        let fullscreen = ShaderModule::new(ctx, shaders::FULLSCREEN_VERT)?;
        let tonemap_frag = ShaderModule::new(ctx, shaders::TONEMAP_FRAG)?;
        let operator = match scene.tone_map.operator {
            ToneMapOperator::Reinhard => 0,
            ToneMapOperator::Aces => 1,
        };
        let tonemap_pipeline = GraphicsPipeline::new(
            ctx,
            &tonemap_pipeline_layout,
            &render_pass,
            &GraphicsPipelineDesc {
                vertex_shader: &fullscreen,
                fragment_shader: &tonemap_frag,
                specialization: &[(0, operator), (1, scene.tone_map.exposure.to_bits())],
                vertex_stride: 0,
                vertex_attributes: &[],
                cull_mode: CullModeFlags::NONE,
                depth_test: false,
                depth_write: false,
                alpha_blend: false,
                subpass: 1,
            },
        )?;

        // Readback buffers.
        let pixels = width as u64 * height as u64;
        let output_readback =
            Buffer::new(ctx, "output readback", pixels * 4, BufferUsage::Readback)?;
        let hdr_readback = if keep_hdr {
            let texel = match plan.hdr_format {
                HdrFormat::Rgba16F => 8,
                HdrFormat::Rgba32F => 16,
            };
            Some(Buffer::new(
                ctx,
                "hdr readback",
                pixels * texel,
                BufferUsage::Readback,
            )?)
        } else {
            None
        };
        // Record the frame once; every submission replays it.
        let frame = TimedFrame::begin(ctx, plan.passes.len() as u32)?;
        let cmd = frame.cmd();
        let clears = [
            vk::clear_color([0.0; 4]),
            // Reversed-Z: the far plane is 0.
            vk::clear_depth(0.0),
            vk::clear_color([0.0; 4]),
        ];
        let record_draws = |draws: &[Draw]| {
            let mut bound: Option<PipelineKey> = None;
            for d in draws {
                let pipeline = &pipelines[&d.pipeline];
                let layout = if d.pipeline.textured {
                    textured_layout.as_ref().expect("exists for textured draws")
                } else {
                    &plain_layout
                };
                if bound != Some(d.pipeline) {
                    cmd.bind_pipeline(pipeline);
                    bound = Some(d.pipeline);
                }
                cmd.bind_descriptor_set(layout, 1, &object_set, &[block_offsets[d.object]]);
                if let Some(t) = d.texture {
                    cmd.bind_descriptor_set(layout, 2, &texture_sets[t], &[]);
                }
                let range = &ranges[d.object];
                cmd.bind_geometry(&geometry, range.vertex_offset, range.index_offset);
                cmd.draw_indexed(range.index_count);
            }
        };
        // Subpass 0 (opaque, transparent) and subpass 1 (tone map) live in
        // one render pass, begun before the first of them.
        let mut in_render_pass = false;
        let mut begin_render_pass = |cmd: &CommandBuffer| {
            if !in_render_pass {
                cmd.begin_render_pass(&render_pass, &framebuffer, &clears);
                cmd.bind_descriptor_set(&plain_layout, 0, &frame_set, &[]);
                in_render_pass = true;
            }
        };
        for pass in &plan.passes {
            match pass {
                Pass::HdrUpload => {
                    let upload = hdr_upload
                        .as_ref()
                        .expect("the plan uploads only with an input image");
                    record_hdr_upload(cmd, upload, &hdr);
                }
                Pass::Opaque => {
                    begin_render_pass(cmd);
                    record_draws(&plan.opaque);
                }
                Pass::Transparent => {
                    begin_render_pass(cmd);
                    record_draws(&plan.transparent);
                }
                Pass::ToneMap => {
                    begin_render_pass(cmd);
                    cmd.next_subpass();
                    cmd.bind_pipeline(&tonemap_pipeline);
                    cmd.bind_descriptor_set(&tonemap_pipeline_layout, 0, &tonemap_set, &[]);
                    cmd.draw(3);
                    cmd.end_render_pass();
                }
                Pass::Readback => {
                    cmd.copy_image_to_buffer(&output, &output_readback);
                    if let Some(buffer) = &hdr_readback {
                        cmd.copy_image_to_buffer(&hdr, buffer);
                    }
                }
            }
            frame.stamp();
        }
        let frame = frame.finish()?;

        let mut set_layouts = vec![frame_layout, object_layout, tonemap_layout];
        set_layouts.extend(texture_layout);
        let mut pipeline_layouts = vec![plain_layout, tonemap_pipeline_layout];
        pipeline_layouts.extend(textured_layout);
        let mut all_pipelines: Vec<GraphicsPipeline> = pipelines.into_values().collect();
        all_pipelines.push(tonemap_pipeline);
        let mut descriptor_sets = vec![frame_set, object_set, tonemap_set];
        descriptor_sets.extend(texture_sets);

        Ok(Renderer {
            frame,
            output_readback,
            hdr_readback,
            _descriptor_sets: descriptor_sets,
            _descriptor_pool: pool,
            _pipelines: all_pipelines,
            _pipeline_layouts: pipeline_layouts,
            _set_layouts: set_layouts,
            _framebuffer: framebuffer,
            _render_pass: render_pass,
            _attachments: vec![hdr, depth, output],
            _textures: textures,
            _sampler: sampler,
            _buffers: [geometry, frame_buffer, object_buffer]
                .into_iter()
                .chain(hdr_upload)
                .collect(),
            plan,
            ctx: ctx.clone(),
        })
    }

    pub fn plan(&self) -> &FramePlan {
        &self.plan
    }

    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    /// Submits the recorded frame and waits for it.
    pub fn render_frame(&mut self) -> Result<FrameTiming, RenderError> {
        self.frame.submit()
    }

    /// The tone-mapped sRGB output of the last frame.
    pub fn output(&self) -> Pixels<u8> {
        Pixels {
            width: self.plan.width,
            height: self.plan.height,
            data: self.output_readback.read().to_vec(),
        }
    }

    /// The linear HDR image of the last frame (before tone mapping), when
    /// the renderer was created with `keep_hdr`.
    pub fn hdr(&self) -> Option<Pixels<f32>> {
        let buffer = self.hdr_readback.as_ref()?;
        let bytes = buffer.read();
        let data = match self.plan.hdr_format {
            HdrFormat::Rgba16F => bytes
                .chunks_exact(2)
                .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32())
                .collect(),
            HdrFormat::Rgba32F => bytes
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        };
        Some(Pixels {
            width: self.plan.width,
            height: self.plan.height,
            data,
        })
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // Nothing may be pending when the resources go; render_frame always
        // waits, but a frame interrupted by an error might not have.
        let _ = self.ctx.wait_idle();
    }
}

/// The vertex attributes a pipeline consumes: position and normal always,
/// UVs only for textured materials. (Tangents stay in the vertex format for
/// normal mapping but are not fed to shaders that do not read them.)
fn vertex_attributes(textured: bool) -> Vec<VertexAttribute> {
    let offset = |f: usize| f as u32;
    let mut attributes = vec![
        VertexAttribute {
            location: 0,
            format: Format::R32G32B32_SFLOAT,
            offset: offset(std::mem::offset_of!(Vertex, position)),
        },
        VertexAttribute {
            location: 1,
            format: Format::R32G32B32_SFLOAT,
            offset: offset(std::mem::offset_of!(Vertex, normal)),
        },
    ];
    if textured {
        attributes.push(VertexAttribute {
            location: 3,
            format: Format::R32G32_SFLOAT,
            offset: offset(std::mem::offset_of!(Vertex, uv)),
        });
    }
    attributes
}

/// Copies the uploaded HDR image into the HDR attachment and leaves it in
/// COLOR_ATTACHMENT_OPTIMAL, where the render pass loads it.
fn record_hdr_upload(cmd: &CommandBuffer, upload: &Buffer, hdr: &Image) {
    cmd.image_barrier(
        hdr,
        ImageBarrier {
            old_layout: ImageLayout::UNDEFINED,
            new_layout: ImageLayout::TRANSFER_DST_OPTIMAL,
            // The previous submission's tone-map read and readback copy.
            src_stage: PipelineStageFlags::FRAGMENT_SHADER | PipelineStageFlags::TRANSFER,
            src_access: AccessFlags::empty(),
            dst_stage: PipelineStageFlags::TRANSFER,
            dst_access: AccessFlags::TRANSFER_WRITE,
            base_mip: 0,
            mip_count: 1,
        },
    );
    cmd.copy_buffer_to_image(upload, hdr);
    cmd.image_barrier(
        hdr,
        ImageBarrier {
            old_layout: ImageLayout::TRANSFER_DST_OPTIMAL,
            new_layout: ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            src_stage: PipelineStageFlags::TRANSFER,
            src_access: AccessFlags::TRANSFER_WRITE,
            dst_stage: PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            dst_access: AccessFlags::COLOR_ATTACHMENT_READ | AccessFlags::COLOR_ATTACHMENT_WRITE,
            base_mip: 0,
            mip_count: 1,
        },
    );
}

fn upload_geometry(
    ctx: &Arc<Context>,
    meshes: &[Mesh],
) -> Result<(Buffer, Vec<GeometryRange>), RenderError> {
    let mut bytes: Vec<u8> = Vec::new();
    let mut vertex_offsets = Vec::new();
    for m in meshes {
        vertex_offsets.push(bytes.len() as u64);
        bytes.extend_from_slice(bytemuck::cast_slice(&m.vertices));
    }
    let mut ranges = Vec::new();
    for (m, vertex_offset) in meshes.iter().zip(vertex_offsets) {
        // Index data must be 4-byte aligned for UINT32 indices.
        bytes.resize(bytes.len().next_multiple_of(4), 0);
        ranges.push(GeometryRange {
            vertex_offset,
            index_offset: bytes.len() as u64,
            index_count: m.indices.len() as u32,
        });
        bytes.extend_from_slice(bytemuck::cast_slice(&m.indices));
    }
    let buffer = Buffer::with_data(ctx, "geometry", &bytes, BufferUsage::Geometry)?;
    Ok((buffer, ranges))
}

/// The per-object block: header, then exactly the lights that reach it.
fn object_block(scene: &Scene, index: usize, draw: Option<&Draw>) -> Vec<u8> {
    let object = &scene.objects[index];
    let material = &scene.materials[object.material];
    let model = object.transform.matrix();
    let normal = glam::Mat4::from_mat3(object.transform.normal_matrix());
    let lights: Vec<GpuLight> = draw
        .map(|d| {
            d.lights
                .iter()
                .map(|&l| gpu_light(&scene.lights[l]))
                .collect()
        })
        .unwrap_or_default();
    let header = ObjectHeader {
        model: model.to_cols_array_2d(),
        normal_matrix: normal.to_cols_array_2d(),
        ka: material.ka.extend(0.0).to_array(),
        kd: material.kd.extend(material.opacity).to_array(),
        ks: material.ks.extend(material.shininess).to_array(),
        counts: [lights.len() as u32, 0, 0, 0],
    };
    let mut bytes = bytemuck::bytes_of(&header).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&lights));
    bytes
}

fn gpu_light(light: &Light) -> GpuLight {
    match light {
        Light::Point {
            position,
            color,
            attenuation,
        } => GpuLight {
            position: position.extend(1.0).to_array(),
            color: color.extend(0.0).to_array(),
            attenuation: attenuation.extend(0.0).to_array(),
        },
        Light::Directional { direction, color } => GpuLight {
            position: (-*direction).extend(0.0).to_array(),
            color: color.extend(0.0).to_array(),
            attenuation: [1.0, 0.0, 0.0, 0.0],
        },
    }
}

/// Loads a PNG as an sRGB texture with a full mip chain.
fn load_texture(ctx: &Arc<Context>, path: &std::path::Path) -> Result<Image, RenderError> {
    let img = image::open(path)
        .map_err(|e| RenderError::Texture {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?
        .to_rgba8();
    let (w, h) = img.dimensions();
    let mip_levels = 32 - w.max(h).leading_zeros();
    let linear_blits = vk::supports_linear_filter(ctx, TEXTURE_FORMAT);
    let mip_levels = if linear_blits { mip_levels } else { 1 };
    let texture = Image::new(
        ctx,
        "texture",
        ImageDesc {
            width: w,
            height: h,
            format: TEXTURE_FORMAT,
            usage: ImageUsageFlags::SAMPLED
                | ImageUsageFlags::TRANSFER_DST
                | ImageUsageFlags::TRANSFER_SRC,
            mip_levels,
            aspect: ImageAspectFlags::COLOR,
        },
    )?;
    let staging = Buffer::with_data(ctx, "texture staging", img.as_raw(), BufferUsage::Upload)?;
    CommandBuffer::run_once(ctx, |cmd| {
        cmd.image_barrier(
            &texture,
            ImageBarrier {
                old_layout: ImageLayout::UNDEFINED,
                new_layout: ImageLayout::TRANSFER_DST_OPTIMAL,
                src_stage: PipelineStageFlags::TOP_OF_PIPE,
                src_access: AccessFlags::empty(),
                dst_stage: PipelineStageFlags::TRANSFER,
                dst_access: AccessFlags::TRANSFER_WRITE,
                base_mip: 0,
                mip_count: mip_levels,
            },
        );
        cmd.copy_buffer_to_image(&staging, &texture);
        cmd.generate_mipmaps(&texture);
    })?;
    Ok(texture)
}
