//! GPU resources of the atmosphere, shared by the passes that march it
//! (the sky-view table's compute pass and the atmosphere subpass): the
//! uniform block, the [`OpticalDepthTable`] baked on the CPU and uploaded
//! as an RGBA32F image (read texel by texel and filtered by hand in the
//! shaders), and the sky-view table's image, written on the device; with
//! multiple scattering, the two tables of [`SunTables`], baked on the
//! device here.
//!
//! Tables are images, not storage buffers: lavapipe turns a storage-buffer
//! read at a per-pixel index into a bounds-checked loop over the SIMD
//! lanes, while a texel fetch is one gather; on the sky-view lookup
//! (twelve reads a pixel) that measured about five times the cost.
//! Everything planet-scale is computed here in f64 and given to the
//! shaders camera-relative.

use super::passes::aerial_volume;
use super::plan::FramePlan;
use super::sun_tables::{self, SunTables};
use super::RenderError;
use crate::atmosphere::OpticalDepthTable;
use crate::scene::{Camera, Sky, TableFilter};
use crate::shader_ids::{
    float_constants, AERIAL_VOLUME_BINDING, AERIAL_VOLUME_WRITE_BINDING, SPEC_OBJECT_SKY_OFFSET,
    SPEC_SKY_STATIC,
};
use crate::vk::{
    Buffer, BufferUsage, CommandBuffer, Context, DescriptorBinding, DescriptorPool, DescriptorSet,
    DescriptorSetLayout, DescriptorType, Format, Image, ImageAspectFlags, ImageDesc,
    ImageUsageFlags, Sampler, SamplerFilter, ShaderStageFlags,
};
use glam::DVec3;
use std::sync::Arc;

/// The uniform block of `glsl/include/atmosphere.glsl`, std140 (vec4s only).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkyUniforms {
    /// xyz: camera forward; w: the aerial-perspective volume's reach.
    pub forward: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub origin: [f32; 4],
    pub terms: [f32; 4],
    pub radii: [f32; 4],
    pub rayleigh: [f32; 4],
    pub mie_scattering: [f32; 4],
    pub mie_extinction: [f32; 4],
    pub ozone_absorption: [f32; 4],
    pub ozone_layer: [f32; 4],
    pub sun_direction: [f32; 4],
    pub sun_irradiance: [f32; 4],
    pub ground_albedo: [f32; 4],
    pub viewport: [f32; 4],
    pub zenith: [f32; 4],
    pub azimuth_zero: [f32; 4],
    pub sky_view: [f32; 4],
}

fn v4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

/// The pixel ray basis of `camera` at `aspect`: forward, and the right and
/// up vectors scaled so that forward + right·x_ndc − up·y_ndc is the ray
/// through NDC (x, y) at unit view depth. In f64, as the view matrix.
pub fn ray_basis(camera: &Camera, aspect: f64) -> (DVec3, DVec3, DVec3) {
    let eye = camera.eye;
    let forward = (camera.look_at - eye).normalize();
    let right = forward.cross(camera.up.as_dvec3()).normalize();
    let up = right.cross(forward);
    let tan = (f64::from(camera.fov_y_degrees).to_radians() * 0.5).tan();
    (forward, right * (tan * aspect), up * tan)
}

