//! A CPU reference renderer in double precision: the exact image of a scene
//! that the GPU's tessellated, single-precision frame approximates.
//!
//! Each pixel centre is ray-cast against the *analytic* surfaces (sphere,
//! finite plane, open cylinder), each in its own object space, and shaded
//! with exactly the Blinn-Phong formula of `glsl/include/lighting.glsl`,
//! with the same per-object light sets ([`Scene::lights_reaching`]) as the
//! GPU. `aerial sweep --reference cpu` measures every combination against
//! this image instead of against the best GPU setting.
//!
//! With `[atmosphere]` the sun is one more directional light on every
//! object, its colour the irradiance times the exact transmittance to the
//! shaded point ([`quadrature::sun_transmittance`], zero in the
//! planet's shadow), and with every order of scattering ([`Transport::Full`])
//! the sky lights the objects too, by the model the GPU uses
//! (`glsl/include/object_air.glsl`) but from the reference's own
//! irradiance: the horizontal irradiance of full light transport
//! ([`crate::atmosphere::transport::sky_irradiance`], Monte Carlo, at
//! three altitudes across each object's bounding sphere, interpolated)
//! spread over tilted surfaces by [`tilted_sky`]: isotropic with a
//! brighter horizon, plus the ground's reflection.
//!
//! The shadow-casting light ([`Scene::shadow_light`]: a point light, a
//! directional light, or the sun) is occluded exactly: its term at a
//! point counts only when a ray from there towards the light (up to a
//! point light's position) meets no opaque object
//! with `casts_shadows` (either face; [`shadows`]), where the GPU samples
//! a shadow map. Left out: every other light's shadows (as on the GPU),
//! shadows of transparent objects, the sun's penumbra (the sun is a
//! direction, so its shadows are hard); objects block none of each
//! other's sky; the sky
//! light has no specular part, is zero above the atmosphere (the light
//! the planet reflects into space is left out), and ignores the tilted
//! model's own error (docs/atmosphere.md measures it against full
//! transport). Every pixel
//! then goes through
//! the air as the atmosphere pass draws it, but from the f64 reference
//! ([`crate::atmosphere::quadrature`], at its image precision): the sky or
//! the lit ground sphere where no object is hit, plus the attenuated sun
//! disc; aerial perspective (transmittance and in-scattering over the
//! distance to the surface) where one is. By default the air's light is
//! every order of scattering ([`Transport::Full`]: the exact single
//! scattering plus the Monte Carlo estimate of
//! [`crate::atmosphere::transport`], seeded per pixel), whatever the
//! scene's `multiple_scattering`: the reference is the physics, and a
//! single-scattering render is measured against it like any other
//! approximation; [`Transport::Single`] gives the exact single-scattering
//! image. Rows are shared between the machine's cores.
//!
//! It lives in `render/` because it is a second renderer (scene in, linear
//! RGBA out, like the GPU renderer's HDR image); `report/` only compares
//! images and stays free of any way of making them.
//!
//! # What "exact" means here, and what it does not cover
//!
//! - The GPU rasterizes polygons whose vertices lie on the surface, so a
//!   curved silhouette is a polygon inside the analytic outline: pixels
//!   along the outline can be covered by one image and not the other.
//!   That difference is not noise in the reference: it *is* part of the
//!   tessellation error that a sweep reports, and it shrinks as the
//!   tessellation grows.
//! - Interior pixels differ by the flat facets (the GPU's surface point is
//!   up to r(1 - cos(pi/n)) inside the sphere, and its normals are
//!   interpolated) and by single-precision shading: again what a sweep
//!   measures.
//! - Front faces only: a hit whose geometric normal faces along the ray is
//!   skipped, as the GPU culls back faces. Hits nearer than the camera's
//!   near plane or beyond a finite far plane are skipped, as the GPU clips
//!   them.
//! - Shapes without a closed-form intersection here (torus, flag) and
//!   material features the formula does not cover (textures and normal
//!   maps, opacity below 1, two-sided faces, Gouraud and toon shading) are
//!   refused with an error naming the object, its material and the
//!   feature, never approximated. A map whose `MapKindInfo::reference`
//!   says how (a specular map) is applied, on planes, sampled at the
//!   nearest texel (`texture_filter = "nearest"`).

use glam::{DMat3, DMat4, DQuat, DVec3};

use super::Pixels;
use crate::atmosphere::transport::{
    multiple_radiance, sky_irradiance, TransportSettings, UNLIMITED,
};
use crate::atmosphere::{quadrature, Atmosphere, Sun};
use crate::scene::material_maps::{ColorSpace, MapKindInfo, MapSource, ReferenceUse};
use crate::scene::{
    placeholder_texels, Light, Material, Scene, ShadingModel, ShadowLight, Shape, Texture,
    TextureFilter, Transform, MAX_OUTPUT_SIZE, PLACEHOLDER_TEXTURE,
};
use shadows::{Caster, Occluders};

