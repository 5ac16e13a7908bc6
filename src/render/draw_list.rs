//! The draw list of a frame: one draw per object, or one instanced draw
//! per batch of opaque objects that differ only in their transform, with
//! its pipeline variant, textures and lights; objects wholly outside the
//! view are left out; draws are grouped to save binds and ordered for the
//! depth test (opaque front to back, transparent back to front).

use std::collections::HashMap;
use std::sync::Arc;

use super::geometry::SceneGeometry;
use crate::scene::material_maps::{MapKind, MapMask, MapSource, MAP_KIND_COUNT};
use crate::scene::{Material, Scene, ShadingModel, ShadowLight};

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
    /// Drawn as instances: the transforms come from the instance buffer
    /// (shader feature `INSTANCED`), not the object's block.
    pub instanced: bool,
    /// Lit by the shadow-casting light, whose term the shadow map scales
    /// (shader feature `SHADOWS`, the shadow set).
    pub shadowed: bool,
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

/// One draw: an object, or a batch of objects drawn as instances.
#[derive(Clone, Debug, PartialEq)]
pub struct Draw {
    /// The object whose mesh and block (material, lights) the draw uses:
    /// for a batch, its first member in scene order.
    pub object: usize,
    pub pipeline: PipelineKey,
    /// Its maps, by kind (in table order): indices into `FramePlan::maps`.
    pub maps: MapSlots,
    /// Indices into `Scene::lights` evaluated while drawing the object
    /// (empty for surfaces lit later by the deferred lighting pass). The
    /// atmosphere's sun and sky are not among them: see
    /// [`PipelineKey::air`].
    pub lights: Vec<usize>,
    /// The batch an instanced draw draws (`pipeline.instanced`).
    pub instances: Option<Instances>,
}

impl Draw {
    /// The draw with what the view decides (the batch members in view)
    /// left out: two plans whose draws agree on this need the same
    /// pipelines, blocks and buffers.
    pub fn without_view(&self) -> Draw {
        let mut draw = self.clone();
        if let Some(instances) = &mut draw.instances {
            instances.visible.clear();
        }
        draw
    }

    /// The objects the draw covers, in view or not.
    pub fn objects(&self) -> &[usize] {
        match &self.instances {
            Some(instances) => &instances.members,
            None => std::slice::from_ref(&self.object),
        }
    }

    /// The objects this draw puts on screen, in drawing order: an instance
    /// batch's members in view, or its one object.
    pub fn visible(&self) -> &[usize] {
        match &self.instances {
            Some(instances) => &instances.visible,
            None => std::slice::from_ref(&self.object),
        }
    }
}

/// A batch of opaque objects with the same mesh, material, lights and
/// pipeline: one draw whose per-instance transforms come from the frame's
/// instance buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct Instances {
    /// The batch's first slot in the instance buffer; it owns one slot per
    /// member, in view or not, so the layout does not follow the view.
    pub first: u32,
    /// Every member, in scene order.
    pub members: Vec<usize>,
    /// The members in view, front to back: what is drawn, from `first` on.
    pub visible: Vec<usize>,
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
    /// Draws wholly outside the view: not recorded, but their pipelines
    /// and blocks are made, so a view that brings them in keeps the
    /// frame's resources.
    pub hidden: Vec<Draw>,
    /// Slots in the instance buffer (every batch's members); 0 when no
    /// objects are drawn as instances, and the frame has no such buffer.
    pub instance_slots: u32,
    /// Distinct map images, each of one kind.
    pub maps: Vec<(MapKind, MapSource)>,
}

/// The fewest objects drawn as one instanced draw: a single object keeps
/// its plain draw, so a scene of unique objects has no instance buffer.
const MIN_INSTANCES: usize = 2;

