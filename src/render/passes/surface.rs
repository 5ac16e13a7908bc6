//! Surface passes: draw the scene's objects. Three declared forms share
//! this type:
//! - `opaque`: forward shading into the colour target, depth tested and
//!   written;
//! - `transparent`: forward shading blended over the colour target, depth
//!   tested but not written (the draws are sorted back to front instead);
//! - `gbuffer`: opaque surfaces for deferred lighting, writing the ambient
//!   term to the colour target and the G-buffer targets (shader feature
//!   `GBUFFER`).
//!
//! In a scene with an atmosphere every form also lights its surfaces by
//! the sun and sky at each shaded point (`AirLight`, shader features
//! `SUN_LIGHT` and `SKY_LIGHT`), reading the atmosphere's set.

use super::{PassResources, PassSetup, PassType, RecordPass};
use crate::mesh::Vertex;
use crate::render::gpu_types::InstanceTransform;
use crate::render::plan::{
    attachment, AirLight, Draw, FramePlan, FrameShape, PassIo, PipelineKey, ShadingKey,
};
use crate::render::shadow_view::ShadowView;
use crate::render::static_lights;
use crate::render::RenderError;
use crate::scene::material_maps::MapMask;
use crate::scene::Scene;
use crate::shader_ids::*;
use crate::shaders::{self, ObjectFragFeatures, ObjectVertFeatures};
use crate::vk::{
    Blend, CommandBuffer, CullModeFlags, Format, GraphicsPipeline, GraphicsPipelineDesc,
    ShaderModule, VertexAttribute,
};
use crate::vk::{CompareOp, DepthUse};
use std::collections::btree_map::Entry;
use std::collections::BTreeMap;

/// Which form of the pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Form {
    Opaque,
    Transparent,
    GBuffer,
}

/// A pipeline: the draw's key, and its lights when they are
/// specialization constants (`render::static_lights`).
type SurfaceKey = (PipelineKey, Option<Vec<usize>>);

pub struct SurfacePass {
    form: Form,
    draws: Vec<Draw>,
    /// Each draw's pipeline, resolved when the draws are taken so that
    /// recording copies no light lists.
    draw_keys: Vec<SurfaceKey>,
    pipelines: BTreeMap<SurfaceKey, GraphicsPipeline>,
    /// Whether draws that can carry their lights as constants do.
    static_lights: bool,
}

/// Which pipeline `d` uses: with `static_lights`, a draw whose lights fit
/// is specialized by them (the atmosphere's sun is not among them: it
/// follows the frame's sun from the atmosphere's uniforms).
fn surface_key(d: &Draw, static_lights: bool) -> SurfaceKey {
    let lights = (static_lights && static_lights::fits(&d.lights)).then(|| d.lights.clone());
    (d.pipeline, lights)
}

/// [`surface_key`] of each of `draws`.
fn surface_keys(draws: &[Draw], static_lights: bool) -> Vec<SurfaceKey> {
    draws
        .iter()
        .map(|d| surface_key(d, static_lights))
        .collect()
}

/// The forms in the frame's list ([`super::PASSES`]).
pub const OPAQUE: &dyn PassType = &Form::Opaque;
pub const TRANSPARENT: &dyn PassType = &Form::Transparent;
pub const GBUFFER: &dyn PassType = &Form::GBuffer;