/// The uniform block for `sky` seen by `camera` on a `width`×`height`
/// target, with a table of `table_size`.
pub fn uniforms(
    sky: &Sky,
    camera: &Camera,
    width: u32,
    height: u32,
    table_size: (u32, u32),
) -> SkyUniforms {
    let a = &sky.atmosphere;
    let s = &sky.sun;
    let (forward, right, up) = ray_basis(camera, f64::from(width) / f64::from(height));
    let origin = camera.eye - a.center;
    let length = origin.length();
    let c = |radius: f64| (length - radius) * (length + radius);
    // Reversed-Z depth = A + B / view depth (see Camera::projection).
    let near = f64::from(camera.near);
    let (depth_a, depth_b) = match camera.far {
        Some(far) => {
            let far = f64::from(far);
            (-near / (far - near), near * far / (far - near))
        }
        None => (0.0, near),
    };
    // The shaders see the effective top: a tall atmosphere is cut where
    // its air is negligible (Atmosphere::effective_top_radius), so the
    // march and the tables sample the air, and a camera above it is in
    // space.
    let top = a.effective_top_radius();
    let big_h = ((top - a.bottom_radius) * (top + a.bottom_radius)).sqrt();
    // The sky-view table's frame: the camera's zenith, the azimuth origin
    // towards the sun, and the nadir angles of the ground's horizon and
    // of the atmosphere's edge, as atan2 of a tangent and a radius, which
    // stays precise a metre above the ground and at the Moon's distance.
    let zenith = origin / length;
    let towards_sun = s.direction - zenith * zenith.dot(s.direction);
    let azimuth_zero = if towards_sun.length() > 1e-9 {
        towards_sun.normalize()
    } else {
        zenith.any_orthonormal_vector()
    };
    let tangent_nadir = |radius: f64| {
        let tangent = (length - radius).max(0.0) * (length + radius);
        radius.atan2(tangent.sqrt())
    };
    let edge = if length >= top {
        tangent_nadir(top)
    } else {
        std::f64::consts::PI
    };
    let (view_w, view_h) = sky.sky_view.unwrap_or((0, 0));
    let disc = if s.disc {
        1.0 / (std::f64::consts::PI * s.angular_radius * s.angular_radius)
    } else {
        0.0
    };
    SkyUniforms {
        forward: v4(forward, 0.0),
        right: v4(right, 0.0),
        up: v4(up, 0.0),
        origin: v4(origin, length),
        terms: [
            c(a.bottom_radius) as f32,
            c(top) as f32,
            depth_a as f32,
            depth_b as f32,
        ],
        radii: [
            a.bottom_radius as f32,
            top as f32,
            big_h as f32,
            sky.samples as f32,
        ],
        rayleigh: v4(a.rayleigh_scattering, 1.0 / a.rayleigh_scale_height),
        mie_scattering: v4(a.mie_scattering, 1.0 / a.mie_scale_height),
        mie_extinction: v4(a.mie_extinction, a.mie_g),
        ozone_absorption: v4(a.ozone_absorption, a.ozone_layer[0]),
        ozone_layer: [
            a.ozone_layer[1] as f32,
            a.ozone_layer[2] as f32,
            table_size.0 as f32,
            table_size.1 as f32,
        ],
        sun_direction: v4(s.direction, s.angular_radius.cos()),
        sun_irradiance: v4(s.irradiance, disc),
        ground_albedo: v4(a.ground_albedo, crate::atmosphere::table::LOG_OFFSET),
        viewport: [
            width as f32,
            height as f32,
            1.0 / width as f32,
            1.0 / height as f32,
        ],
        zenith: v4(zenith, tangent_nadir(a.bottom_radius)),
        azimuth_zero: v4(azimuth_zero, edge),
        sky_view: [view_w as f32, view_h as f32, 0.0, 0.0],
    }
}

/// The uniform block for `sky` seen by `camera` in the frame `plan`: the
/// block of [`uniforms`], and the aerial-perspective volume's reach (the
/// forward vector's spare w, 0 without a volume), which changes with the
/// view and so is not a constant.
fn plan_uniforms(
    sky: &Sky,
    camera: &Camera,
    plan: &FramePlan,
    table_size: (u32, u32),
) -> SkyUniforms {
    let mut block = uniforms(sky, camera, plan.width, plan.height, table_size);
    block.forward[3] = plan.aerial_volume_reach.unwrap_or(0.0) as f32;
    block
}

/// Every table holds four 32-bit floats a texel.
pub(super) const TABLE_FORMAT: Format = Format::R32G32B32A32_SFLOAT;