/// Why a scene has no CPU reference.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CpuRenderError {
    #[error("object '{object}': the {shape} shape has no CPU reference (supported: sphere, plane, cylinder)")]
    UnsupportedShape { object: String, shape: &'static str },
    #[error("object '{object}', material '{material}': {feature} has no CPU reference (supported: opaque, untextured phong materials)")]
    UnsupportedMaterial {
        object: String,
        material: String,
        feature: String,
    },
    #[error("object '{object}': material index {index} is out of range (the scene has {count} materials)")]
    NoMaterial {
        object: String,
        index: usize,
        count: usize,
    },
    #[error("output size {width}x{height}: each side must be in 1..={max}", max = MAX_OUTPUT_SIZE)]
    Size { width: u32, height: u32 },
}

/// Renders the exact image of `scene`: linear RGBA, row 0 at the top,
/// alpha 1 where a surface is hit and (0, 0, 0, 0) elsewhere.
///
/// # Errors
///
/// [`CpuRenderError`] naming the object (and material) whose shape or
/// material has no CPU reference.
pub fn render_on_cpu(scene: &Scene) -> Result<Pixels<f32>, CpuRenderError> {
    Ok(CpuScene::new(scene)?.render())
}

/// [`render_on_cpu`] with the air's light transport `transport` instead
/// of every order at [`IMAGE_PATHS`].
pub fn render_on_cpu_with(
    scene: &Scene,
    transport: Transport,
) -> Result<Pixels<f32>, CpuRenderError> {
    let mut reference = CpuScene::new(scene)?;
    reference.transport = transport;
    Ok(reference.render())
}

/// Everything [`render_on_cpu`] reads from a scene, in double precision.
///
/// Two scenes with equal `CpuScene`s have identical reference images,
/// so a sweep can use it as a cache key: knobs that change only how the GPU
/// renders (HDR format, tessellation apart from its effect on the light
/// sets) leave it unchanged.
#[derive(Clone, Debug, PartialEq)]
pub struct CpuScene {
    width: u32,
    height: u32,
    eye: DVec3,
    /// Unit camera basis, as `Mat4::look_at_rh` builds it.
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    tan_half_fov: f64,
    near: f64,
    far: Option<f64>,
    ambient: DVec3,
    objects: Vec<CpuObject>,
    /// With `[atmosphere]`: the sun and the atmosphere, only (the pass's
    /// quality settings, `multiple_scattering` among them, do not change
    /// the exact image, so sweeping them reuses one reference).
    sky: Option<(Sun, Atmosphere)>,
    /// How much of the light transport the air's radiance includes.
    transport: Transport,
    /// Whether the sun is the shadow-casting light.
    sun_shadowed: bool,
    /// What occludes the shadow-casting light; empty without one.
    casters: Vec<Caster>,
}

/// How much light transport the reference computes in the air.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Single scattering alone: what the atmosphere pass draws with
    /// `multiple_scattering = false`, exact to the quadrature's tolerance.
    Single,
    /// Every order ([`crate::atmosphere::transport`]): the exact single
    /// scattering plus a Monte Carlo estimate of the higher orders from
    /// `paths` paths per pixel and channel, seeded by the pixel, so the
    /// same scene gives the same image.
    Full { paths: u32 },
}

/// Paths per pixel and channel of the default reference's higher orders.
/// Measured on Earth's sky, one path's estimate spreads by about 1.5 to 3
/// times the higher orders' radiance, so 1024 paths leave a standard error
/// of about 5 to 10 % of the higher orders, 1 to 3 % of a pixel: noise
/// that a sweep's RMSE against this reference includes as a floor.
pub const IMAGE_PATHS: u32 = 1024;

/// Paths per channel of each horizontal sky irradiance the objects' sky
/// light is interpolated from (three per object, computed once per
/// render, the same random streams at each altitude): about 1 % standard
/// error in red, 0.5 % in blue, on Earth's sky under a sun 30° up.
pub const SKY_LIGHT_PATHS: u32 = 1 << 15;

/// One object, ready for ray casting.
#[derive(Clone, Debug, PartialEq)]
struct CpuObject {
    surface: Surface,
    /// World to object space.
    world_to_object: DMat4,
    /// Inverse transpose of the object-to-world 3x3: carries object-space
    /// normals to world space.
    normal_matrix: DMat3,
    ka: DVec3,
    kd: DVec3,
    ks: DVec3,
    /// A map multiplying `ks` (`ReferenceUse::ScalesSpecular`).
    specular_map: Option<ReferenceMap>,
    shininess: f64,
    /// The lights that reach this object on the GPU, in scene order (the
    /// atmosphere's sun is not one of them: it is lit per point).
    lights: Vec<CpuLight>,
    /// The object's bounding sphere (world centre, radius), across which
    /// the sky light's horizontal irradiance is sampled.
    bounds: (DVec3, f64),
}

/// The horizontal sky irradiance (full light transport, the sun's direct
/// light excluded) at three altitudes of one object, bottom to top of its
/// bounding sphere, at the cosine of the sun's zenith angle over its
/// centre (across an object a few kilometres wide it changes by less than
/// 1e-3).
#[derive(Clone, Copy, Debug, PartialEq)]
struct HorizontalSky {
    altitudes: [f64; 3],
    irradiance: [DVec3; 3],
}