impl PassType for Form {
    fn name(&self) -> &'static str {
        match self {
            Form::Opaque => "opaque",
            Form::Transparent => "transparent",
            Form::GBuffer => "gbuffer",
        }
    }

    /// Opaque surfaces in one of the forward and the G-buffer forms (in
    /// every frame that draws a scene, with objects or not); transparent
    /// ones where the scene has some.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo> {
        use attachment::*;
        shape.scene?;
        let target = shape.target;
        let io = match self {
            Form::Opaque if !shape.deferred => {
                PassIo::subpass(vec![target], Some((DEPTH, shape.surface_depth())), vec![])
            }
            Form::GBuffer if shape.deferred => PassIo::subpass(
                vec![target, ALBEDO, NORMAL, MATERIAL],
                Some((DEPTH, shape.surface_depth())),
                vec![],
            ),
            Form::Transparent if shape.any_transparent => {
                PassIo::subpass(vec![target], Some((DEPTH, DepthUse::Test)), vec![])
            }
            _ => return None,
        };
        // Shadowed draws look the shadow map up (forward forms only).
        let shadowed = shape.shadow_map.is_some() && *self != Form::GBuffer;
        Some(if shadowed {
            io.sampling(&[SHADOW_MAP])
        } else {
            io
        })
    }

    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError> {
        SurfacePass::create(setup, *self)
    }
}

impl SurfacePass {
    fn create(setup: &PassSetup<'_>, form: Form) -> Result<Box<dyn RecordPass>, RenderError> {
        let draws = match form {
            Form::Transparent => setup.plan.transparent.clone(),
            Form::Opaque | Form::GBuffer => setup.plan.opaque.clone(),
        };
        // Pipelines for the draws out of view too, so a view that brings
        // them in keeps the pass.
        let hidden: Vec<Draw> = setup
            .plan
            .hidden
            .iter()
            .filter(|d| d.pipeline.blended == (form == Form::Transparent))
            .cloned()
            .collect();
        let mut pipelines = BTreeMap::new();
        let distinct = |keys: &[SurfaceKey]| {
            let mut keys = keys.to_vec();
            keys.sort();
            keys.dedup();
            keys
        };
        // Past the limit, every draw reads its lights from its block.
        let every_key =
            |lights: bool| [surface_keys(&draws, lights), surface_keys(&hidden, lights)].concat();
        let static_lights = static_lights::enabled(setup.scene, distinct(&every_key(true)).len());
        let draw_keys = surface_keys(&draws, static_lights);
        let keys = distinct(&every_key(static_lights));
        // Drawn straight into the 8-bit output (UNORM), the shader encodes
        // sRGB itself, as the tone map does.
        let encode_srgb = matches!(
            &setup.decl.io,
            PassIo::Subpass { colour, .. } if colour.first() == Some(&attachment::OUTPUT)
        );
        if !keys.is_empty() {
            let resources = setup.scene_resources()?;
            // The atmosphere's constants, for pipelines it lights.
            let air_constants = match (&setup.scene.sky, setup.frame.sky) {
                (Some(sky), Some(sky_resources)) => sky_resources.object_constants(sky),
                _ => Vec::new(),
            };
            let render_pass = setup.render_pass()?;
            let blend = match form {
                Form::Opaque => vec![Blend::Replace],
                Form::Transparent => vec![Blend::Alpha],
                Form::GBuffer => vec![Blend::Replace; 4],
            };
            // Keys that differ only in specialization constants (light
            // count, shading model) share their shader modules.
            let mut modules: BTreeMap<_, (ShaderModule, ShaderModule)> = BTreeMap::new();
            for (key, lights) in keys {
                let (vert, frag) = match modules.entry(shader_features(&key, form)) {
                    Entry::Occupied(modules) => modules.into_mut(),
                    Entry::Vacant(slot) => {
                        let (vert, frag) = *slot.key();
                        slot.insert((
                            ShaderModule::new(setup.ctx, shaders::OBJECT_VERT.spirv(vert))?,
                            ShaderModule::new(setup.ctx, shaders::OBJECT_FRAG.spirv(frag))?,
                        ))
                    }
                };
                let (vert, frag) = (&*vert, &*frag);
                let attributes = vertex_attributes(key.maps, key.debug != 0);
                let instance_attributes = if key.instanced {
                    instance_attributes()
                } else {
                    Vec::new()
                };
                let specialization = specialization(
                    &key,
                    encode_srgb,
                    setup.plan.shadow.as_ref(),
                    static_lights::constants(
                        setup.scene,
                        resources.light_anchor,
                        lights.as_deref(),
                    ),
                    &air_constants,
                )?;
                let pipeline = GraphicsPipeline::new(
                    setup.ctx,
                    &resources.layout,
                    &render_pass.render_pass,
                    &GraphicsPipelineDesc {
                        vertex_shader: vert,
                        fragment_shader: Some(frag),
                        specialization: &specialization,
                        vertex_stride: std::mem::size_of::<Vertex>() as u32,
                        vertex_attributes: &attributes,
                        instance_stride: instance_stride(key.instanced),
                        instance_attributes: &instance_attributes,
                        cull_mode: if key.two_sided {
                            CullModeFlags::NONE
                        } else {
                            CullModeFlags::BACK
                        },
                        depth_test: Some(depth_compare(setup, form)),
                        // Transparent surfaces test against opaque depth but
                        // do not hide each other; they are sorted instead.
                        // After a depth pre-pass, depth is final already.
                        depth_write: form != Form::Transparent && !after_prepass(setup),
                        depth_bias: None,
                        blend: &blend,
                        subpass: setup.subpass,
                    },
                )?;
                pipelines.insert((key, lights), pipeline);
            }
        }
        Ok(Box::new(SurfacePass {
            form,
            draws,
            draw_keys,
            pipelines,
            static_lights,
        }))
    }
}