/// Fields drop in order: the set before its pool, the layout after the
/// pipelines that use it (owned by the passes, dropped first).
pub struct SkyResources {
    /// Binding 0: uniforms; 1: optical-depth table; 2: the sky-view table
    /// written (compute); 3: the sky-view table read (fragment); 4 and 5:
    /// the multiple-scattering and sky-irradiance tables, with multiple
    /// scattering; 8 and 9: the aerial-perspective volume written
    /// (compute) and read (fragment), in frames with it. Object pipelines
    /// bind it too, as their `SKY_SET`, for the sun and sky light at each
    /// shaded point.
    pub set: DescriptorSet,
    _pool: DescriptorPool,
    pub layout: DescriptorSetLayout,
    uniforms: Buffer,
    /// The optical-depth table's size, which the uniforms carry.
    table_size: (u32, u32),
    _table: Image,
    /// The sky-view table, when the scene has one: three panels of
    /// width × height (Rayleigh, Mie, transmittance) side by side, and a
    /// fourth (the higher orders) with multiple scattering.
    pub sky_view_image: Option<Image>,
    _sampler: Sampler,
    /// The sky-view table's bilinear sampler, where there is a table and
    /// the device can filter its format (see
    /// [`SkyResources::sky_view_hardware_filter`]).
    sky_view_sampler: Option<Sampler>,
    /// The sky-view table's size (directions), when there is one.
    pub sky_view: Option<(u32, u32)>,
    /// The aerial-perspective volume, when the frame has one: in-scattering
    /// and transmittance panels side by side, `2 W × H × D` texels.
    pub aerial_volume: Option<AerialVolume>,
    /// The optical-depth table's size in bytes and its bake time (wall
    /// clock), for the reports.
    pub table_bytes: usize,
    pub table_bake_seconds: f64,
    /// The block's unchanging fields the pipelines hold as constants.
    static_fields: [[f32; 4]; 9],
    /// The multiple-scattering and sky-irradiance tables, with multiple
    /// scattering.
    sun_tables: Option<SunTables>,
    /// Whether the device filters the tables' format linearly.
    linear_filter: bool,
}

/// The specialization constants of the atmosphere shaders that carry the
/// sky block's unchanging fields, and how they filter the
/// multiple-scattering and sky-irradiance tables.
fn static_constants(static_fields: [[f32; 4]; 9], linear_filter: bool) -> Vec<(u32, u32)> {
    float_constants(SPEC_SKY_STATIC, static_fields.into_iter().flatten())
        .chain([sun_tables::filter_constant(linear_filter)])
        .collect()
}

impl SkyUniforms {
    /// The fields the frame never changes, in the order the shaders
    /// declare their constants (both generated from glsl/interface.toml).
    fn static_fields(&self) -> [[f32; 4]; 9] {
        super::gpu_types::sky_static_fields(self)
    }
}

/// The aerial-perspective volume's image, its sampler and its size.
pub struct AerialVolume {
    pub image: Image,
    _sampler: Sampler,
    /// Columns across and down the screen, slices in distance.
    pub size: (u32, u32, u32),
}

impl AerialVolume {
    fn new(
        ctx: &Arc<Context>,
        sky: &Sky,
        linear_filter: bool,
    ) -> Result<AerialVolume, RenderError> {
        let (w, h, d) = sky.aerial_volume;
        let image = Image::new_volume(
            ctx,
            "aerial-perspective volume",
            ImageDesc {
                width: 2 * w,
                height: h,
                format: TABLE_FORMAT,
                usage: ImageUsageFlags::STORAGE | ImageUsageFlags::SAMPLED,
                mip_levels: 1,
                aspect: ImageAspectFlags::COLOR,
            },
            d,
        )?;
        // Read through the sampler's filter where the device filters the
        // format (the multiple-scattering tables' check), by texel fetches
        // otherwise.
        let filter = if linear_filter {
            SamplerFilter::Bilinear
        } else {
            SamplerFilter::Nearest
        };
        Ok(AerialVolume {
            image,
            _sampler: Sampler::clamped(ctx, filter)?,
            size: (w, h, d),
        })
    }