impl DrawList {
    /// The draws of `scene`, whose meshes and bounds are `geometry`;
    /// `deferred` when opaque Phong surfaces are lit in the lighting pass
    /// (they then carry no lights of their own).
    pub fn new(scene: &Scene, geometry: &SceneGeometry, deferred: bool) -> DrawList {
        let mut maps: Vec<(MapKind, MapSource)> = Vec::new();
        let draws: Vec<Draw> = (0..scene.objects.len())
            .map(|i| object_draw(scene, geometry, i, deferred, &mut maps))
            .collect();
        let (opaque, transparent): (Vec<Draw>, Vec<Draw>) =
            draws.into_iter().partition(|d| !d.pipeline.blended);
        let (opaque, instance_slots) = batch(scene, geometry, opaque);

        let frustum = Frustum::of(scene);
        let eye = scene.camera.eye;
        let distance = |object: usize| geometry.bounds[object].0.distance(eye);
        let in_view = |object: usize| {
            let (centre, radius) = geometry.bounds[object];
            frustum.may_see(scene.camera.relative(centre), f64::from(radius))
        };
        let mut hidden = Vec::new();
        // Each draw with the distance of its nearest object in view.
        let mut keyed = |draws: Vec<Draw>| -> Vec<(f64, Draw)> {
            let mut kept = Vec::with_capacity(draws.len());
            for mut d in draws {
                let nearest = match &mut d.instances {
                    Some(instances) => {
                        let mut visible: Vec<(f64, usize)> = instances
                            .members
                            .iter()
                            .filter(|&&o| in_view(o))
                            .map(|&o| (distance(o), o))
                            .collect();
                        visible.sort_by(|a, b| a.0.total_cmp(&b.0));
                        instances.visible = visible.iter().map(|&(_, o)| o).collect();
                        visible.first().map(|&(d, _)| d)
                    }
                    None => in_view(d.object).then(|| distance(d.object)),
                };
                match nearest {
                    Some(nearest) => kept.push((nearest, d)),
                    None => hidden.push(d),
                }
            }
            kept
        };
        let mut opaque = keyed(opaque);
        let mut transparent = keyed(transparent);
        // Opaque: grouped by pipeline and texture (fewer binds), front to
        // back within a group, so the depth test rejects hidden fragments
        // before they are shaded. The shininess exponent is left out of the
        // grouping: it only changes the specular arithmetic, and materials
        // differing in it alone are better drawn front to back than a bind
        // apart.
        let group = |d: &Draw| {
            let pipeline = PipelineKey {
                shininess_exponent: 0,
                ..d.pipeline
            };
            (pipeline, d.maps)
        };
        opaque.sort_by(|a, b| group(&a.1).cmp(&group(&b.1)).then(a.0.total_cmp(&b.0)));
        // Transparent: back to front; ties keep scene order.
        transparent.sort_by(|a, b| b.0.total_cmp(&a.0));
        let unkey = |keyed: Vec<(f64, Draw)>| keyed.into_iter().map(|(_, d)| d).collect();
        DrawList {
            opaque: unkey(opaque),
            transparent: unkey(transparent),
            hidden,
            maps,
            instance_slots,
        }
    }
}

/// Object `i`'s own draw (its maps added to `maps`).
fn object_draw(
    scene: &Scene,
    geometry: &SceneGeometry,
    i: usize,
    deferred: bool,
    maps: &mut Vec<(MapKind, MapSource)>,
) -> Draw {
    let object = &scene.objects[i];
    // A debug view draws attributes, not light: every surface opaque, no
    // lights.
    let debug = scene.output.debug_view.map_or(0, |v| v as u32);
    let material = &scene.materials[object.material];
    let slots = map_slots(material, debug, maps);
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
    let shadowed = receives_shadow(scene, material, &lights, debug);
    Draw {
        object: i,
        pipeline: PipelineKey {
            shading: material.shading.into(),
            maps: mask,
            blended,
            lights: lights.len() as u32,
            debug,
            // The G-buffer form leaves lighting to the lighting pass; only
            // the forward shaders use it.
            shininess_exponent: if lit_later {
                0
            } else {
                shininess_exponent(material.shininess)
            },
            two_sided: object.is_two_sided(material),
            // The sun and sky light every surface of the scene, lit later
            // or not: per point, they gain nothing from the lighting
            // pass's tiles.
            air: AirLight::of(scene),
            instanced: false,
            shadowed,
        },
        maps: slots,
        lights,
        instances: None,
    }
}

