//! GPU resources shared by every pass that draws the scene's objects: one
//! geometry buffer, the per-frame uniforms, the per-object blocks (a
//! dynamic uniform buffer, std140) and the material maps, with one
//! material descriptor set per combination of maps a draw uses, and the
//! one pipeline layout object pipelines use (with the atmosphere's set
//! when its sun and sky light the objects).

use super::geometry::SceneGeometry;
use super::gpu_types::{GpuLight, InstanceTransform, ObjectHeader, ViewUniforms};
use super::plan::{AirLight, Draw, FramePlan, MapSlots};
use super::sky_resources::SkyResources;
use super::RenderError;
use crate::mesh::height::{encode_normal_map, GreenAxis, HeightEdge, HeightFilter, HeightMap};
use crate::mesh::Mesh;
use crate::scene::material_maps::{MapKind, MapKindInfo, MapSource, MAP_KINDS, MAP_KIND_COUNT};
use crate::scene::{placeholder_texels, Light, Scene, Texture, TextureFilter, PLACEHOLDER_TEXTURE};
use crate::shader_ids::{SHADOW_SET, SKY_SET};
use crate::vk::{
    self, Buffer, BufferUsage, CommandBuffer, Context, DescriptorBinding, DescriptorPool,
    DescriptorSet, DescriptorSetLayout, DescriptorType, Format, Image, ImageAspectFlags, ImageDesc,
    ImageUsageFlags, PipelineLayout, Sampler, SamplerFilter, ShaderStageFlags,
};
use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::sync::Arc;

/// One object's range inside the shared geometry buffer.
#[derive(Clone, Copy, Debug)]
pub struct GeometryRange {
    pub vertex_offset: u64,
    pub index_offset: u64,
    pub index_count: u32,
}

/// Fields drop in declaration order: sets before their pool, layouts after
/// the pipelines' users are gone.
pub struct SceneResources {
    pub frame_set: DescriptorSet,
    pub object_set: DescriptorSet,
    /// One material set per distinct combination of maps the draws use,
    /// by indices into `FramePlan::maps`.
    material_sets: Vec<(MapSlots, DescriptorSet)>,
    _pool: DescriptorPool,
    /// The one layout of object pipelines: frame, object and (when some
    /// draw samples an image) material sets, and, when the atmosphere
    /// lights the objects, its set (`SkyResources::set`), at the numbers
    /// in `shader_ids`.
    pub layout: PipelineLayout,
    pub frame_layout: DescriptorSetLayout,
    pub object_layout: DescriptorSetLayout,
    _material_layout: Option<DescriptorSetLayout>,
    /// An empty layout in the material set's place, when the atmosphere's
    /// set follows it and no draw samples an image (a pipeline layout
    /// numbers its sets without gaps).
    _empty_layout: Option<DescriptorSetLayout>,
    /// The maps and the 1x1 defaults the sets point at.
    _images: Vec<Image>,
    _sampler: Option<Sampler>,
    pub geometry: Buffer,
    pub ranges: Vec<GeometryRange>,
    /// Dynamic offset of each object's block.
    pub block_offsets: Vec<u32>,
    /// The world position static lights are placed from: the camera when
    /// these resources were made (`render::static_lights`).
    pub light_anchor: glam::DVec3,
    /// The instanced draws' transforms (`Instances`), when the frame has
    /// any.
    pub instances: Option<Buffer>,
    frame_buffer: Buffer,
    object_buffer: Buffer,
}

