//! The atmosphere subpass: a full-screen pass between the surfaces and the
//! tone map that reads the surface colour and depth as input attachments
//! and writes the HDR target: sky, aerial perspective over the surfaces,
//! the analytic ground sphere and the sun disc (`glsl/atmosphere.frag`).
//! Pixels without a surface read the sky-view table when the scene has
//! one (see [`super::sky_view`]); the others march their own ray. The two
//! kinds are two draws of the subpass, split by a depth test against the
//! read-only depth (EQUAL to the far plane: nothing drawn; LESS: a
//! surface), so each shader variant holds only its own path and
//! lavapipe skips the pixels a draw does not cover before shading them
//! (with the march's code merely present in the sky-view shader, the
//! frame measured about 20 % more CPU time). With the aerial-perspective
//! volume (see [`super::aerial_volume`]) the surface pixels read it instead
//! of marching (the AERIAL_VOLUME variant, LESS), and the others take the
//! sky view or march (EQUAL). The uniforms and tables are the frame's
//! [`SkyResources`].

use super::{
    fullscreen_pipeline, InputAttachments, PassResources, PassSetup, PassType, RecordPass,
};
use crate::atmosphere::TableMapping;
use crate::render::plan::{attachment, FrameShape, PassIo};
use crate::render::sky_resources::SkyResources;
use crate::render::RenderError;
use crate::scene::{OzoneDepth, ShadowLight, TableFilter};
use crate::shader_ids::{
    SHADOW_SET, SPEC_OZONE_EXACT, SPEC_SKY_VIEW_HARDWARE_FILTER, SPEC_TABLE_FILTER,
    SPEC_TABLE_MAPPING, SPEC_TRANSPARENT_OVER_SKY,
};
use crate::shaders::{self, AtmosphereFragFeatures};
use crate::vk::{
    CommandBuffer, ComputePipeline, DescriptorSetLayout, GraphicsPipeline, PipelineLayout,
    ShaderModule,
};
use crate::vk::{CompareOp, DepthUse};

/// Fields drop in order: the pipelines before their layout and the sets.
pub struct AtmospherePass {
    /// Each pipeline draws the full screen once, in order.
    pipelines: Vec<GraphicsPipeline>,
    layout: PipelineLayout,
    inputs: InputAttachments,
    /// The empty sets' layout below the shadow set, with the sun's
    /// shadows (whose set is then bound).
    empty: Option<DescriptorSetLayout>,
}

/// A compute pipeline over the atmosphere's set that marches it (the
/// sky-view table's and the aerial-perspective volume's passes): `spirv`
/// with the atmosphere shaders' constants, the table's and the sky
/// block's unchanging fields. The layout is returned to outlive it.
pub(crate) fn march_pipeline(
    setup: &PassSetup<'_>,
    resources: &SkyResources,
    sky: &crate::scene::Sky,
    spirv: &[u8],
) -> Result<(PipelineLayout, ComputePipeline), RenderError> {
    let layout = PipelineLayout::new(setup.ctx, &[&resources.layout])?;
    let shader = ShaderModule::new(setup.ctx, spirv)?;
    let constants = [&table_constants(sky)[..], &resources.static_constants()].concat();
    let pipeline = ComputePipeline::new(setup.ctx, &layout, &shader, &constants)?;
    Ok((layout, pipeline))
}

/// The specialization constants the atmosphere shaders share: the
/// optical-depth table's mapping and filter, and where the ozone's
/// integral comes from, select code paths once, at pipeline creation.
pub(crate) fn table_constants(sky: &crate::scene::Sky) -> [(u32, u32); 3] {
    let mapping = match sky.table_mapping {
        TableMapping::Horizon => 0,
        TableMapping::Linear => 1,
    };
    let filter = match sky.table_filter {
        TableFilter::Manual => 0,
        TableFilter::Nearest => 1,
        TableFilter::Hardware => 2,
    };
    let ozone_exact = u32::from(sky.ozone_depth == OzoneDepth::Exact);
    [
        (SPEC_TABLE_MAPPING, mapping),
        (SPEC_TABLE_FILTER, filter),
        (SPEC_OZONE_EXACT, ozone_exact),
    ]
}

/// The pass in the frame's list ([`super::PASSES`]).
pub const PASS: &dyn PassType = &Pass;

struct Pass;