impl HorizontalSky {
    /// Quadratic through the three samples, at `h` clamped to them.
    fn at(&self, h: f64) -> DVec3 {
        let [h0, h1, h2] = self.altitudes;
        let [e0, e1, e2] = self.irradiance;
        if h2 - h0 <= 0.0 {
            return e1;
        }
        let h = h.clamp(h0, h2);
        let l0 = (h - h1) * (h - h2) / ((h0 - h1) * (h0 - h2));
        let l1 = (h - h0) * (h - h2) / ((h1 - h0) * (h1 - h2));
        let l2 = (h - h0) * (h - h1) / ((h2 - h0) * (h2 - h1));
        e0 * l0 + e1 * l1 + e2 * l2
    }
}

/// The atmosphere's light on the objects of one render.
struct ObjectAir<'a> {
    sun: &'a Sun,
    atmosphere: &'a Atmosphere,
    /// Per object, with every order of scattering; `None` for single
    /// scattering (no sky light, as the GPU with `multiple_scattering =
    /// false`).
    skies: Option<Vec<HorizontalSky>>,
}

impl ObjectAir<'_> {
    /// The sun's colour at `p` (world space) and the sky's irradiance on a
    /// surface of normal `n` there, for object `object`.
    fn at(&self, object: usize, p: DVec3, n: DVec3) -> (DVec3, DVec3) {
        let a = self.atmosphere;
        let rel = p - a.center;
        let transmittance = quadrature::sun_transmittance(a, rel, self.sun.direction);
        let sun = self.sun.irradiance * transmittance;
        let Some(skies) = &self.skies else {
            return (sun, DVec3::ZERO);
        };
        // Above the air (at the shaders' effective top) no sky light: the
        // light the planet reflects into space is left out.
        if rel.length() > a.effective_top_radius() {
            return (sun, DVec3::ZERO);
        }
        let up = rel.normalize();
        let mu_s = up.dot(self.sun.direction);
        let horizontal = skies[object].at(a.altitude(rel).max(0.0));
        (sun, tilted_sky(a, up, n, mu_s, sun, horizontal))
    }
}

/// The sky's irradiance on a surface of normal `n` where the local up is
/// `up`, the sun at cosine `mu_s` from the zenith with colour `sun` there
/// and the sky's horizontal irradiance `horizontal`: the model of
/// `glsl/include/object_air.glsl` (isotropic with Reindl's horizon
/// brightening, plus the ground's reflection), in f64.
fn tilted_sky(
    atmosphere: &Atmosphere,
    up: DVec3,
    n: DVec3,
    mu_s: f64,
    sun: DVec3,
    horizontal: DVec3,
) -> DVec3 {
    let sun_horizontal = sun * mu_s.max(0.0);
    let global = sun_horizontal + horizontal;
    let f = (sun_horizontal / global.max(DVec3::splat(1e-30))).powf(0.5);
    let c = n.dot(up);
    let half_tilt = (0.5 - 0.5 * c).max(0.0).sqrt();
    horizontal * (0.5 + 0.5 * c) * (DVec3::ONE + f * half_tilt.powi(3))
        + atmosphere.ground_albedo * global * (0.5 - 0.5 * c)
}

/// [`HorizontalSky`] of an object bounded by `bounds`, by
/// [`sky_irradiance`] with `paths` paths per channel, seeded by `seed`.
fn horizontal_sky(
    atmosphere: &Atmosphere,
    sun: &Sun,
    bounds: (DVec3, f64),
    paths: u32,
    seed: u64,
) -> HorizontalSky {
    let (centre, radius) = bounds;
    let rel = centre - atmosphere.center;
    let up = rel.normalize();
    let h = atmosphere.altitude(rel);
    let altitudes = [(h - radius).max(0.0), h.max(0.0), (h + radius).max(0.0)];
    let irradiance = altitudes.map(|alt| {
        let point = up * (atmosphere.bottom_radius + alt);
        let settings = TransportSettings {
            paths,
            seed,
            max_order: UNLIMITED,
        };
        sky_irradiance(atmosphere, sun, point, up, settings).0
    });
    HorizontalSky {
        altitudes,
        irradiance,
    }
}

/// The analytic surfaces the reference can intersect, in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface {
    /// `|p| = radius`.
    Sphere { radius: f64 },
    /// `y = 0`, `|x| <= width / 2`, `|z| <= depth / 2`, front face `+Y`.
    Plane { width: f64, depth: f64 },
    /// `x^2 + z^2 = radius^2`, `|y| <= height / 2`, open, front face outward.
    Cylinder { radius: f64, height: f64 },
}

/// A light as the shader sees it (`GpuLight`).
#[derive(Clone, Copy, Debug, PartialEq)]
enum CpuLight {
    Point {
        position: DVec3,
        color: DVec3,
        /// (constant, linear, quadratic).
        attenuation: DVec3,
        /// Subtracted from the attenuation (`Light::window`).
        window: f64,
        /// Whether it is the shadow-casting light.
        shadowed: bool,
    },
    Directional {
        /// Unit vector towards the light (the negated travel direction).
        to_light: DVec3,
        color: DVec3,
        /// Whether it is the shadow-casting light.
        shadowed: bool,
    },
}

/// A front-facing ray hit in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter: the point is `origin + t * direction`.
    pub t: f64,
    /// Object-space outward normal (not normalized).
    pub normal: DVec3,
}

/// The visible surface along a camera ray, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
struct WorldHit {
    t: f64,
    /// Index into `CpuScene::objects` (and `Scene::objects`).
    object: usize,
    point: DVec3,
    /// Unit outward normal.
    normal: DVec3,
}

