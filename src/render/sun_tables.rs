//! The two tables that multiple scattering adds to the atmosphere, baked
//! on the device when its resources are made, before any frame:
//!
//! - the multiple-scattering table (Hillaire 2020): Ψ_ms per unit solar
//!   irradiance by (cosine of the sun's zenith angle, altitude), which the
//!   march multiplies by the scattering coefficient at every sample
//!   (`glsl/multiple_scattering.comp`);
//! - the sky-irradiance table: the whole sky's irradiance on a horizontal
//!   surface by the same two coordinates, which lights the ground
//!   (`glsl/sky_irradiance.comp`, which reads the first table).
//!
//! Both depend on the atmosphere alone, not on the sun's direction or the
//! camera, so a frame that moves the sun or the camera keeps them. They
//! share one layout (`sun_table_coords` in `glsl/include/atmosphere.glsl`).
//! The bakes march the same optical-depth table and read the same
//! uniforms as the atmosphere pass, through its descriptor set (set 0);
//! each writes its table through a set of its own (set 1).

use super::sky_resources::TABLE_FORMAT;
use super::RenderError;
use crate::scene::Sky;
use crate::shader_ids::SPEC_SUN_TABLES_LINEAR_FILTER;
use crate::shaders;
use crate::vk::{
    CommandBuffer, ComputePipeline, Context, DescriptorBinding, DescriptorPool, DescriptorSet,
    DescriptorSetLayout, DescriptorType, Image, ImageAspectFlags, ImageDesc, ImageUsageFlags,
    ImageUse, PipelineLayout, Sampler, SamplerFilter, ShaderModule, ShaderStageFlags,
};
use std::sync::Arc;
use std::time::Instant;

/// Invocations per workgroup side (`local_size` in both shaders).
const GROUP: u32 = 8;

/// The sizes of the two tables, multiple scattering then sky irradiance.
pub type Sizes = ((u32, u32), (u32, u32));

/// The baked tables, sampled by the atmosphere shaders (set 0, bindings 4
/// and 5) through their sampler; held so they live as long as the set
/// that points at them.
pub struct SunTables {
    _multiple_scattering: Image,
    _irradiance: Image,
    _sampler: Sampler,
    sizes: Sizes,
}

/// The specialization constant that tells the shaders how to filter both
/// tables.
pub fn filter_constant(linear_filter: bool) -> (u32, u32) {
    (SPEC_SUN_TABLES_LINEAR_FILTER, u32::from(linear_filter))
}

fn table_image(ctx: &Arc<Context>, name: &str, size: (u32, u32)) -> Result<Image, RenderError> {
    Ok(Image::new(
        ctx,
        name,
        ImageDesc {
            width: size.0,
            height: size.1,
            format: TABLE_FORMAT,
            usage: ImageUsageFlags::STORAGE | ImageUsageFlags::SAMPLED,
            mip_levels: 1,
            aspect: ImageAspectFlags::COLOR,
        },
    )?)
}

/// One bake: a compute pipeline over the sky's set and an output set.
struct Bake {
    pipeline: ComputePipeline,
    output: DescriptorSet,
}

impl SunTables {
    /// The sizes `sky` asks for, or `None` without multiple scattering: a
    /// change needs new tables and shader variants.
    pub fn sizes_for(sky: &Sky) -> Option<Sizes> {
        sky.multiple_scattering
            .then_some((sky.ms_table_size, sky.irradiance_table_size))
    }

    /// The sizes these tables were baked at.
    pub fn sizes(&self) -> Sizes {
        self.sizes
    }