impl RecordPass for SurfacePass {
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError> {
        let Some(resources) = frame.scene else {
            return Ok(());
        };
        let mut bound: Option<&SurfaceKey> = None;
        for (d, key) in self.draws.iter().zip(&self.draw_keys) {
            let layout = &resources.layout;
            if bound != Some(key) {
                cmd.bind_pipeline(&self.pipelines[key]);
                if bound.is_none() {
                    cmd.bind_descriptor_set(layout, FRAME_SET, &resources.frame_set, &[]);
                    // Every draw of a scene shares one AirLight.
                    if key.0.air != AirLight::None {
                        cmd.bind_descriptor_set(layout, SKY_SET, &frame.sky()?.set, &[]);
                    }
                    // Present exactly when some draw is shadowed.
                    if let Some(shadow) = frame.shadow {
                        cmd.bind_descriptor_set(layout, SHADOW_SET, &shadow.set, &[]);
                    }
                }
                bound = Some(key);
            }
            let range = &resources.ranges[d.object];
            if range.index_count == 0 {
                continue;
            }
            cmd.bind_descriptor_set(
                layout,
                OBJECT_SET,
                &resources.object_set,
                &[resources.block_offsets[d.object]],
            );
            if let Some(set) = resources.material_set(&d.maps) {
                cmd.bind_descriptor_set(layout, MATERIAL_SET, set, &[]);
            }
            resources.draw(cmd, d)?;
        }
        Ok(())
    }

    /// Takes the new view's draw order (the same draws, sorted from the
    /// new camera).
    fn set_view(&mut self, _scene: &Scene, plan: &FramePlan) -> Result<(), RenderError> {
        let draws = match self.form {
            Form::Transparent => &plan.transparent,
            Form::Opaque | Form::GBuffer => &plan.opaque,
        };
        let keys = surface_keys(draws, self.static_lights);
        if let Some((d, _)) = draws
            .iter()
            .zip(&keys)
            .find(|(_, key)| !self.pipelines.contains_key(key))
        {
            return Err(RenderError::Frame(format!(
                "object {} needs a pipeline the '{:?}' pass did not create",
                d.object, self.form
            )));
        }
        self.draws = draws.clone();
        self.draw_keys = keys;
        Ok(())
    }
}

/// Whether opaque surfaces were drawn depth-only before this pass: its
/// declared depth use is then a test, not a write.
fn after_prepass(setup: &PassSetup<'_>) -> bool {
    setup.plan.has(super::depth_prepass::PASS)
        && matches!(
            &setup.decl.io,
            PassIo::Subpass {
                depth: Some((_, DepthUse::Test)),
                ..
            }
        )
}