impl SceneResources {
    /// The resources of `plan`'s draws; `sky` must be present when a draw
    /// is lit by the atmosphere ([`AirLight`]), whose set its layout then
    /// includes.
    pub fn new(
        ctx: &Arc<Context>,
        scene: &Scene,
        geometry: &SceneGeometry,
        plan: &FramePlan,
        sky: Option<&SkyResources>,
        shadow: Option<&DescriptorSetLayout>,
    ) -> Result<SceneResources, RenderError> {
        let (geometry_buffer, ranges) = upload_geometry(ctx, geometry)?;
        let light_anchor = scene.camera.eye;
        let frame = ViewUniforms::new(scene, plan.width, plan.height, light_anchor);
        let frame_buffer = Buffer::with_data(
            ctx,
            "frame",
            bytemuck::bytes_of(&frame),
            BufferUsage::Uniform,
        )?;

        let (object_buffer, block_offsets, block_range) = object_blocks(ctx, scene, plan)?;
        let instances = match plan.instance_slots {
            0 => None,
            slots => {
                let size = u64::from(slots) * std::mem::size_of::<InstanceTransform>() as u64;
                let mut buffer = Buffer::new(ctx, "instances", size, BufferUsage::Instances)?;
                write_instances(&mut buffer, scene, plan);
                Some(buffer)
            }
        };
        let maps = MaterialImages::new(ctx, scene, plan)?;

        let frame_layout = uniform_layout(ctx, DescriptorType::UNIFORM_BUFFER)?;
        let object_layout = uniform_layout(ctx, DescriptorType::UNIFORM_BUFFER_DYNAMIC)?;
        let mut pool_layouts = vec![&frame_layout, &object_layout];
        if let Some(m) = &maps.layout {
            pool_layouts.extend(std::iter::repeat_n(m, maps.combinations.len()));
        }
        let pool = DescriptorPool::for_layouts(ctx, &pool_layouts)?;
        let frame_set = pool.allocate(&frame_layout)?;
        frame_set.write_buffer(
            0,
            DescriptorType::UNIFORM_BUFFER,
            &frame_buffer,
            std::mem::size_of::<ViewUniforms>() as u64,
        );
        let object_set = pool.allocate(&object_layout)?;
        object_set.write_buffer(
            0,
            DescriptorType::UNIFORM_BUFFER_DYNAMIC,
            &object_buffer,
            block_range,
        );
        let material_sets = maps.sets(&pool)?;
        let (layout, empty_layout) = pipeline_layout(
            ctx,
            plan,
            sky,
            shadow,
            [&frame_layout, &object_layout],
            maps.layout.as_ref(),
        )?;
        Ok(SceneResources {
            frame_set,
            object_set,
            material_sets,
            _pool: pool,
            layout,
            frame_layout,
            object_layout,
            _material_layout: maps.layout,
            _empty_layout: empty_layout,
            _images: maps
                .images
                .into_iter()
                .chain(maps.defaults.into_iter().flatten())
                .collect(),
            _sampler: maps.sampler,
            geometry: geometry_buffer,
            ranges,
            block_offsets,
            light_anchor,
            instances,
            frame_buffer,
            object_buffer,
        })
    }

    /// Rewrites what follows the view, between frames: the per-frame
    /// uniforms (camera) and the object blocks (their camera-relative
    /// transforms and lights), for `scene` planned as `plan`, whose draws
    /// carry the same lights as those this was created with (so every
    /// block keeps its size and offset). The sun's direction and
    /// irradiance live in the atmosphere's uniforms.
    pub fn set_view(&mut self, scene: &Scene, plan: &FramePlan) {
        let frame = ViewUniforms::new(scene, plan.width, plan.height, self.light_anchor);
        self.frame_buffer.write(0, bytemuck::bytes_of(&frame));
        let draws = draw_of_object(scene, plan);
        for (i, &offset) in self.block_offsets.iter().enumerate() {
            let block = object_block(scene, i, draws[i]);
            self.object_buffer.write(offset as usize, &block);
        }
        if let Some(buffer) = &mut self.instances {
            write_instances(buffer, scene, plan);
        }
    }

    /// The material set of a draw with these maps (indices into the
    /// plan's list), `None` for a draw without maps.
    pub fn material_set(&self, maps: &MapSlots) -> Option<&DescriptorSet> {
        self.material_sets
            .iter()
            .find(|(slots, _)| slots == maps)
            .map(|(_, set)| set)
    }