impl PassType for Pass {
    fn name(&self) -> &'static str {
        "atmosphere"
    }

    /// Over the surfaces, in frames with an atmosphere: reads the
    /// surfaces' colour and depth, writes HDR.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        use attachment::*;
        shape.sky.then(|| {
            let io = PassIo::subpass(
                vec![HDR],
                Some((DEPTH, DepthUse::Test)),
                vec![SURFACE, DEPTH],
            );
            // The ground takes the sun's shadows.
            if sun_shadows(shape) {
                io.sampling(&[SHADOW_MAP])
            } else {
                io
            }
        })
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        create(setup)
    }
}

/// Whether the frame draws the sun's shadows (onto the ground too).
fn sun_shadows(shape: &FrameShape<'_>) -> bool {
    shape.shadow_map.is_some()
        && shape
            .scene
            .is_some_and(|s| s.shadow_light == Some(ShadowLight::Sun))
}

fn create(setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
    let resources = setup.sky_resources()?;
    let sky = setup.scene.sky.as_ref().ok_or_else(|| {
        RenderError::Frame("the atmosphere pass needs a scene with [atmosphere]".into())
    })?;
    let inputs = InputAttachments::declared(setup)?;
    // With the sun's shadows, the shadow set at SHADOW_SET, after empty
    // sets.
    let shadow = match setup.decl.samples() {
        [] => None,
        _ => Some(setup.frame.shadow()?),
    };
    let empty = match shadow {
        Some(_) => Some(DescriptorSetLayout::new(setup.ctx, &[])?),
        None => None,
    };
    let mut set_layouts = vec![&resources.layout, &inputs.layout];
    if let (Some(shadow), Some(empty)) = (shadow, &empty) {
        set_layouts.resize(SHADOW_SET as usize, empty);
        set_layouts.push(&shadow.layout);
    }
    let layout = PipelineLayout::new(setup.ctx, &set_layouts)?;
    // The march's constants, plus the two only this pass's sky-view
    // variant reads.
    let constants = [
        &table_constants(sky)[..],
        &[
            (
                SPEC_SKY_VIEW_HARDWARE_FILTER,
                u32::from(resources.sky_view_hardware_filter()),
            ),
            (
                SPEC_TRANSPARENT_OVER_SKY,
                u32::from(setup.plan.draws().any(|d| d.pipeline.blended)),
            ),
        ],
        &resources.static_constants(),
        &shadow
            .and(setup.plan.shadow.as_ref())
            .map_or(Vec::new(), |view| view.constants().to_vec()),
    ]
    .concat();
    // (shader features, depth test) per draw.
    // With the aerial-perspective volume, pixels with a surface read it
    // (the AERIAL_VOLUME variant, LESS) and the others take the sky view
    // or march (EQUAL); without, the marching variant draws the surfaces.
    type Features = AtmosphereFragFeatures;
    let base = Features::NONE
        .with(
            Features::MULTIPLE_SCATTERING,
            resources.multiple_scattering(),
        )
        .with(Features::SHADOWS, shadow.is_some());
    let volume = resources.aerial_volume.is_some();
    let surfaces = base.with(Features::AERIAL_VOLUME, volume);
    let draws: Vec<(Features, Option<CompareOp>)> = match (resources.sky_view.is_some(), volume) {
        (true, _) => vec![
            (base | Features::SKY_VIEW, Some(CompareOp::EQUAL)),
            (surfaces, Some(CompareOp::LESS)),
        ],
        (false, true) => vec![
            (base, Some(CompareOp::EQUAL)),
            (surfaces, Some(CompareOp::LESS)),
        ],
        (false, false) => vec![(base, None)],
    };
    let pipelines = draws
        .iter()
        .map(|&(features, test)| {
            fullscreen_pipeline(
                setup.ctx,
                &layout,
                &setup.render_pass()?.render_pass,
                setup.subpass,
                shaders::ATMOSPHERE_FRAG.spirv(features),
                &constants,
                test,
            )
        })
        .collect::<Result<_, _>>()?;
    Ok(Box::new(AtmospherePass {
        pipelines,
        layout,
        inputs,
        empty,
    }))
}

impl RecordPass for AtmospherePass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let sky: &SkyResources = frame.sky()?;
        // Both pipelines share the layout, so the sets stay bound across
        // the pipeline switch.
        cmd.bind_descriptor_set(&self.layout, 0, &sky.set, &[]);
        cmd.bind_descriptor_set(&self.layout, 1, &self.inputs.set, &[]);
        if self.empty.is_some() {
            cmd.bind_descriptor_set(&self.layout, SHADOW_SET, &frame.shadow()?.set, &[]);
        }
        for pipeline in &self.pipelines {
            cmd.bind_pipeline(pipeline);
            cmd.draw(3);
        }
        Ok(())
    }
}