    /// Makes both tables for `sky` and points bindings 4 and 5 of
    /// `sky_set` (whose layout is `sky_layout`) at them, then bakes them.
    /// They are read through the sampler's bilinear filter where
    /// `linear_filter` (the device filters their format), by texel
    /// fetches otherwise. `constants` are the atmosphere shaders'
    /// specialization constants (the table's mapping and filter, the
    /// sky's static fields, the tables' filter).
    pub fn bake(
        ctx: &Arc<Context>,
        sky: &Sky,
        sky_layout: &DescriptorSetLayout,
        sky_set: &DescriptorSet,
        linear_filter: bool,
        constants: &[(u32, u32)],
    ) -> Result<SunTables, RenderError> {
        let start = Instant::now();
        let sampler = Sampler::clamped(
            ctx,
            if linear_filter {
                SamplerFilter::Bilinear
            } else {
                SamplerFilter::Nearest
            },
        )?;
        let multiple_scattering = table_image(ctx, "multiple-scattering table", sky.ms_table_size)?;
        let irradiance = table_image(ctx, "sky-irradiance table", sky.irradiance_table_size)?;
        // The frame reads both through set 0. Neither bake statically uses
        // the binding of the table it writes, so pointing them there now
        // (before the bakes are recorded) is valid.
        sky_set.write_sampled_image(4, &multiple_scattering, &sampler);
        sky_set.write_sampled_image(5, &irradiance, &sampler);

        let output_layout = DescriptorSetLayout::new(
            ctx,
            &[DescriptorBinding {
                binding: 0,
                kind: DescriptorType::STORAGE_IMAGE,
                stages: ShaderStageFlags::COMPUTE,
            }],
        )?;
        let pool = DescriptorPool::for_layouts(ctx, &[&output_layout, &output_layout])?;
        let layout = PipelineLayout::new(ctx, &[sky_layout, &output_layout])?;
        let bake = |spirv: &[u8], target: &Image| -> Result<Bake, RenderError> {
            let shader = ShaderModule::new(ctx, spirv)?;
            let pipeline = ComputePipeline::new(ctx, &layout, &shader, constants)?;
            let output = pool.allocate(&output_layout)?;
            output.write_storage_image(0, target);
            Ok(Bake { pipeline, output })
        };
        let ms_bake = bake(
            shaders::MULTIPLE_SCATTERING_COMP.base(),
            &multiple_scattering,
        )?;
        let irradiance_bake = bake(shaders::SKY_IRRADIANCE_COMP.base(), &irradiance)?;
        let groups = |(w, h): (u32, u32)| [w.div_ceil(GROUP), h.div_ceil(GROUP), 1];
        CommandBuffer::run_once(ctx, |cmd| {
            cmd.transition_discarding(&multiple_scattering, ImageUse::ComputeWrite);
            cmd.bind_compute_pipeline(&ms_bake.pipeline);
            cmd.bind_compute_descriptor_set(&layout, 0, sky_set);
            cmd.bind_compute_descriptor_set(&layout, 1, &ms_bake.output);
            cmd.dispatch(groups(sky.ms_table_size));
            // The irradiance bake marches with the first table.
            cmd.transition(&multiple_scattering, ImageUse::ShaderSampled);
            cmd.transition_discarding(&irradiance, ImageUse::ComputeWrite);
            cmd.bind_compute_pipeline(&irradiance_bake.pipeline);
            cmd.bind_compute_descriptor_set(&layout, 1, &irradiance_bake.output);
            cmd.dispatch(groups(sky.irradiance_table_size));
            cmd.transition(&irradiance, ImageUse::ShaderSampled);
        })?;
        let bake_seconds = start.elapsed().as_secs_f64();
        log::info!(
            "multiple-scattering table {}x{} and sky-irradiance table {}x{} baked in {bake_seconds:.3} s",
            sky.ms_table_size.0,
            sky.ms_table_size.1,
            sky.irradiance_table_size.0,
            sky.irradiance_table_size.1,
        );
        Ok(SunTables {
            _multiple_scattering: multiple_scattering,
            _irradiance: irradiance,
            _sampler: sampler,
            sizes: (sky.ms_table_size, sky.irradiance_table_size),
        })
    }
}