    /// Records every member of `draw` (in view or not), for the shadow
    /// pass: the instance buffer holds them all after the visible ones.
    pub fn draw_every_member(&self, cmd: &CommandBuffer, draw: &Draw) -> Result<(), RenderError> {
        let mut every = draw.clone();
        if let Some(instances) = &mut every.instances {
            instances.visible = instances.members.clone();
        }
        self.draw(cmd, &every)
    }

    /// Records `draw`'s geometry: its range of the shared buffer, drawn
    /// once or, for an instance batch, once per visible member from the
    /// instance buffer. The pipeline and sets are bound by the caller.
    pub fn draw(&self, cmd: &CommandBuffer, draw: &Draw) -> Result<(), RenderError> {
        let range = &self.ranges[draw.object];
        cmd.bind_geometry(&self.geometry, range.vertex_offset, range.index_offset);
        match &draw.instances {
            Some(instances) => {
                let buffer = self.instances.as_ref().ok_or_else(|| {
                    RenderError::Frame("an instanced draw, but no instance buffer".into())
                })?;
                cmd.bind_instances(buffer, 0);
                cmd.draw_indexed_instances(
                    range.index_count,
                    instances.visible.len() as u32,
                    instances.first,
                );
            }
            None => cmd.draw_indexed(range.index_count),
        }
        Ok(())
    }
}

/// A set layout of one uniform buffer of `kind` at binding 0, read by
/// both stages (the frame's and the objects' sets).
pub(crate) fn uniform_layout(
    ctx: &Arc<Context>,
    kind: DescriptorType,
) -> Result<DescriptorSetLayout, RenderError> {
    Ok(DescriptorSetLayout::new(
        ctx,
        &[DescriptorBinding {
            binding: 0,
            kind,
            stages: ShaderStageFlags::VERTEX | ShaderStageFlags::FRAGMENT,
        }],
    )?)
}

/// The per-object blocks, each at an aligned offset, all read through one
/// dynamic uniform-buffer descriptor whose range fits the largest: the
/// buffer, each block's offset and the range.
fn object_blocks(
    ctx: &Arc<Context>,
    scene: &Scene,
    plan: &FramePlan,
) -> Result<(Buffer, Vec<u32>, u64), RenderError> {
    let draws = draw_of_object(scene, plan);
    let blocks: Vec<Vec<u8>> = (0..scene.objects.len())
        .map(|i| object_block(scene, i, draws[i]))
        .collect();
    let (object_bytes, block_offsets, block_range) =
        pack_blocks(ctx, &blocks, std::mem::size_of::<ObjectHeader>(), |i| {
            format!("objects[{i}] \"{}\"", scene.objects[i].name)
        })?;
    let object_buffer = Buffer::with_data(ctx, "objects", &object_bytes, BufferUsage::Uniform)?;
    Ok((object_buffer, block_offsets, block_range))
}

/// The one layout of object pipelines: `sets` (frame, object), the
/// material set's layout when some draw samples a map, and the
/// atmosphere's set when it lights the objects (which `sky` must then
/// hold), after an empty layout in the material set's place when there is
/// none (a pipeline layout numbers its sets without gaps). Returns the
/// layout and that empty layout.
fn pipeline_layout(
    ctx: &Arc<Context>,
    plan: &FramePlan,
    sky: Option<&SkyResources>,
    shadow: Option<&DescriptorSetLayout>,
    sets: [&DescriptorSetLayout; 2],
    material_layout: Option<&DescriptorSetLayout>,
) -> Result<(PipelineLayout, Option<DescriptorSetLayout>), RenderError> {
    let mut slots: Vec<Option<&DescriptorSetLayout>> = sets.map(Some).to_vec();
    slots.push(material_layout);
    let air_lit = plan.draws().any(|d| d.pipeline.air != AirLight::None);
    let sky_layout = match sky {
        Some(sky) if air_lit => Some(&sky.layout),
        None if air_lit => {
            return Err(RenderError::Frame(
                "objects lit by the atmosphere, but the frame has no atmosphere resources".into(),
            ))
        }
        _ => None,
    };
    for (index, layout) in [(SKY_SET, sky_layout), (SHADOW_SET, shadow)] {
        if let Some(layout) = layout {
            slots.resize(index as usize, None);
            slots.push(Some(layout));
        }
    }
    while slots.last().is_some_and(Option::is_none) {
        slots.pop();
    }
    // Sets a pipeline does not use, below one it does, get an empty layout.
    let empty_layout = match slots.iter().any(Option::is_none) {
        true => Some(DescriptorSetLayout::new(ctx, &[])?),
        false => None,
    };
    let set_layouts: Vec<&DescriptorSetLayout> = slots
        .iter()
        .map(|slot| {
            slot.or(empty_layout.as_ref())
                .expect("an empty layout fills the gaps")
        })
        .collect();
    Ok((PipelineLayout::new(ctx, &set_layouts)?, empty_layout))
}

