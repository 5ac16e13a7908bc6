//! The draw list of a frame: one draw per object, with its pipeline
//! variant, textures and lights, grouped to save binds and ordered for the
//! depth test (opaque front to back, transparent back to front).

use super::geometry::SceneGeometry;
use crate::scene::material_maps::{MapKind, MapMask, MapSource, MAP_KIND_COUNT};
use crate::scene::{Material, Scene, ShadingModel};

/// A pipeline variant: shading model, light count and whole-number
/// shininess (specialization constants), the material maps it reads (shader
/// variants or a specialization constant, with the material descriptor
/// set) and alpha blending (the transparent pass).
///
/// The light count is a constant so the driver compiles the light loop with
/// a fixed trip count (unrolled, with constant offsets into the light
/// block); on lavapipe that is about twice as fast as a loop bounded by a
/// value read from the buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PipelineKey {
    pub shading: ShadingKey,
    /// The kinds of map the draw samples (each selected as its row of
    /// `MAP_KINDS` says; see [`MapMask::shader_features`]).
    pub maps: MapMask,
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
    /// Its maps, by kind (in table order): indices into `FramePlan::maps`.
    pub maps: MapSlots,
    /// Indices into `Scene::lights` evaluated while drawing the object
    /// (empty for surfaces lit later by the deferred lighting pass). The
    /// atmosphere's sun and sky are not among them: see
    /// [`PipelineKey::air`].
    pub lights: Vec<usize>,
}

/// A draw's maps: for each kind (in table order), an index into the
/// frame's list of distinct maps.
pub type MapSlots = [Option<usize>; MAP_KIND_COUNT];

/// The frame's draws and the textures they use, each loaded once.
#[derive(Clone, Debug, Default)]
pub struct DrawList {
    /// Opaque draws, grouped by pipeline and texture to save binds, front
    /// to back within a group (into the G-buffer when lit deferred).
    pub opaque: Vec<Draw>,
    /// Transparent draws, back to front from the camera.
    pub transparent: Vec<Draw>,
    /// Distinct map images, each of one kind.
    pub maps: Vec<(MapKind, MapSource)>,
}

impl DrawList {
    /// The draws of `scene`, whose meshes and bounds are `geometry`;
    /// `deferred` when opaque Phong surfaces are lit in the lighting pass
    /// (they then carry no lights of their own).
    pub fn new(scene: &Scene, geometry: &SceneGeometry, deferred: bool) -> DrawList {
        let mut maps: Vec<(MapKind, MapSource)> = Vec::new();
        let mut opaque = Vec::new();
        let mut transparent = Vec::new();
        // A debug view draws attributes, not light: every surface opaque,
        // no lights.
        let debug = scene.output.debug_view.map_or(0, |v| v as u32);
        let air = AirLight::of(scene);
        for (i, object) in scene.objects.iter().enumerate() {
            let material = &scene.materials[object.material];
            let slots = map_slots(material, debug, &mut maps);
            let mask = slots
                .iter()
                .zip(MapKind::all())
                .filter(|(slot, _)| slot.is_some())
                .fold(MapMask::default(), |mask, (_, kind)| mask.with(kind));
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
                    maps: mask,
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
                maps: slots,
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
            (pipeline, d.maps)
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
            maps,
        }
    }
}

/// The slots of `material`'s maps in `maps` (the frame's distinct map
/// images), adding those not there yet. Per-vertex lighting cannot use a
/// per-pixel map (the scene warned): such a map is left out, so no variant
/// reads what nobody uses. Debug views draw it whatever the shading.
fn map_slots(material: &Material, debug: u32, maps: &mut Vec<(MapKind, MapSource)>) -> MapSlots {
    let lit_per_vertex = material.shading == ShadingModel::Gouraud && debug == 0;
    let mut slots = MapSlots::default();
    for (kind, source) in material.maps.iter() {
        if lit_per_vertex && kind.info().per_pixel_only {
            continue;
        }
        let index = maps
            .iter()
            .position(|(k, s)| *k == kind && s.same_image(source))
            .unwrap_or_else(|| {
                maps.push((kind, source.clone()));
                maps.len() - 1
            });
        slots[kind as usize] = Some(index);
    }
    slots
}