    /// The volume's size in bytes.
    pub fn bytes(size: (u32, u32, u32)) -> u64 {
        2 * u64::from(size.0) * u64::from(size.1) * u64::from(size.2) * 16
    }
}

impl SkyResources {
    /// The specialization constants that carry the sky block's unchanging
    /// fields, as the atmosphere shaders read them, and how they filter the
    /// multiple-scattering and sky-irradiance tables.
    pub fn static_constants(&self) -> Vec<(u32, u32)> {
        static_constants(self.static_fields, self.linear_filter)
    }

    /// The specialization constants of object pipelines that read these
    /// resources (`glsl/include/object_air.glsl`): the march's table
    /// constants and [`static_constants`](Self::static_constants), each
    /// id moved up by `SPEC_OBJECT_SKY_OFFSET`.
    pub fn object_constants(&self, sky: &Sky) -> Vec<(u32, u32)> {
        crate::render::passes::atmosphere::table_constants(sky)
            .into_iter()
            .chain(self.static_constants())
            .map(|(id, value)| (id + SPEC_OBJECT_SKY_OFFSET, value))
            .collect()
    }

    /// Whether these resources hold the multiple-scattering tables, so
    /// the atmosphere shaders that read them take their
    /// `MULTIPLE_SCATTERING` variant.
    pub fn multiple_scattering(&self) -> bool {
        self.sun_tables.is_some()
    }

    /// Whether `sky` seen by `camera` in `plan` keeps the fields these
    /// resources' pipelines hold as constants, so that `set_view` can move
    /// to it.
    pub fn keeps_static_fields(&self, sky: &Sky, camera: &Camera, plan: &FramePlan) -> bool {
        let block = uniforms(sky, camera, plan.width, plan.height, self.table_size);
        block.static_fields() == self.static_fields
            && SunTables::sizes_for(sky) == self.sun_tables.as_ref().map(SunTables::sizes)
    }

    /// Whether the atmosphere pass reads the sky-view table through its
    /// bilinear sampler rather than by four fetches and a blend.
    pub fn sky_view_hardware_filter(&self) -> bool {
        self.sky_view_sampler.is_some()
    }

    /// Rewrites the uniforms for `sky` (its sun) seen by `camera`, between
    /// frames; the tables do not depend on either (the sky-view table is
    /// computed from the uniforms in every frame).
    pub fn set_view(&mut self, sky: &Sky, camera: &Camera, plan: &FramePlan) {
        let block = plan_uniforms(sky, camera, plan, self.table_size);
        self.uniforms.write(0, bytemuck::bytes_of(&block));
    }