/// The images of the plan's maps, and what their material sets need: one
/// layout with a fixed binding per map kind and a sampler, only when some
/// draw samples a map. Each distinct combination of maps a draw uses gets
/// one set; a slot the combination leaves empty holds its kind's 1x1
/// default (`MapKindInfo::empty_slot`), made only when some set needs it.
struct MaterialImages {
    sampler: Option<Sampler>,
    layout: Option<DescriptorSetLayout>,
    /// By index into `FramePlan::maps`.
    images: Vec<Image>,
    /// By kind.
    defaults: [Option<Image>; MAP_KIND_COUNT],
    /// The distinct combinations of maps the draws use (none empty).
    combinations: Vec<MapSlots>,
}

impl MaterialImages {
    fn new(
        ctx: &Arc<Context>,
        scene: &Scene,
        plan: &FramePlan,
    ) -> Result<MaterialImages, RenderError> {
        let mut combinations: Vec<MapSlots> = plan
            .draws()
            .map(|d| d.maps)
            .filter(|slots| slots.iter().any(Option::is_some))
            .collect();
        combinations.sort_unstable();
        combinations.dedup();
        if plan.maps.is_empty() {
            return Ok(MaterialImages {
                sampler: None,
                layout: None,
                images: Vec::new(),
                defaults: Default::default(),
                combinations,
            });
        }
        let sampler = Sampler::new(
            ctx,
            match scene.output.texture_filter {
                TextureFilter::Nearest => SamplerFilter::Nearest,
                TextureFilter::Bilinear => SamplerFilter::Bilinear,
                TextureFilter::Trilinear => SamplerFilter::Trilinear,
            },
            16,
        )?;
        let images = plan
            .maps
            .iter()
            .map(|(kind, source)| load_map(ctx, kind.info(), source))
            .collect::<Result<Vec<_>, _>>()?;
        let mut defaults: [Option<Image>; MAP_KIND_COUNT] = Default::default();
        for (info, default) in MAP_KINDS.iter().zip(&mut defaults) {
            if combinations.iter().any(|c| c[info.kind as usize].is_none()) {
                let format = info.format(false);
                *default = Some(upload_texture(ctx, 1, 1, &info.empty_slot, format)?);
            }
        }
        let bindings = MAP_KINDS.map(|info| DescriptorBinding {
            binding: info.binding,
            kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
            stages: ShaderStageFlags::FRAGMENT,
        });
        Ok(MaterialImages {
            sampler: Some(sampler),
            layout: Some(DescriptorSetLayout::new(ctx, &bindings)?),
            images,
            defaults,
            combinations,
        })
    }

    /// One set from `pool` per combination, each slot written with its map
    /// or its kind's default.
    fn sets(&self, pool: &DescriptorPool) -> Result<Vec<(MapSlots, DescriptorSet)>, RenderError> {
        let (Some(layout), Some(sampler)) = (&self.layout, &self.sampler) else {
            return Ok(Vec::new());
        };
        let mut sets = Vec::with_capacity(self.combinations.len());
        for slots in &self.combinations {
            let set = pool.allocate(layout)?;
            for (info, slot) in MAP_KINDS.iter().zip(slots) {
                let image = match slot {
                    Some(i) => &self.images[*i],
                    None => self.defaults[info.kind as usize]
                        .as_ref()
                        .expect("a default exists for every kind a set leaves empty"),
                };
                set.write_sampled_image(info.binding, image, sampler);
            }
            sets.push((*slots, set));
        }
        Ok(sets)
    }
}