/// The maps of `material` the reference applies, on `surface` sampled
/// with `filter`: the one that scales `ks`, if any. Errors with the phrase
/// for the first map (in table order) it cannot apply.
fn reference_maps(
    material: &Material,
    surface: &Surface,
    filter: TextureFilter,
) -> Result<Option<ReferenceMap>, String> {
    let mut specular = None;
    for (kind, source) in material.maps.iter() {
        let info = kind.info();
        match info.reference {
            ReferenceUse::Unsupported(phrase) => return Err(phrase.to_string()),
            ReferenceUse::ScalesSpecular => {
                if surface.uv(DVec3::ZERO).is_none() {
                    return Err(format!(
                        "a {} on a {} (the reference has texture coordinates for planes only)",
                        info.field,
                        surface.name()
                    ));
                }
                if filter != TextureFilter::Nearest {
                    return Err(format!(
                        "a {} filtered with texture_filter = \"{}\" (the reference samples \
                         the nearest texel: use \"nearest\")",
                        info.field,
                        format!("{filter:?}").to_lowercase()
                    ));
                }
                specular = Some(ReferenceMap::load(info, source)?);
            }
        }
    }
    Ok(specular)
}

/// A map's texels as the shader reads them (decoded from sRGB for a
/// colour map), top row first.
#[derive(Clone, Debug, PartialEq)]
struct ReferenceMap {
    width: u32,
    height: u32,
    texels: Vec<DVec3>,
}

impl ReferenceMap {
    fn load(info: &MapKindInfo, source: &MapSource) -> Result<ReferenceMap, String> {
        let (width, height, bytes) = match &source.texture {
            Texture::File(path) => {
                let image = crate::image_io::decode(path)
                    .map_err(|reason| format!("{}: {reason}", path.display()))?
                    .to_rgba8();
                (image.width(), image.height(), image.into_raw())
            }
            Texture::Placeholder => {
                let (side, _) = PLACEHOLDER_TEXTURE;
                (side, side, placeholder_texels())
            }
        };
        let decode = |c: u8| {
            let c = f64::from(c) / 255.0;
            match info.color_space {
                ColorSpace::Linear => c,
                ColorSpace::Srgb if c <= 0.04045 => c / 12.92,
                ColorSpace::Srgb => ((c + 0.055) / 1.055).powf(2.4),
            }
        };
        let texels = bytes
            .chunks_exact(4)
            .map(|t| DVec3::new(decode(t[0]), decode(t[1]), decode(t[2])))
            .collect();
        Ok(ReferenceMap {
            width,
            height,
            texels,
        })
    }

    /// The texel nearest `(u, v)` (`v` up the image, as the shaders flip
    /// it), repeating outside `[0, 1)` as the sampler does.
    fn nearest(&self, u: f64, v: f64) -> DVec3 {
        let x = (u * f64::from(self.width)).floor() as i64;
        let y = ((1.0 - v) * f64::from(self.height)).floor() as i64;
        let x = x.rem_euclid(i64::from(self.width)) as usize;
        let y = y.rem_euclid(i64::from(self.height)) as usize;
        self.texels[y * self.width as usize + x]
    }
}

impl Surface {
    /// The texture coordinates of the object-space point `p` on the
    /// surface, as the tessellated mesh has them (`mesh::PlaneSurface`:
    /// `u` along `+X`, `v` along `-Z`); `None` for surfaces the reference
    /// has none for.
    fn uv(&self, p: DVec3) -> Option<(f64, f64)> {
        match *self {
            Surface::Plane { width, depth } => Some((p.x / width + 0.5, 0.5 - p.z / depth)),
            Surface::Sphere { .. } | Surface::Cylinder { .. } => None,
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Surface::Sphere { .. } => "sphere",
            Surface::Plane { .. } => "plane",
            Surface::Cylinder { .. } => "cylinder",
        }
    }

    fn of(shape: &Shape) -> Option<Surface> {
        let f = f64::from;
        match *shape {
            Shape::Sphere { radius } => Some(Surface::Sphere { radius: f(radius) }),
            Shape::Plane { width, depth } => Some(Surface::Plane {
                width: f(width),
                depth: f(depth),
            }),
            Shape::Cylinder { radius, height } => Some(Surface::Cylinder {
                radius: f(radius),
                height: f(height),
            }),
            Shape::Torus { .. } | Shape::Flag { .. } | Shape::Mesh { .. } => None,
        }
    }