/// Whether a draw of `material` evaluating scene `lights` (and the sun,
/// with an atmosphere) is lit by the frame's shadow-casting light, when
/// the frame draws a shadow map (`plan::shadow_map_size`). Gouraud
/// surfaces, lit per vertex, take no shadow.
fn receives_shadow(scene: &Scene, material: &Material, lights: &[usize], debug: u32) -> bool {
    if super::plan::shadow_map_size(scene, debug).is_none()
        || material.shading == ShadingModel::Gouraud
    {
        return false;
    }
    match scene.shadow_light {
        Some(ShadowLight::Light(l)) => lights.contains(&l),
        Some(ShadowLight::Sun) => AirLight::of(scene) != AirLight::None,
        None => false,
    }
}

/// The opaque `draws` with every set of at least [`MIN_INSTANCES`] that
/// differ only in their transform (same mesh, material, maps, lights,
/// pipeline and shadow casting) made one instanced draw, in the order of their first members;
/// and the instance slots the batches take. The batches follow the scene
/// alone, not the view.
fn batch(scene: &Scene, geometry: &SceneGeometry, draws: Vec<Draw>) -> (Vec<Draw>, u32) {
    type BatchKey = (
        PipelineKey,
        MapSlots,
        Vec<usize>,
        usize,
        *const crate::mesh::Mesh,
        bool,
    );
    let key = |d: &Draw| -> BatchKey {
        (
            d.pipeline,
            d.maps,
            d.lights.clone(),
            scene.objects[d.object].material,
            Arc::as_ptr(&geometry.meshes[d.object]),
            // The shadow pass draws a batch whole.
            scene.objects[d.object].casts_shadows,
        )
    };
    let mut groups: Vec<Vec<Draw>> = Vec::new();
    let mut index: HashMap<BatchKey, usize> = HashMap::new();
    for d in draws {
        let slot = *index.entry(key(&d)).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[slot].push(d);
    }
    let mut slots = 0u32;
    let mut out = Vec::new();
    for group in groups {
        if group.len() < MIN_INSTANCES {
            out.extend(group);
            continue;
        }
        let members: Vec<usize> = group.iter().map(|d| d.object).collect();
        let mut first = group.into_iter().next().expect("a batch has members");
        first.pipeline.instanced = true;
        first.instances = Some(Instances {
            first: slots,
            visible: Vec::new(),
            members,
        });
        slots += first.objects().len() as u32;
        out.push(first);
    }
    (out, slots)
}

/// The view's frustum as planes in camera-relative space, for culling
/// objects by their bounding spheres.
struct Frustum {
    /// Unit normals pointing inwards, and offsets: a point p is inside
    /// plane (n, d) when n·p + d >= 0.
    planes: Vec<(glam::DVec3, f64)>,
}

impl Frustum {
    /// The frustum of `scene`'s camera at its output's aspect, from the
    /// clip-space bounds of Vulkan (-w <= x, y <= w, 0 <= z <= w) applied
    /// to the camera-relative view-projection (the rows' sums and
    /// differences). A bound with no direction (the far plane at infinity)
    /// culls nothing and is left out.
    fn of(scene: &Scene) -> Frustum {
        let aspect = scene.output.width as f32 / scene.output.height as f32;
        let m = scene.camera.view_projection_f64(aspect);
        let row = |r: usize| glam::DVec4::new(m.x_axis[r], m.y_axis[r], m.z_axis[r], m.w_axis[r]);
        let (x, y, z, w) = (row(0), row(1), row(2), row(3));
        let planes = [w + x, w - x, w + y, w - y, z, w - z]
            .into_iter()
            .filter_map(|p| {
                let length = p.truncate().length();
                (length > 1e-12 * p.w.abs().max(1.0) && length.is_finite())
                    .then(|| (p.truncate() / length, p.w / length))
            })
            .collect();
        Frustum { planes }
    }

    /// Whether a sphere at `centre` (camera-relative) of `radius` may be
    /// seen: false only when it lies wholly outside one plane.
    fn may_see(&self, centre: glam::DVec3, radius: f64) -> bool {
        self.planes
            .iter()
            .all(|(n, d)| n.dot(centre) + d >= -radius)
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