/// Lays `blocks` (a header of `header_size` bytes then lights) out at
/// offsets aligned for dynamic uniform buffers, each padded to room for at
/// least one light (the shortest array a shader can declare). Returns the
/// bytes, each block's offset, and the descriptor range (the largest
/// block). `name(i)` names block i in the error when it exceeds the
/// device's uniform range.
pub fn pack_blocks(
    ctx: &Context,
    blocks: &[Vec<u8>],
    header_size: usize,
    name: impl Fn(usize) -> String,
) -> Result<(Vec<u8>, Vec<u32>, u64), RenderError> {
    let light_size = std::mem::size_of::<GpuLight>();
    let alignment = ctx.uniform_offset_alignment().max(16);
    let min_block = (header_size + light_size) as u64;
    let max_range = ctx.max_uniform_range();
    if let Some((i, b)) = blocks
        .iter()
        .enumerate()
        .find(|(_, b)| b.len() as u64 > max_range)
    {
        return Err(RenderError::TooManyLights {
            what: name(i),
            lights: (b.len() - header_size) / light_size,
            max: (max_range as usize).saturating_sub(header_size) / light_size,
        });
    }
    let range = blocks
        .iter()
        .map(|b| b.len() as u64)
        .max()
        .unwrap_or(0)
        .max(min_block);
    let mut offsets = Vec::with_capacity(blocks.len());
    let mut bytes = Vec::new();
    for b in blocks {
        offsets.push(bytes.len() as u32);
        bytes.extend_from_slice(b);
        bytes.resize((bytes.len() as u64).next_multiple_of(alignment) as usize, 0);
    }
    // The last block's descriptor range must still fit in the buffer.
    let last = offsets.last().copied().unwrap_or(0) as u64;
    bytes.resize(bytes.len().max((last + range) as usize), 0);
    Ok((bytes, offsets, range))
}

fn upload_geometry(
    ctx: &Arc<Context>,
    geometry: &SceneGeometry,
) -> Result<(Buffer, Vec<GeometryRange>), RenderError> {
    // Each distinct mesh once (objects of the same shape share one, see
    // `SceneGeometry::meshes`), known by its allocation: vertices first,
    // then indices.
    let mut distinct: Vec<&Arc<Mesh>> = Vec::new();
    let mut vertex_offsets: HashMap<*const Mesh, u64> = HashMap::new();
    let mut bytes: Vec<u8> = Vec::new();
    for m in &geometry.meshes {
        if let Entry::Vacant(slot) = vertex_offsets.entry(Arc::as_ptr(m)) {
            slot.insert(bytes.len() as u64);
            distinct.push(m);
            bytes.extend_from_slice(bytemuck::cast_slice(&m.vertices));
        }
    }
    let mut shared: HashMap<*const Mesh, GeometryRange> = HashMap::new();
    for m in distinct {
        // Index data must be 4-byte aligned for UINT32 indices.
        bytes.resize(bytes.len().next_multiple_of(4), 0);
        let range = GeometryRange {
            vertex_offset: vertex_offsets[&Arc::as_ptr(m)],
            index_offset: bytes.len() as u64,
            index_count: m.indices.len() as u32,
        };
        shared.insert(Arc::as_ptr(m), range);
        bytes.extend_from_slice(bytemuck::cast_slice(&m.indices));
    }
    let ranges = geometry
        .meshes
        .iter()
        .map(|m| shared[&Arc::as_ptr(m)])
        .collect();
    // A buffer cannot be empty; a scene without objects still gets one.
    if bytes.is_empty() {
        bytes.resize(4, 0);
    }
    let buffer = Buffer::with_data(ctx, "geometry", &bytes, BufferUsage::Geometry)?;
    Ok((buffer, ranges))
}