    /// The nearest front-facing hit of the ray `origin + t * direction`
    /// with `t` in `[t_min, t_max]`, in object space. `direction` need not
    /// be a unit vector (a scaled object's object-space ray is not), so
    /// `t` stays the world-space ray parameter.
    ///
    /// A hit is front-facing when the outward normal points against the
    /// ray. The test is done in object space because it equals the world
    /// one: with `M` the object-to-world matrix, `(M^-T n) . (M d) = n . d`.
    pub fn intersect(
        &self,
        origin: DVec3,
        direction: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<Hit> {
        self.crossings(origin, direction)
            .into_iter()
            .flatten()
            .find(|hit| hit.t >= t_min && hit.t <= t_max && hit.normal.dot(direction) < 0.0)
    }

    /// Whether the ray `origin + t * direction` meets the surface, by
    /// either face, at a `t` in `(t_min, t_max]`: an occluder blocks light
    /// whichever way it faces.
    pub fn blocks(&self, origin: DVec3, direction: DVec3, t_min: f64, t_max: f64) -> bool {
        self.crossings(origin, direction)
            .into_iter()
            .flatten()
            .any(|hit| hit.t > t_min && hit.t <= t_max)
    }

    /// Every point where the line `o + t d` meets the surface, either
    /// face, smaller `t` first, with the outward normal there.
    fn crossings(&self, o: DVec3, d: DVec3) -> [Option<Hit>; 2] {
        let at = |t: f64, normal: DVec3| Some(Hit { t, normal });
        match *self {
            Surface::Sphere { radius } => {
                let Some(roots) = sphere_roots(o, d, radius) else {
                    return [None; 2];
                };
                // From outside the near root is the front face and the far
                // one the back face; from inside both face away.
                roots.map(|t| at(t, o + d * t))
            }
            Surface::Plane { width, depth } => {
                if d.y == 0.0 {
                    return [None; 2];
                }
                let t = -o.y / d.y;
                let p = o + d * t;
                if p.x.abs() > width * 0.5 || p.z.abs() > depth * 0.5 {
                    return [None; 2];
                }
                [at(t, DVec3::Y), None]
            }
            Surface::Cylinder { radius, height } => {
                let flat = DVec3::new(1.0, 0.0, 1.0);
                let Some(roots) = sphere_roots(o * flat, d * flat, radius) else {
                    return [None; 2];
                };
                // The cylinder is open: a ray can pass the near wall above
                // its rim and meet the far wall from inside, which is a back
                // face and culled, exactly as on the GPU.
                roots.map(|t| {
                    let p = o + d * t;
                    (p.y.abs() <= height * 0.5).then_some(Hit {
                        t,
                        normal: DVec3::new(p.x, 0.0, p.z),
                    })
                })
            }
        }
    }
}

/// Where the ray `o + t d` meets the sphere `|p| = radius` (a circle when
/// both vectors have `y = 0`), smaller `t` first; `None` on a miss or when
/// `d` is zero (a ray along a cylinder's axis).
///
/// Solved from the point of the ray closest to the centre rather than by
/// the textbook `|o|^2 - r^2`: for a small sphere far away that difference
/// of nearly equal numbers keeps few digits (1e8 - 1e-6 loses all but two),
/// while the closest point is computed to within an ulp of the distance.
fn sphere_roots(o: DVec3, d: DVec3, radius: f64) -> Option<[f64; 2]> {
    let a = d.length_squared();
    if a == 0.0 {
        return None;
    }
    let t_mid = -o.dot(d) / a;
    let closest = o + d * t_mid;
    let half_chord_squared = (radius * radius - closest.length_squared()) / a;
    if half_chord_squared < 0.0 {
        return None;
    }
    let h = half_chord_squared.sqrt();
    Some([t_mid - h, t_mid + h])
}

/// The object-to-world matrix of `transform` in f64.
fn model_matrix(transform: &Transform) -> DMat4 {
    let axis = transform.rotate_axis.as_dvec3();
    // A zero axis means no rotation, as in `Transform::rotation`.
    let rotation = match axis.try_normalize() {
        Some(axis) => {
            DQuat::from_axis_angle(axis, f64::from(transform.rotate_degrees).to_radians())
        }
        None => DQuat::IDENTITY,
    };
    DMat4::from_scale_rotation_translation(
        transform.scale.as_dvec3(),
        rotation,
        transform.translate,
    )
}

impl CpuScene {
    /// Checks that every object can be ray-cast and shaded exactly, and
    /// gathers what the reference needs.
    ///
    /// # Errors
    ///
    /// The first object (in scene order) with an unsupported shape or
    /// material feature, or a material index out of range.
    pub fn new(scene: &Scene) -> Result<CpuScene, CpuRenderError> {
        let (width, height) = (scene.output.width, scene.output.height);
        if !(1..=MAX_OUTPUT_SIZE).contains(&width) || !(1..=MAX_OUTPUT_SIZE).contains(&height) {
            return Err(CpuRenderError::Size { width, height });
        }
        let mut objects = Vec::with_capacity(scene.objects.len());
        for (index, object) in scene.objects.iter().enumerate() {
            let material =
                scene
                    .materials
                    .get(object.material)
                    .ok_or_else(|| CpuRenderError::NoMaterial {
                        object: object.name.clone(),
                        index: object.material,
                        count: scene.materials.len(),
                    })?;
            let surface =
                Surface::of(&object.shape).ok_or_else(|| CpuRenderError::UnsupportedShape {
                    object: object.name.clone(),
                    shape: object.shape.kind_name(),
                })?;
            let unsupported = |feature: String| CpuRenderError::UnsupportedMaterial {
                object: object.name.clone(),
                material: material.name.clone(),
                feature,
            };
            let specular_map = reference_maps(material, &surface, scene.output.texture_filter)
                .map_err(unsupported)?;
            let feature = if material.is_transparent() {
                Some(format!("transparency (opacity {})", material.opacity))
            } else if object.is_two_sided(material) {
                // The reference culls back faces, as one-sided draws do.
                Some("two-sided faces (two_sided)".to_string())
            } else {
                match material.shading {
                    ShadingModel::Phong => None,
                    ShadingModel::Gouraud => Some("gouraud shading".to_string()),
                    ShadingModel::Toon => Some("toon shading".to_string()),
                }
            };
            if let Some(feature) = feature {
                return Err(unsupported(feature));
            }
            let model = model_matrix(&object.transform);
            let lights = scene
                .lights_reaching(index)
                .into_iter()
                .filter_map(|i| scene.lights.get(i).map(|light| (i, light)))
                .map(|(i, light)| match *light {
                    Light::Point {
                        position,
                        color,
                        attenuation,
                    } => CpuLight::Point {
                        position,
                        color: color.as_dvec3(),
                        attenuation: attenuation.as_dvec3(),
                        window: f64::from(light.window(scene.light_cutoff)),
                        shadowed: scene.shadow_light == Some(ShadowLight::Light(i)),
                    },
                    // The scene holds a unit travel direction; the shader
                    // is given its negation and normalizes it again, so the
                    // f64 normalization matches.
                    Light::Directional { direction, color } => CpuLight::Directional {
                        to_light: (-direction.as_dvec3()).normalize_or_zero(),
                        color: color.as_dvec3(),
                        shadowed: scene.shadow_light == Some(ShadowLight::Light(i)),
                    },
                })
                .collect();
            let bounds = scene
                .object_bounds(index)
                .map_or((model.transform_point3(DVec3::ZERO), 0.0), |(c, r)| {
                    (c, f64::from(r))
                });
            objects.push(CpuObject {
                surface,
                world_to_object: model.inverse(),
                normal_matrix: DMat3::from_mat4(model).inverse().transpose(),
                ka: material.ka.as_dvec3(),
                kd: material.kd.as_dvec3(),
                ks: material.ks.as_dvec3(),
                specular_map,
                shininess: f64::from(material.shininess),
                lights,
                bounds,
            });
        }
        let camera = &scene.camera;
        let eye = camera.eye;
        // The basis of Mat4::look_at_rh: forward f, right s = f x up,
        // true up u = s x f. The scene guarantees eye != look_at and an up
        // not parallel to the view direction.
        let forward = (camera.look_at - eye).normalize_or_zero();
        let right = forward.cross(camera.up.as_dvec3()).normalize_or_zero();
        let up = right.cross(forward);
        Ok(CpuScene {
            width,
            height,
            eye,
            right,
            up,
            forward,
            tan_half_fov: (f64::from(camera.fov_y_degrees).to_radians() * 0.5).tan(),
            near: f64::from(camera.near),
            far: camera.far.map(f64::from),
            ambient: scene.ambient.as_dvec3(),
            objects,
            sky: scene
                .sky
                .as_ref()
                .map(|sky| (sky.sun.clone(), sky.atmosphere.clone())),
            transport: Transport::Full { paths: IMAGE_PATHS },
            sun_shadowed: scene.sky.is_some() && scene.shadow_light == Some(ShadowLight::Sun),
            casters: match scene.shadow_light {
                Some(_) => shadows::casters(scene),
                None => Vec::new(),
            },
        })
    }

