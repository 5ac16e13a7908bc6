//! The draw list of a frame: one draw per object, with its pipeline
//! variant, textures and lights, grouped to save binds and ordered for the
//! depth test (opaque front to back, transparent back to front).

use super::geometry::SceneGeometry;
use crate::scene::{Scene, ShadingModel, Texture};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// A pipeline variant: shading model, light count and whole-number
/// shininess (specialization constants), base colour texture (a shader variant with its own
/// descriptor set) and alpha blending (the transparent pass).
///
/// The light count is a constant so the driver compiles the light loop with
/// a fixed trip count (unrolled, with constant offsets into the light
/// block); on lavapipe that is about twice as fast as a loop bounded by a
/// value read from the buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PipelineKey {
    pub shading: ShadingKey,
    pub textured: bool,
    /// Tangent-space normal map (shader feature `NORMAL_MAP`, the tangent
    /// attribute and one more descriptor set).
    pub normal_mapped: bool,
    pub blended: bool,
    /// Lights in the object's block.
    pub lights: u32,
    /// The attribute a debug view draws (`DebugView as u32`), 0 for none
    /// (shader feature `DEBUG_VIEW`, specialization constant 3).
    pub debug: u32,
    /// The material's shininess when it is a whole number from 1 to
    /// [`MAX_SHININESS_EXPONENT`], else 0 (specialization constant 4): the
    /// shader then raises to that power by multiplying instead of `pow`.
    pub shininess_exponent: u32,
    /// Both sides drawn: no back-face culling, and the normal reversed on
    /// back faces (specialization constant 6, given only when true, so
    /// one-sided pipelines are created exactly as without it).
    pub two_sided: bool,
    /// The atmosphere's light on the object, computed at each shaded point
    /// (shader features `SUN_LIGHT` and `SKY_LIGHT`, and the atmosphere's
    /// descriptor set).
    pub air: AirLight,
}

/// How an atmosphere lights objects: per shaded point (per pixel; per
/// vertex for Gouraud), from the tables the atmosphere pass reads
/// (`glsl/include/object_air.glsl`). The sun's direction and irradiance
/// come from the atmosphere's uniforms, so a frame that turns the sun
/// keeps its pipelines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AirLight {
    /// No atmosphere (or a debug view): the object shaders compile none
    /// of it.
    None,
    /// The sun through the air, with its transmittance to the point and
    /// the planet's shadow (single scattering: no sky light, as on the
    /// ground).
    Sun,
    /// The sun and the sky's irradiance (multiple scattering, whose
    /// sky-irradiance table the sky light reads).
    SunAndSky,
}

impl AirLight {
    /// The light `scene`'s atmosphere gives its objects: none without one
    /// or in a debug view (which draws attributes, not light).
    pub fn of(scene: &Scene) -> AirLight {
        match &scene.sky {
            Some(_) if scene.output.debug_view.is_some() => AirLight::None,
            Some(sky) if sky.multiple_scattering => AirLight::SunAndSky,
            Some(_) => AirLight::Sun,
            None => AirLight::None,
        }
    }

    /// Whether objects take the atmosphere's sun light.
    pub fn sun(self) -> bool {
        self != AirLight::None
    }

    /// Whether objects take the atmosphere's sky light.
    pub fn sky(self) -> bool {
        self == AirLight::SunAndSky
    }
}

/// The largest shininess the shaders raise to by squaring (nine squarings).
pub const MAX_SHININESS_EXPONENT: u32 = 1023;

/// [`PipelineKey::shininess_exponent`] for `shininess`.
pub fn shininess_exponent(shininess: f32) -> u32 {
    if shininess.fract() == 0.0 && (1.0..=MAX_SHININESS_EXPONENT as f32).contains(&shininess) {
        shininess as u32
    } else {
        0
    }
}

/// `ShadingModel` as an ordered key (the GLSL specialization value).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ShadingKey {
    Phong = 0,
    Gouraud = 1,
    Toon = 2,
}

impl From<ShadingModel> for ShadingKey {
    fn from(m: ShadingModel) -> Self {
        match m {
            ShadingModel::Phong => ShadingKey::Phong,
            ShadingModel::Gouraud => ShadingKey::Gouraud,
            ShadingModel::Toon => ShadingKey::Toon,
        }
    }
}

/// One object draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Draw {
    pub object: usize,
    pub pipeline: PipelineKey,
    /// Index into `FramePlan::textures`.
    pub texture: Option<usize>,
    /// Index into `FramePlan::normal_maps`.
    pub normal_map: Option<usize>,
    /// Indices into `Scene::lights` evaluated while drawing the object
    /// (empty for surfaces lit later by the deferred lighting pass). The
    /// atmosphere's sun and sky are not among them: see
    /// [`PipelineKey::air`].
    pub lights: Vec<usize>,
}

/// Where a normal map comes from: a normal-map file, or a height map
/// converted when the textures are loaded (`height_scale` set).
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMapSource {
    pub path: PathBuf,
    pub height_scale: Option<f32>,
}