/// The depth comparison of the pass's pipelines. Reversed-Z: nearer
/// surfaces have larger depth, so GREATER keeps the nearest. After the
/// depth pre-pass, which drew the same positions (see `depth_prepass`),
/// EQUAL shades only the fragment it kept.
fn depth_compare(setup: &PassSetup<'_>, form: Form) -> CompareOp {
    if form != Form::Transparent && after_prepass(setup) {
        CompareOp::EQUAL
    } else {
        CompareOp::GREATER
    }
}

/// The specialization constants of `key`'s pipeline: its own, then the
/// static lights' (`light_constants`) and, for objects the atmosphere
/// lights, the atmosphere's (`air_constants`, empty without one).
fn specialization(
    key: &PipelineKey,
    encode_srgb: bool,
    shadow: Option<&ShadowView>,
    light_constants: Vec<(u32, u32)>,
    air_constants: &[(u32, u32)],
) -> Result<Vec<(u32, u32)>, RenderError> {
    let mut specialization = vec![
        (SPEC_SHADING_MODEL, key.shading as u32),
        (SPEC_LIGHT_COUNT, key.lights),
        (SPEC_LIGHT_ARRAY_LENGTH, key.lights.max(1)),
        (SPEC_DEBUG_ATTRIBUTE, key.debug),
        (SPEC_SHININESS_EXPONENT, key.shininess_exponent),
    ];
    // Only two-sided pipelines carry the constant: one-sided ones keep its
    // default (false) and their cull mode.
    if key.two_sided {
        specialization.push((SPEC_TWO_SIDED, 1));
    }
    // Likewise the maps selected by a constant: a pipeline without them is
    // created as if the constant did not exist.
    if key.maps.constant() != 0 {
        specialization.push((SPEC_MATERIAL_MAPS, key.maps.constant()));
    }
    if encode_srgb {
        specialization.push((SPEC_ENCODE_SRGB, 1));
    }
    if let Some(shadow) = shadow.filter(|_| key.shadowed) {
        specialization.extend(shadow.constants());
    }
    specialization.extend(light_constants);
    if key.air != AirLight::None {
        if air_constants.is_empty() {
            return Err(RenderError::Frame(
                "objects lit by the atmosphere, but the frame has no atmosphere".into(),
            ));
        }
        specialization.extend(air_constants);
    }
    Ok(specialization)
}

/// The object shaders' features for a pipeline of `key` in `form`: the
/// vertex stage's and the fragment stage's (which alone has `GBUFFER`).
fn shader_features(key: &PipelineKey, form: Form) -> (ObjectVertFeatures, ObjectFragFeatures) {
    let debug = key.debug != 0;
    let gouraud = !debug && key.shading == ShadingKey::Gouraud;
    let (maps_vert, maps_frag) = key.maps.shader_features();
    let vert = maps_vert
        .with(ObjectVertFeatures::DEBUG_VIEW, debug)
        .with(ObjectVertFeatures::GOURAUD, gouraud)
        .with(ObjectVertFeatures::SUN_LIGHT, key.air.sun())
        .with(ObjectVertFeatures::SKY_LIGHT, key.air.sky())
        .with(ObjectVertFeatures::INSTANCED, key.instanced);
    let frag = maps_frag
        .with(ObjectFragFeatures::GBUFFER, form == Form::GBuffer)
        .with(ObjectFragFeatures::DEBUG_VIEW, debug)
        .with(ObjectFragFeatures::GOURAUD, gouraud)
        .with(ObjectFragFeatures::SUN_LIGHT, key.air.sun())
        .with(ObjectFragFeatures::SKY_LIGHT, key.air.sky())
        .with(
            ObjectFragFeatures::SHADOWS,
            key.shadowed && form != Form::GBuffer,
        );
    (vert, frag)
}