    /// The unit world-space ray direction through the centre of pixel
    /// `(x, y)`, row 0 at the top. The GPU's projection maps view-space
    /// `+Y` to the top row (its `y_c = -f y_v` and Vulkan's downward NDC
    /// `y`), with `aspect = width / height`.
    pub fn ray(&self, x: u32, y: u32) -> DVec3 {
        let aspect = f64::from(self.width) / f64::from(self.height);
        let ndc_x = (f64::from(x) + 0.5) / f64::from(self.width) * 2.0 - 1.0;
        let ndc_y = (f64::from(y) + 0.5) / f64::from(self.height) * 2.0 - 1.0;
        let sx = ndc_x * self.tan_half_fov * aspect;
        let sy = -ndc_y * self.tan_half_fov;
        (self.right * sx + self.up * sy + self.forward).normalize()
    }

    /// The whole image, rows split between the machine's cores (the
    /// atmosphere's nested quadrature costs milliseconds a pixel).
    pub fn render(&self) -> Pixels<f32> {
        let (w, h) = (self.width as usize, self.height as usize);
        let air = self.sky.as_ref().map(|(sun, atmosphere)| ObjectAir {
            sun,
            atmosphere,
            skies: match self.transport {
                Transport::Single => None,
                Transport::Full { .. } => Some(
                    self.objects
                        .iter()
                        .enumerate()
                        .map(|(i, o)| {
                            horizontal_sky(atmosphere, sun, o.bounds, SKY_LIGHT_PATHS, i as u64)
                        })
                        .collect(),
                ),
            },
        });
        let air = air.as_ref();
        let occluders = Occluders::new(self.casters.clone());
        let occluders = &occluders;
        let mut data = vec![0f32; w * h * 4];
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .clamp(1, h.max(1));
        // Interleaved rows: the sky's cost varies with the view direction,
        // so each thread gets rows from the whole image.
        let mut rows: Vec<Vec<(usize, &mut [f32])>> = (0..threads).map(|_| Vec::new()).collect();
        for (y, row) in data.chunks_mut(w * 4).enumerate() {
            rows[y % threads].push((y, row));
        }
        std::thread::scope(|s| {
            for part in rows {
                s.spawn(move || {
                    for (y, row) in part {
                        for (x, pixel) in row.chunks_exact_mut(4).enumerate() {
                            pixel.copy_from_slice(&self.pixel(x as u32, y as u32, air, occluders));
                        }
                    }
                });
            }
        });
        Pixels {
            width: self.width,
            height: self.height,
            data,
        }
    }

