//! The aerial-perspective volume: before the render pass, a compute
//! dispatch marches one ray per column of a grid through the screen
//! (`glsl/aerial_volume.comp`), storing at each of its slices the light the
//! air scatters towards the camera in front of it and the transmittance to
//! it, so that the atmosphere subpass reads them at each surface instead
//! of marching every pixel (`aerial_perspective = "volume"`).
//!
//! The idea is Hillaire's (2020) camera-frustum volume. Here one
//! invocation marches its column once through every slice, the slices
//! reach the farthest object in view (`plan::aerial_volume_reach`), and the
//! pass exists only in frames with surfaces under an atmosphere.

use super::atmosphere::march_pipeline;
use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::render::plan::{FrameShape, PassIo};
use crate::render::RenderError;
use crate::scene::AerialPerspective;
use crate::shaders::{self, AerialVolumeCompFeatures};
use crate::vk::{CommandBuffer, ComputePipeline, ImageUse, PipelineLayout};

/// Invocations per workgroup side (`local_size` in the shader).
const GROUP: u32 = 8;

/// Fields drop in order: the pipeline before its layout.
pub struct AerialVolumePass {
    pipeline: ComputePipeline,
    layout: PipelineLayout,
    /// Columns across and down.
    columns: (u32, u32),
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "aerial volume"
    }

    /// In frames with an atmosphere pass and `aerial_perspective =
    /// "volume"`; the volume only serves pixels with a surface, so a frame
    /// without objects has none to read it.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        let scene = shape.scene?;
        let volume = scene
            .sky
            .as_ref()
            .is_some_and(|s| s.aerial_perspective == AerialPerspective::Volume);
        (shape.sky && volume && !scene.objects.is_empty())
            .then_some(PassIo::Compute { samples: vec![] })
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
    let (sky, volume) = match (&setup.scene.sky, &resources.aerial_volume) {
        (Some(sky), Some(volume)) => (sky, volume),
        _ => {
            return Err(RenderError::Frame(
                "the aerial-volume pass needs a scene with [atmosphere] and an \
                 aerial-perspective volume"
                    .into(),
            ))
        }
    };
    let features = AerialVolumeCompFeatures::NONE.with(
        AerialVolumeCompFeatures::MULTIPLE_SCATTERING,
        resources.multiple_scattering(),
    );
    let (layout, pipeline) = march_pipeline(
        setup,
        resources,
        sky,
        shaders::AERIAL_VOLUME_COMP.spirv(features),
    )?;
    Ok(Box::new(AerialVolumePass {
        pipeline,
        layout,
        columns: (volume.size.0, volume.size.1),
    }))
}

impl RecordPass for AerialVolumePass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let sky = frame.sky()?;
        let volume = sky.aerial_volume.as_ref().ok_or_else(|| {
            RenderError::Frame("the aerial-volume pass has no aerial-perspective volume".into())
        })?;
        // Every texel is rewritten: the previous submission's reads must
        // finish, its contents are not needed.
        cmd.transition_discarding(&volume.image, ImageUse::ComputeWrite);
        cmd.bind_compute_pipeline(&self.pipeline);
        cmd.bind_compute_descriptor_set(&self.layout, 0, &sky.set);
        cmd.dispatch([
            self.columns.0.div_ceil(GROUP),
            self.columns.1.div_ceil(GROUP),
            1,
        ]);
        // The atmosphere subpass samples what this wrote.
        cmd.transition(&volume.image, ImageUse::FragmentSampled);
        Ok(())
    }
}