    pub fn new(
        ctx: &Arc<Context>,
        sky: &Sky,
        camera: &Camera,
        plan: &FramePlan,
    ) -> Result<SkyResources, RenderError> {
        let table = bake_optical_depth_table(sky);
        let block = plan_uniforms(sky, camera, plan, (table.width, table.height));
        let uniforms = Buffer::with_data(
            ctx,
            "atmosphere",
            bytemuck::bytes_of(&block),
            BufferUsage::Uniform,
        )?;
        let table_image = upload_optical_depth_table(ctx, &table)?;
        let sky_view_image = sky_view_image(ctx, sky)?;
        let sampler = table_sampler(ctx, sky)?;
        // The sky-view table is filtered by the sampler wherever the device
        // can (glsl/atmosphere.frag, SKY_VIEW_HARDWARE_FILTER), and fetched
        // and filtered by hand where it cannot.
        let linear_filter = crate::vk::supports_linear_sampling(ctx, TABLE_FORMAT);
        let sky_view_sampler = match &sky_view_image {
            Some(_) if linear_filter => Some(Sampler::clamped(ctx, SamplerFilter::Bilinear)?),
            _ => None,
        };
        let aerial_volume = if plan.has(aerial_volume::PASS) {
            Some(AerialVolume::new(ctx, sky, linear_filter)?)
        } else {
            None
        };
        let bindings = descriptor_bindings(sky, sky_view_image.is_some(), aerial_volume.is_some());
        let layout = DescriptorSetLayout::new(ctx, &bindings)?;
        let pool = DescriptorPool::for_layouts(ctx, &[&layout])?;
        let set = pool.allocate(&layout)?;
        write_set(
            &set,
            &uniforms,
            (&table_image, &sampler),
            sky_view_image
                .as_ref()
                .map(|image| (image, sky_view_sampler.as_ref().unwrap_or(&sampler))),
            aerial_volume.as_ref(),
        );
        let static_fields = block.static_fields();
        let sun_tables = if sky.multiple_scattering {
            Some(bake_sun_tables(
                ctx,
                sky,
                &layout,
                &set,
                linear_filter,
                static_fields,
            )?)
        } else {
            None
        };
        Ok(SkyResources {
            sun_tables,
            linear_filter,
            set,
            _pool: pool,
            layout,
            uniforms,
            table_size: (table.width, table.height),
            _table: table_image,
            sky_view_image,
            _sampler: sampler,
            sky_view_sampler,
            sky_view: sky.sky_view,
            aerial_volume,
            table_bytes: table.bytes(),
            table_bake_seconds: table.bake_seconds,
            static_fields,
        })
    }
}

/// The sky's optical-depth table, baked on the CPU (the time logged).
fn bake_optical_depth_table(sky: &Sky) -> OpticalDepthTable {
    let table = OpticalDepthTable::bake(
        &sky.atmosphere,
        sky.table_size.0,
        sky.table_size.1,
        sky.table_mapping,
    );
    log::info!(
        "optical-depth table {}x{} baked in {:.3} s",
        table.width,
        table.height,
        table.bake_seconds
    );
    table
}

/// The optical-depth table's image, filled from `table` and left ready to
/// sample.
fn upload_optical_depth_table(
    ctx: &Arc<Context>,
    table: &OpticalDepthTable,
) -> Result<Image, RenderError> {
    let table_image = Image::new(
        ctx,
        "optical-depth table",
        ImageDesc {
            width: table.width,
            height: table.height,
            format: TABLE_FORMAT,
            usage: ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_DST,
            mip_levels: 1,
            aspect: ImageAspectFlags::COLOR,
        },
    )?;
    let staging = Buffer::with_data(
        ctx,
        "optical-depth table staging",
        bytemuck::cast_slice(&table.texels),
        BufferUsage::Upload,
    )?;
    CommandBuffer::run_once(ctx, |cmd| {
        cmd.copy_buffer_to_image(&staging, &table_image);
        cmd.transition(&table_image, crate::vk::ImageUse::ShaderSampled);
    })?;
    Ok(table_image)
}

/// The sky-view table's image, where the sky has one.
fn sky_view_image(ctx: &Arc<Context>, sky: &Sky) -> Result<Option<Image>, RenderError> {
    Ok(sky
        .sky_view
        .map(|(w, h)| {
            Image::new(
                ctx,
                "sky-view table",
                ImageDesc {
                    width: sky.sky_view_panels() * w,
                    height: h,
                    format: TABLE_FORMAT,
                    usage: ImageUsageFlags::STORAGE | ImageUsageFlags::SAMPLED,
                    mip_levels: 1,
                    aspect: ImageAspectFlags::COLOR,
                },
            )
        })
        .transpose()?)
}

/// The sampler of the tables. Tables are read with texelFetch and filtered
/// by hand, except the optical-depth table with od_filter = hardware: then
/// the sampler filters it (texel centres: the shader adds half a texel).
fn table_sampler(ctx: &Arc<Context>, sky: &Sky) -> Result<Sampler, RenderError> {
    let filter = if sky.table_filter == TableFilter::Hardware {
        if !crate::vk::supports_linear_sampling(ctx, TABLE_FORMAT) {
            return Err(RenderError::Frame(format!(
                "atmosphere.od_filter = \"hardware\": this device cannot filter {TABLE_FORMAT:?} \
                 images linearly; use \"manual\""
            )));
        }
        SamplerFilter::Bilinear
    } else {
        SamplerFilter::Nearest
    };
    Ok(Sampler::clamped(ctx, filter)?)
}