    /// RGBA of pixel (x, y): alpha 1 where a surface is hit and, with an
    /// atmosphere, everywhere (the atmosphere pass writes every pixel).
    fn pixel(&self, x: u32, y: u32, air: Option<&ObjectAir>, occluders: &Occluders) -> [f32; 4] {
        let dir = self.ray(x, y);
        let surface = self.shade(dir, air, occluders);
        let colour = match &self.sky {
            None => surface.map(|(_, c)| c),
            Some((sun, atmosphere)) => {
                // Each pixel its own random streams: the same scene gives
                // the same image.
                let higher_orders = match self.transport {
                    Transport::Single => None,
                    Transport::Full { paths } => Some(TransportSettings {
                        paths,
                        seed: u64::from(y) << 32 | u64::from(x),
                        max_order: UNLIMITED,
                    }),
                };
                let air = Air {
                    sun,
                    atmosphere,
                    higher_orders,
                };
                Some(air.radiance(self.eye, dir, surface))
            }
        };
        match colour {
            Some(c) => [c.x as f32, c.y as f32, c.z as f32, 1.0],
            None => [0.0; 4],
        }
    }

    /// The distance to and the radiance of the surface along the unit ray
    /// `dir` from the eye, or `None` when it hits nothing.
    /// `air`: the atmosphere's light on the objects, with `[atmosphere]`;
    /// `occluders`: what blocks the shadow-casting light.
    fn shade(
        &self,
        dir: DVec3,
        air: Option<&ObjectAir>,
        occluders: &Occluders,
    ) -> Option<(f64, DVec3)> {
        let hit = self.trace(dir)?;
        let object = &self.objects[hit.object];
        let at = Shading {
            hit,
            v: -dir,
            ks: object.ks_at(hit.point),
            occluders,
        };
        let mut colour = object.ka * self.ambient;
        for light in &object.lights {
            colour += object.lit(light, &at);
        }
        if let Some(air) = air {
            // The sun after the object's lights, then the sky, in the
            // shaders' order.
            let (sun, sky) = air.at(hit.object, hit.point, hit.normal);
            let light = CpuLight::Directional {
                to_light: air.sun.direction,
                color: sun,
                shadowed: self.sun_shadowed,
            };
            colour += object.lit(&light, &at);
            colour += object.kd * sky;
        }
        Some((hit.t, colour))
    }

    /// The nearest visible surface along the unit ray `dir` from the eye.
    fn trace(&self, dir: DVec3) -> Option<WorldHit> {
        // The GPU clips at view depths `near` and `far`; along this ray the
        // depth is t * cos, cos the angle to the view axis (> 0 for any
        // pixel of a field of view under 180 degrees).
        let cos = dir.dot(self.forward);
        let t_min = self.near / cos;
        let t_max = self.far.map_or(f64::INFINITY, |far| far / cos);
        let mut nearest: Option<(f64, usize, DVec3)> = None;
        for (index, object) in self.objects.iter().enumerate() {
            let o = object.world_to_object.transform_point3(self.eye);
            let d = object.world_to_object.transform_vector3(dir);
            let limit = nearest.map_or(t_max, |(t, _, _)| t);
            if let Some(hit) = object.surface.intersect(o, d, t_min, limit) {
                // Ties keep the earlier object, as the GPU's GREATER depth
                // test keeps the first fragment drawn at a depth.
                if nearest.is_none_or(|(t, _, _)| hit.t < t) {
                    nearest = Some((hit.t, index, hit.normal));
                }
            }
        }
        let (t, object, normal) = nearest?;
        Some(WorldHit {
            t,
            object,
            point: self.eye + dir * t,
            normal: (self.objects[object].normal_matrix * normal).normalize(),
        })
    }
}

/// The air a pixel's ray goes through.
struct Air<'a> {
    sun: &'a Sun,
    atmosphere: &'a Atmosphere,
    /// With every order: how the higher orders are estimated.
    higher_orders: Option<TransportSettings>,
}

impl Air<'_> {
    /// What the atmosphere pass draws along the unit ray `dir` from `eye`
    /// (world space), from the f64 reference
    /// ([`crate::atmosphere::quadrature`]): a surface at distance t with
    /// radiance L is seen as L·T + in-scattered light over the t metres
    /// in front of it, unless the ground sphere is nearer; otherwise the
    /// sky or the lit ground, plus the sun's disc (attenuated) where the
    /// ray misses the ground; with every order, plus the higher orders'
    /// light ([`crate::atmosphere::transport::multiple_radiance`]).
    ///
    /// In front of a surface the higher orders are those along the whole
    /// ray less those from beyond the surface, attenuated: the in-scattered
    /// light over the t metres, exactly when the surface blocks none of the
    /// higher orders' paths through the air (objects are lit by the sun
    /// alone, and do not shade the air around them).
    fn radiance(&self, eye: DVec3, dir: DVec3, surface: Option<(f64, DVec3)>) -> DVec3 {
        let origin = eye - self.atmosphere.center;
        let single = air(self.sun, self.atmosphere, eye, dir, surface);
        let Some(settings) = self.higher_orders else {
            return single;
        };
        let higher =
            |from: DVec3| multiple_radiance(self.atmosphere, self.sun, from, dir, settings).0;
        let segment = quadrature::atmosphere_segment(self.atmosphere, origin, dir);
        let ground = match segment {
            Some((_, end, true)) => Some(end),
            _ => None,
        };
        match surface {
            Some((t, _)) if ground.is_none_or(|g| t < g) => {
                let behind = origin + t * dir;
                let view = match segment {
                    Some((start, _, _)) if t > start => {
                        self.atmosphere.transmittance(quadrature::densities_between(
                            self.atmosphere,
                            origin + start * dir,
                            behind,
                        ))
                    }
                    _ => DVec3::ONE,
                };
                single + higher(origin) - view * higher(behind)
            }
            _ => single + higher(origin),
        }
    }
}