/// The frame's draws and the textures they use, each loaded once.
#[derive(Clone, Debug, Default)]
pub struct DrawList {
    /// Opaque draws, grouped by pipeline and texture to save binds, front
    /// to back within a group (into the G-buffer when lit deferred).
    pub opaque: Vec<Draw>,
    /// Transparent draws, back to front from the camera.
    pub transparent: Vec<Draw>,
    /// Distinct base-colour textures.
    pub textures: Vec<Texture>,
    /// Distinct normal maps (linear, not sRGB).
    pub normal_maps: Vec<NormalMapSource>,
}

impl DrawList {
    /// The draws of `scene`, whose meshes and bounds are `geometry`;
    /// `deferred` when opaque Phong surfaces are lit in the lighting pass
    /// (they then carry no lights of their own).
    pub fn new(scene: &Scene, geometry: &SceneGeometry, deferred: bool) -> DrawList {
        let mut textures: Vec<Texture> = Vec::new();
        let mut texture_index = BTreeMap::new();
        let mut normal_maps: Vec<NormalMapSource> = Vec::new();
        let mut normal_map_index = BTreeMap::new();
        let mut opaque = Vec::new();
        let mut transparent = Vec::new();
        // A debug view draws attributes, not light: every surface opaque,
        // no lights.
        let debug = scene.output.debug_view.map_or(0, |v| v as u32);
        let air = AirLight::of(scene);
        for (i, object) in scene.objects.iter().enumerate() {
            let material = &scene.materials[object.material];
            let texture = material.texture.as_ref().map(|source| {
                *texture_index.entry(source.clone()).or_insert_with(|| {
                    textures.push(source.clone());
                    textures.len() - 1
                })
            });
            // Per-vertex lighting cannot use a per-pixel normal (the scene
            // warned): the map is left out, so no variant interpolates
            // tangents nobody reads. Debug views draw it whatever the shading.
            let lit_per_vertex = material.shading == ShadingModel::Gouraud && debug == 0;
            let normal_map = material
                .normal_map
                .as_ref()
                .filter(|_| !lit_per_vertex)
                .map(|path| {
                    let source = NormalMapSource {
                        path: path.clone(),
                        height_scale: material.height_scale,
                    };
                    let key = (path.clone(), material.height_scale.map(f32::to_bits));
                    *normal_map_index.entry(key).or_insert_with(|| {
                        normal_maps.push(source);
                        normal_maps.len() - 1
                    })
                });
            let blended = material.opacity < 1.0 && debug == 0;
            let lit_later = deferred && !blended && material.shading == ShadingModel::Phong;
            let lights = if lit_later || debug != 0 {
                Vec::new()
            } else {
                let (centre, radius) = geometry.bounds[i];
                scene.lights_reaching_sphere(centre, radius)
            };
            let draw = Draw {
                object: i,
                pipeline: PipelineKey {
                    shading: material.shading.into(),
                    textured: texture.is_some(),
                    normal_mapped: normal_map.is_some(),
                    blended,
                    lights: lights.len() as u32,
                    debug,
                    // The G-buffer form leaves lighting to the lighting
                    // pass; only the forward shaders use it.
                    shininess_exponent: if lit_later {
                        0
                    } else {
                        shininess_exponent(material.shininess)
                    },
                    two_sided: object.is_two_sided(material),
                    // The sun and sky light every surface of the scene, lit
                    // later or not: per point, they gain nothing from the
                    // lighting pass's tiles.
                    air,
                },
                texture,
                normal_map,
                lights,
            };
            if blended {
                transparent.push(draw);
            } else {
                opaque.push(draw);
            }
        }
        let eye = scene.camera.eye;
        let distance = |d: &Draw| geometry.bounds[d.object].0.distance(eye);
        // Opaque: grouped by pipeline and texture (fewer binds), front to
        // back within a group, so the depth test rejects hidden fragments
        // before they are shaded.
        let mut keyed: Vec<(f64, Draw)> = opaque.into_iter().map(|d| (distance(&d), d)).collect();
        // The shininess exponent is left out of the grouping: it only
        // changes the specular arithmetic, and materials differing in it
        // alone are better drawn front to back than a bind apart.
        let group = |d: &Draw| {
            let pipeline = PipelineKey {
                shininess_exponent: 0,
                ..d.pipeline
            };
            (pipeline, d.texture, d.normal_map)
        };
        keyed.sort_by(|a, b| group(&a.1).cmp(&group(&b.1)).then(a.0.total_cmp(&b.0)));
        let opaque: Vec<Draw> = keyed.into_iter().map(|(_, d)| d).collect();
        // Transparent: back to front; ties keep scene order.
        let mut keyed: Vec<(f64, Draw)> =
            transparent.into_iter().map(|d| (distance(&d), d)).collect();
        keyed.sort_by(|a, b| b.0.total_cmp(&a.0));
        let transparent: Vec<Draw> = keyed.into_iter().map(|(_, d)| d).collect();

        DrawList {
            opaque,
            transparent,
            textures,
            normal_maps,
        }
    }
}