/// The bindings of the sky's descriptor set: the block and the
/// optical-depth table, then the sky-view table, the sun tables and the
/// aerial-perspective volume where the sky has them.
fn descriptor_bindings(sky: &Sky, sky_view: bool, aerial_volume: bool) -> Vec<DescriptorBinding> {
    // The block and the tables the object shaders read for the sun and
    // sky light on objects are visible to vertex shaders too (Gouraud
    // lights per vertex).
    let both = ShaderStageFlags::VERTEX | ShaderStageFlags::FRAGMENT | ShaderStageFlags::COMPUTE;
    let mut bindings = vec![
        DescriptorBinding {
            binding: 0,
            kind: DescriptorType::UNIFORM_BUFFER,
            stages: both,
        },
        DescriptorBinding {
            binding: 1,
            kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
            stages: both,
        },
    ];
    if sky_view {
        bindings.push(DescriptorBinding {
            binding: 2,
            kind: DescriptorType::STORAGE_IMAGE,
            stages: ShaderStageFlags::COMPUTE,
        });
        bindings.push(DescriptorBinding {
            binding: 3,
            kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
            stages: ShaderStageFlags::FRAGMENT,
        });
    }
    if sky.multiple_scattering {
        for binding in [4, 5] {
            bindings.push(DescriptorBinding {
                binding,
                kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
                stages: both,
            });
        }
    }
    if aerial_volume {
        bindings.push(DescriptorBinding {
            binding: AERIAL_VOLUME_WRITE_BINDING,
            kind: DescriptorType::STORAGE_IMAGE,
            stages: ShaderStageFlags::COMPUTE,
        });
        bindings.push(DescriptorBinding {
            binding: AERIAL_VOLUME_BINDING,
            kind: DescriptorType::COMBINED_IMAGE_SAMPLER,
            stages: ShaderStageFlags::FRAGMENT,
        });
    }
    bindings
}

/// Points the sky's descriptor set at the block, the optical-depth table,
/// the sky-view table (written by its pass, read through its sampler) and
/// the aerial-perspective volume (likewise), where the sky has them.
fn write_set(
    set: &DescriptorSet,
    uniforms: &Buffer,
    (table, sampler): (&Image, &Sampler),
    sky_view: Option<(&Image, &Sampler)>,
    aerial_volume: Option<&AerialVolume>,
) {
    set.write_buffer(0, DescriptorType::UNIFORM_BUFFER, uniforms, uniforms.size());
    set.write_sampled_image(1, table, sampler);
    if let Some((image, sampler)) = sky_view {
        set.write_storage_image(2, image);
        set.write_sampled_image(3, image, sampler);
    }
    if let Some(volume) = aerial_volume {
        set.write_storage_image(AERIAL_VOLUME_WRITE_BINDING, &volume.image);
        set.write_sampled_image(AERIAL_VOLUME_BINDING, &volume.image, &volume._sampler);
    }
}

/// The multiple-scattering and sky-irradiance tables, baked. They are read
/// through the sampler's filter where the device can filter their format
/// (the other tables' too), by four fetches and a blend where it cannot.
fn bake_sun_tables(
    ctx: &Arc<Context>,
    sky: &Sky,
    layout: &DescriptorSetLayout,
    set: &DescriptorSet,
    linear_filter: bool,
    static_fields: [[f32; 4]; 9],
) -> Result<SunTables, RenderError> {
    let constants = [
        &crate::render::passes::atmosphere::table_constants(sky)[..],
        &static_constants(static_fields, linear_filter),
    ]
    .concat();
    SunTables::bake(ctx, sky, layout, set, linear_filter, &constants)
}
