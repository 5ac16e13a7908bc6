//! The atmosphere subpass: a full-screen pass between the surfaces and the
//! tone map that reads the surface colour and depth as input attachments
//! and writes the HDR target: sky, aerial perspective over the surfaces,
//! the analytic ground sphere and the sun disc (`glsl/atmosphere.frag`).
//!
//! It bakes the [`OpticalDepthTable`] on the CPU when created and hands it
//! to the shader as a storage buffer of RGBA32F texels, filtered by hand
//! (four fetches). Everything planet-scale is computed here in f64 and
//! given to the shader camera-relative.

use super::{fullscreen_pipeline, FrameResources, InputAttachments, PassSetup, RecordPass};
use crate::atmosphere::{OpticalDepthTable, TableMapping};
use crate::render::plan::{attachment, FramePlan};
use crate::render::RenderError;
use crate::scene::{Camera, Scene, Sky, TableFilter};
use crate::shaders;
use crate::vk::{
    Buffer, BufferUsage, CommandBuffer, DescriptorBinding, DescriptorPool, DescriptorSet,
    DescriptorSetLayout, DescriptorType, GraphicsPipeline, PipelineLayout, ShaderStageFlags,
};
use glam::DVec3;

/// The uniform block of `glsl/atmosphere.frag`, std140 (vec4s only).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkyUniforms {
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
}

fn v4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

/// The pixel ray basis of `camera` at `aspect`: forward, and the right and
/// up vectors scaled so that forward + right·x_ndc − up·y_ndc is the ray
/// through NDC (x, y) at unit view depth. In f64, as the view matrix.
pub fn ray_basis(camera: &Camera, aspect: f64) -> (DVec3, DVec3, DVec3) {
    let eye = camera.eye.as_dvec3();
    let forward = (camera.look_at.as_dvec3() - eye).normalize();
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
    let origin = camera.eye.as_dvec3() - a.center;
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
    let big_h = ((a.top_radius - a.bottom_radius) * (a.top_radius + a.bottom_radius)).sqrt();
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
            c(a.top_radius) as f32,
            depth_a as f32,
            depth_b as f32,
        ],
        radii: [
            a.bottom_radius as f32,
            a.top_radius as f32,
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
    }
}

/// Fields drop in order: sets before their pool, pipeline before layouts.
pub struct AtmospherePass {
    pipeline: GraphicsPipeline,
    layout: PipelineLayout,
    sky_set: DescriptorSet,
    _pool: DescriptorPool,
    _sky_layout: DescriptorSetLayout,
    inputs: InputAttachments,
    uniforms: Buffer,
    /// The optical-depth table's size, which the uniforms carry.
    table_size: (u32, u32),
    _table: Buffer,
}

pub fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let ctx = setup.ctx;
    let sky = setup.scene.sky.as_ref().ok_or_else(|| {
        RenderError::Frame("the atmosphere pass needs a scene with [atmosphere]".into())
    })?;
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
    let plan = setup.plan;
    let block = uniforms(
        sky,
        &setup.scene.camera,
        plan.width,
        plan.height,
        (table.width, table.height),
    );
    let uniforms = Buffer::with_data(
        ctx,
        "atmosphere",
        bytemuck::bytes_of(&block),
        BufferUsage::Uniform,
    )?;
    let table_buffer = Buffer::with_data(
        ctx,
        "optical-depth table",
        bytemuck::cast_slice(&table.texels),
        BufferUsage::Storage,
    )?;

    let sky_layout = DescriptorSetLayout::new(
        ctx,
        &[
            DescriptorBinding {
                binding: 0,
                kind: DescriptorType::UNIFORM_BUFFER,
                stages: ShaderStageFlags::FRAGMENT,
            },
            DescriptorBinding {
                binding: 1,
                kind: DescriptorType::STORAGE_BUFFER,
                stages: ShaderStageFlags::FRAGMENT,
            },
        ],
    )?;
    let inputs = InputAttachments::new(setup, &[attachment::SURFACE, attachment::DEPTH])?;
    let pool = DescriptorPool::for_layouts(ctx, &[&sky_layout])?;
    let sky_set = pool.allocate(&sky_layout)?;
    sky_set.write_buffer(
        0,
        DescriptorType::UNIFORM_BUFFER,
        &uniforms,
        uniforms.size(),
    );
    sky_set.write_buffer(
        1,
        DescriptorType::STORAGE_BUFFER,
        &table_buffer,
        table_buffer.size(),
    );
    let layout = PipelineLayout::new(ctx, &[&sky_layout, &inputs.layout])?;
    // The table's mapping and filter select code paths once, at pipeline
    // creation.
    let mapping = match sky.table_mapping {
        TableMapping::Horizon => 0,
        TableMapping::Seed => 1,
    };
    let filter = match sky.table_filter {
        TableFilter::Manual => 0,
        TableFilter::Nearest => 1,
    };
    let pipeline = fullscreen_pipeline(
        ctx,
        &layout,
        &setup.render_pass()?.render_pass,
        setup.subpass,
        shaders::ATMOSPHERE_FRAG.base(),
        &[(0, mapping), (1, filter)],
    )?;
    Ok(Box::new(AtmospherePass {
        pipeline,
        layout,
        sky_set,
        _pool: pool,
        _sky_layout: sky_layout,
        inputs,
        uniforms,
        table_size: (table.width, table.height),
        _table: table_buffer,
    }))
}

impl RecordPass for AtmospherePass {
    fn record(&self, cmd: &CommandBuffer, _frame: &FrameResources<'_>) -> Result<(), RenderError> {
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_descriptor_set(&self.layout, 0, &self.sky_set, &[]);
        cmd.bind_descriptor_set(&self.layout, 1, &self.inputs.set, &[]);
        cmd.draw(3);
        Ok(())
    }

    fn set_view(&mut self, scene: &Scene, plan: &FramePlan) -> Result<(), RenderError> {
        let sky = scene.sky.as_ref().ok_or_else(|| {
            RenderError::Frame("the atmosphere pass needs a scene with [atmosphere]".into())
        })?;
        let block = uniforms(sky, &scene.camera, plan.width, plan.height, self.table_size);
        self.uniforms.write(0, bytemuck::bytes_of(&block));
        Ok(())
    }
}