/// [`Air::radiance`]'s single scattering.
fn air(
    sun: &Sun,
    atmosphere: &Atmosphere,
    eye: DVec3,
    dir: DVec3,
    surface: Option<(f64, DVec3)>,
) -> DVec3 {
    let origin = eye - atmosphere.center;
    let segment = quadrature::atmosphere_segment(atmosphere, origin, dir);
    let ground = match segment {
        Some((_, end, true)) => Some(end),
        _ => None,
    };
    if let Some((t, radiance)) = surface {
        if ground.is_none_or(|g| t < g) {
            let (inscattered, view) = quadrature::aerial_perspective_with(
                atmosphere,
                sun,
                origin,
                dir,
                t,
                quadrature::IMAGE,
            );
            return radiance * view + inscattered;
        }
    }
    let mut colour = quadrature::radiance_with(atmosphere, sun, origin, dir, quadrature::IMAGE);
    if sun.disc && ground.is_none() && dir.dot(sun.direction) >= sun.angular_radius.cos() {
        let view = match segment {
            Some((start, end, _)) => atmosphere.transmittance(quadrature::densities_between(
                atmosphere,
                origin + start * dir,
                origin + end * dir,
            )),
            None => DVec3::ONE,
        };
        let disc = 1.0 / (std::f64::consts::PI * sun.angular_radius * sun.angular_radius);
        colour += sun.irradiance * disc * view;
    }
    colour
}

/// What lighting one visible point needs.
struct Shading<'a> {
    hit: WorldHit,
    /// Unit vector towards the eye.
    v: DVec3,
    /// The specular reflectance there ([`CpuObject::ks_at`]).
    ks: DVec3,
    occluders: &'a Occluders,
}

impl CpuObject {
    /// One light's term of `blinn_phong` in `lighting.glsl` (which sums
    /// them after `ka La`), times the light's visibility at the point
    /// when it is the shadow-casting light (tested only where the term
    /// is not zero).
    fn lit(&self, light: &CpuLight, at: &Shading) -> DVec3 {
        let WorldHit {
            object,
            point,
            normal,
            ..
        } = at.hit;
        let term = self.light(light, point, normal, at.v, at.ks);
        match *light {
            CpuLight::Directional {
                to_light,
                shadowed: true,
                ..
            } if term != DVec3::ZERO => term * at.occluders.visibility(object, point, to_light),
            CpuLight::Point {
                position,
                shadowed: true,
                ..
            } if term != DVec3::ZERO => term * at.occluders.visibility_to(object, point, position),
            _ => term,
        }
    }

    /// The specular reflectance at the world point `p`: `ks` times the
    /// specular map's nearest texel there, if the object has one.
    fn ks_at(&self, p: DVec3) -> DVec3 {
        let uv = self.surface.uv(self.world_to_object.transform_point3(p));
        match (&self.specular_map, uv) {
            (Some(map), Some((u, v))) => self.ks * map.nearest(u, v),
            _ => self.ks,
        }
    }

    /// One light's Blinn-Phong term: for a light in front of the surface
    /// (`cos > 0`), `Le att (kd cos + ks max(N.H, 0)^shininess)`.
    fn light(&self, light: &CpuLight, p: DVec3, n: DVec3, v: DVec3, ks: DVec3) -> DVec3 {
        let (l, radiance) = match *light {
            CpuLight::Point {
                position,
                color,
                attenuation: a,
                window,
                ..
            } => {
                let to_light = position - p;
                let d = to_light.length();
                // The shader's fallbacks, for a light exactly on the
                // surface: an arbitrary direction and a floor under the
                // attenuation denominator.
                let l = if d > 0.0 { to_light / d } else { DVec3::Z };
                let att = (1.0 / (a.x + a.y * d + a.z * d * d).max(1e-6) - window).max(0.0);
                (l, color * att)
            }
            CpuLight::Directional {
                to_light, color, ..
            } => (to_light, color),
        };
        let cos_theta = n.dot(l);
        if cos_theta > 0.0 {
            let h = (l + v).normalize();
            let specular = n.dot(h).max(0.0).powf(self.shininess);
            return radiance * (self.kd * cos_theta + ks * specular);
        }
        DVec3::ZERO
    }
}

mod shadows;

#[cfg(test)]
mod shadow_tests;
#[cfg(test)]
mod tests;