/// The draw covering each object (alone or as an instance), by object.
fn draw_of_object<'a>(scene: &Scene, plan: &'a FramePlan) -> Vec<Option<&'a Draw>> {
    let mut draws = vec![None; scene.objects.len()];
    for d in plan.draws() {
        for &object in d.objects() {
            draws[object] = Some(d);
        }
    }
    draws
}

/// Writes each instanced draw's members in view, in its order, from its
/// first slot: their camera-relative model matrices (composed in f64, as
/// the blocks') and normal matrices.
fn write_instances(buffer: &mut Buffer, scene: &Scene, plan: &FramePlan) {
    let size = std::mem::size_of::<InstanceTransform>();
    for d in plan.draws() {
        let Some(instances) = &d.instances else {
            continue;
        };
        // The members in view first (what the surface passes draw), then
        // the others (the shadow pass draws every member).
        let others = instances
            .members
            .iter()
            .filter(|m| !instances.visible.contains(m));
        let transforms: Vec<InstanceTransform> = instances
            .visible
            .iter()
            .chain(others)
            .map(|&i| {
                let transform = &scene.objects[i].transform;
                InstanceTransform {
                    model: transform
                        .matrix_relative_to(scene.camera.eye)
                        .to_cols_array_2d(),
                    normal_matrix: transform.normal_matrix().to_cols_array_2d(),
                }
            })
            .collect();
        buffer.write(
            instances.first as usize * size,
            bytemuck::cast_slice(&transforms),
        );
    }
}

/// The per-object block: header, then exactly the lights its draw
/// evaluates.
fn object_block(scene: &Scene, index: usize, draw: Option<&Draw>) -> Vec<u8> {
    let object = &scene.objects[index];
    let material = &scene.materials[object.material];
    // Relative to the camera: composed in f64, then rounded (the shaders
    // work in camera-relative space, see Camera::view).
    let model = object.transform.matrix_relative_to(scene.camera.eye);
    let normal = glam::Mat4::from_mat3(object.transform.normal_matrix());
    let lights: Vec<GpuLight> = draw
        .map(|d| {
            d.lights
                .iter()
                .map(|&l| scene_light(scene, l, scene.camera.eye))
                .collect()
        })
        .unwrap_or_default();
    let header = ObjectHeader {
        model: model.to_cols_array_2d(),
        normal_matrix: normal.to_cols_array_2d(),
        ka: material.ka.extend(0.0).to_array(),
        kd: material.kd.extend(material.opacity).to_array(),
        ks: material.ks.extend(material.shininess).to_array(),
        // y: 1 when the normal map's green channel points down the image.
        counts: [
            lights.len() as u32,
            u32::from(material.map(MapKind::Normal).is_some_and(|m| m.green_down)),
            0,
            0,
        ],
    };
    let mut bytes = bytemuck::bytes_of(&header).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&lights));
    bytes
}

/// A light as the shaders read it: positions relative to `eye` (the
/// camera), subtracted in f64 before rounding; the window for the scene's
/// light cutoff (`Light::window`) in the attenuation's w.
pub fn gpu_light(light: &Light, eye: glam::DVec3, cutoff: f32) -> GpuLight {
    match light {
        Light::Point {
            position,
            color,
            attenuation,
        } => GpuLight {
            position: (*position - eye).as_vec3().extend(1.0).to_array(),
            color: color.extend(0.0).to_array(),
            attenuation: attenuation.extend(light.window(cutoff)).to_array(),
        },
        Light::Directional { direction, color } => GpuLight {
            position: (-*direction).extend(0.0).to_array(),
            color: color.extend(0.0).to_array(),
            attenuation: [1.0, 0.0, 0.0, 0.0],
        },
    }
}

/// `scene`'s light `l` as the shaders read it ([`gpu_light`]), the
/// shadow-casting light marked by colour w = 1 (`shadow_map.glsl`).
pub fn scene_light(scene: &Scene, l: usize, eye: glam::DVec3) -> GpuLight {
    let mut light = gpu_light(&scene.lights[l], eye, scene.light_cutoff);
    if scene.shadow_light == Some(crate::scene::ShadowLight::Light(l)) {
        light.color[3] = 1.0;
    }
    light
}

