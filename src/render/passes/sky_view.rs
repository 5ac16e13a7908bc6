//! The sky-view table: before the render pass, a compute dispatch marches
//! the atmosphere for a grid of directions around the camera (azimuth from
//! the sun's side × nadir angle, `glsl/sky_view.comp`), so the atmosphere
//! subpass reads the sky and the ground from it instead of marching every
//! pixel. Without a surface in front, a pixel's sums depend only on its
//! direction; the phase functions (the only fast-varying part near the
//! sun), the ground's lighting and the sun disc stay per pixel.
//!
//! The idea is Hillaire's (2020) sky-view table; here it stores the
//! phase-free Rayleigh and Mie sums and the transmittance, and splits the
//! ground and the sky at the horizon so no filter mixes them.

use super::atmosphere::march_pipeline;
use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::render::plan::{FrameShape, PassIo};
use crate::render::RenderError;
use crate::shaders::{self, SkyViewCompFeatures};
use crate::vk::{CommandBuffer, ComputePipeline, ImageUse, PipelineLayout};

/// Invocations per workgroup side (`local_size` in the shader).
const GROUP: u32 = 8;

/// Fields drop in order: the pipeline before its layout.
pub struct SkyViewPass {
    pipeline: ComputePipeline,
    layout: PipelineLayout,
    size: (u32, u32),
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "sky view"
    }

    /// Marched for a grid of directions before the render pass, in frames
    /// with an atmosphere pass and a sky-view table.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        let sky = shape.scene?.sky.as_ref()?;
        (shape.sky && sky.sky_view.is_some()).then_some(PassIo::Compute { samples: vec![] })
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        create(setup)
    }

    fn is_subpass(&self) -> bool {
        false
    }
}

fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let resources = setup.sky_resources()?;
    let (sky, size) = match (&setup.scene.sky, resources.sky_view) {
        (Some(sky), Some(size)) => (sky, size),
        _ => {
            return Err(RenderError::Frame(
                "the sky-view pass needs a scene with [atmosphere] and a sky-view table".into(),
            ))
        }
    };
    let features = SkyViewCompFeatures::NONE.with(
        SkyViewCompFeatures::MULTIPLE_SCATTERING,
        resources.multiple_scattering(),
    );
    let (layout, pipeline) = march_pipeline(
        setup,
        resources,
        sky,
        shaders::SKY_VIEW_COMP.spirv(features),
    )?;
    Ok(Box::new(SkyViewPass {
        pipeline,
        layout,
        size,
    }))
}

impl RecordPass for SkyViewPass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let sky = frame.sky()?;
        let image = sky
            .sky_view_image
            .as_ref()
            .ok_or_else(|| RenderError::Frame("the sky-view pass has no sky-view table".into()))?;
        // Every texel is rewritten: the previous submission's reads must
        // finish, its contents are not needed.
        cmd.transition_discarding(image, ImageUse::ComputeWrite);
        cmd.bind_compute_pipeline(&self.pipeline);
        cmd.bind_compute_descriptor_set(&self.layout, 0, &sky.set);
        cmd.dispatch([self.size.0.div_ceil(GROUP), self.size.1.div_ceil(GROUP), 1]);
        // The atmosphere subpass samples what this wrote.
        cmd.transition(image, ImageUse::FragmentSampled);
        Ok(())
    }
}