/// The instance buffer's stride for a pipeline: an instance's transforms
/// when it draws batches as instances, else none.
pub(super) fn instance_stride(instanced: bool) -> u32 {
    if instanced {
        std::mem::size_of::<InstanceTransform>() as u32
    } else {
        0
    }
}

/// The per-instance attributes of an instanced pipeline: the model
/// matrix's four columns and the normal matrix's three
/// (`InstanceTransform`).
pub(super) fn instance_attributes() -> Vec<VertexAttribute> {
    let model = std::mem::offset_of!(InstanceTransform, model) as u32;
    let normal = std::mem::offset_of!(InstanceTransform, normal_matrix) as u32;
    let columns = (0..4u32).map(|c| VertexAttribute {
        location: INSTANCE_MODEL_LOCATION + c,
        format: Format::R32G32B32A32_SFLOAT,
        offset: model + 16 * c,
    });
    let normal_columns = (0..3u32).map(|c| VertexAttribute {
        location: INSTANCE_NORMAL_LOCATION + c,
        format: Format::R32G32B32_SFLOAT,
        offset: normal + 12 * c,
    });
    columns.chain(normal_columns).collect()
}

/// The vertex attributes a pipeline consumes: position and normal always,
/// UVs for materials with maps, tangents only for those with a map that
/// needs them (shaders that do not read them are not fed them); a debug
/// view reads both.
fn vertex_attributes(maps: MapMask, debug: bool) -> Vec<VertexAttribute> {
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
    if maps.needs_tangents() || debug {
        attributes.push(VertexAttribute {
            location: 2,
            format: Format::R32G32B32A32_SFLOAT,
            offset: offset(std::mem::offset_of!(Vertex, tangent)),
        });
    }
    if maps.needs_uvs() || debug {
        attributes.push(VertexAttribute {
            location: 3,
            format: Format::R32G32_SFLOAT,
            offset: offset(std::mem::offset_of!(Vertex, uv)),
        });
    }
    attributes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::material_maps::{MapKind, MAP_KIND_COUNT};

    /// Every variant the pass can ask for is compiled: the build script leaves out
    /// the combinations the object shaders' rules exclude (the
    /// atmosphere's light in a debug view, the sky without the sun), and
    /// none of them is one a pipeline key leads to. A debug view never
    /// carries the atmosphere's light (`AirLight::of`).
    #[test]
    fn every_variant_a_pipeline_can_ask_for_is_compiled() {
        let mut asked = 0;
        for form in [Form::Opaque, Form::Transparent, Form::GBuffer] {
            for shading in [ShadingKey::Phong, ShadingKey::Gouraud, ShadingKey::Toon] {
                for air in [AirLight::None, AirLight::Sun, AirLight::SunAndSky] {
                    for debug in [0, 1] {
                        if debug != 0 && air != AirLight::None {
                            continue;
                        }
                        for (bits, instanced) in (0..1u32 << MAP_KIND_COUNT)
                            .flat_map(|bits| [(bits, false), (bits, true)])
                        {
                            let maps = MapKind::all()
                                .filter(|&kind| bits & 1 << kind as u32 != 0)
                                .fold(MapMask::default(), MapMask::with);
                            let key = PipelineKey {
                                shading,
                                maps,
                                blended: false,
                                lights: 0,
                                debug,
                                shininess_exponent: 0,
                                two_sided: false,
                                air,
                                instanced,
                                shadowed: false,
                            };
                            let (vert, frag) = shader_features(&key, form);
                            assert!(shaders::OBJECT_VERT.is_compiled(vert), "{key:?}");
                            assert!(shaders::OBJECT_FRAG.is_compiled(frag), "{key:?}");
                            asked += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(asked, 3 * 3 * 4 * (1 << MAP_KIND_COUNT) * 2);
        // And a left-out combination has no SPIR-V.
        assert!(!shaders::OBJECT_FRAG.is_compiled(ObjectFragFeatures::SKY_LIGHT));
    }
}