/// Decodes a texture file (PNG or JPEG, recognised by content).
fn decode_texture(path: &std::path::Path) -> Result<image::DynamicImage, RenderError> {
    crate::image_io::decode(path).map_err(|reason| RenderError::Texture {
        path: path.to_path_buf(),
        reason,
    })
}

/// The image of a map of the kind `info` from `source`: the placeholder's
/// texels, a height map converted to a normal map, or the file with a full
/// mip chain (16 bits per channel where the file and the kind keep them
/// and the device can blit them).
fn load_map(
    ctx: &Arc<Context>,
    info: &MapKindInfo,
    source: &MapSource,
) -> Result<Image, RenderError> {
    let path = match (&source.texture, source.height_scale) {
        (Texture::Placeholder, _) => {
            let (side, _) = PLACEHOLDER_TEXTURE;
            let format = info.format(false);
            return upload_texture(ctx, side, side, &placeholder_texels(), format);
        }
        (Texture::File(path), Some(scale)) => return load_height_map(ctx, info, path, scale),
        (Texture::File(path), None) => path,
    };
    let img = decode_texture(path)?;
    // More than one byte per channel (the same rule as the preflight's
    // memory estimate).
    let sixteen_bit = img.color().bytes_per_pixel() > img.color().channel_count();
    let wide = info.format(sixteen_bit);
    if wide != info.format(false) && vk::supports_linear_blits(ctx, wide) {
        let img = img.to_rgba16();
        let (w, h) = img.dimensions();
        upload_texture(ctx, w, h, bytemuck::cast_slice(img.as_raw()), wide)
    } else {
        let img = img.to_rgba8();
        let (w, h) = img.dimensions();
        upload_texture(ctx, w, h, img.as_raw(), info.format(false))
    }
}

/// A height map at `path` turned into a normal map with `scale` (see
/// `crate::mesh::height`), in the kind's 8-bit format.
fn load_height_map(
    ctx: &Arc<Context>,
    info: &MapKindInfo,
    path: &std::path::Path,
    scale: f32,
) -> Result<Image, RenderError> {
    let texture_error = |reason: String| RenderError::Texture {
        path: path.to_path_buf(),
        reason,
    };
    let heights = HeightMap::load(path).map_err(|e| texture_error(e.to_string()))?;
    let normals = heights
        .normals(scale, HeightFilter::Central, HeightEdge::Wrap)
        .map_err(|e| texture_error(e.to_string()))?;
    upload_texture(
        ctx,
        heights.width,
        heights.height,
        &encode_normal_map(&normals, GreenAxis::Up),
        info.format(false),
    )
}

/// A `w`×`h` texture from tightly packed `pixels` in `format` (top row
/// first), with a full mip chain built by blits where the format supports
/// linear blits.
fn upload_texture(
    ctx: &Arc<Context>,
    w: u32,
    h: u32,
    pixels: &[u8],
    format: Format,
) -> Result<Image, RenderError> {
    let mip_levels = 32 - w.max(h).leading_zeros();
    let linear_blits = vk::supports_linear_blits(ctx, format);
    let mip_levels = if linear_blits { mip_levels } else { 1 };
    let texture = Image::new(
        ctx,
        "texture",
        ImageDesc {
            width: w,
            height: h,
            format,
            usage: ImageUsageFlags::SAMPLED
                | ImageUsageFlags::TRANSFER_DST
                | ImageUsageFlags::TRANSFER_SRC,
            mip_levels,
            aspect: ImageAspectFlags::COLOR,
        },
    )?;
    let staging = Buffer::with_data(ctx, "texture staging", pixels, BufferUsage::Upload)?;
    CommandBuffer::run_once(ctx, |cmd| {
        cmd.copy_buffer_to_image(&staging, &texture);
        cmd.generate_mipmaps(&texture);
    })?;
    Ok(texture)
}
