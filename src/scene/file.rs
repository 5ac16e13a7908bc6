//! The TOML scene format: serde mirror types that only describe the syntax,
//! and the validation that turns them into a [`Description`]: the scene,
//! with each OBJ model named and its options checked but not yet read.
//! `models.rs` reads the models afterwards, so parsing never touches a
//! model file.
//!
//! Parsing and validation are separate on purpose: serde (with
//! `deny_unknown_fields` everywhere) rejects unknown fields and wrong types
//! with the `toml` crate's line/column message, and the validation pass then
//! checks values with the full field path at hand, so every semantic error
//! names exactly one field.
//!
//! Shapes and lights are flat tables with a `type` key rather than serde
//! tagged enums, because serde buffers tagged enums and the `toml` crate then
//! loses the position of errors inside them; the per-type field checks are
//! done here instead, with clearer messages. The checks of single values
//! (numbers, vectors, colours, lengths, directions) are shared with the
//! sky's tables in `checks.rs`.

use std::collections::HashMap;
use std::path::PathBuf;

use glam::Vec3;
use serde::Deserialize;

use super::material_maps::{
    material_file_with_maps, MapKind, MapSource, MaterialMaps, MAP_KIND_COUNT,
};
use super::value_checks::{Check, Result, MAX_COLOUR, MAX_LENGTH, MIN_LENGTH};
use super::{
    Bloom, Camera, DebugView, DepthPrepass, Exposure, HdrFormat, Light, Lighting, Material, Object,
    Output, Scene, SceneError, ShadingModel, ShadowCascades, ShadowFilter, ShadowLight, Shape,
    TextureFilter, ToneMap, ToneMapOperator, Transform,
};

use crate::mesh::obj;
use crate::mesh::smoothing::Smoothing;
use crate::mesh::MAX_SEGMENTS;

/// Largest accepted output width or height.
pub const MAX_OUTPUT_SIZE: u32 = crate::image_io::MAX_IMAGE_SIDE;
/// Fewest segments accepted in either tessellation direction: fewer cannot
/// enclose any volume (a closed surface needs 3 around).
pub const MIN_SEGMENTS: u32 = 3;
/// Default `light_cutoff`.
pub const DEFAULT_LIGHT_CUTOFF: f32 = 1e-3;
/// Default tessellation `[u, v]` when an object does not give one.
pub const DEFAULT_TESSELLATION: [u32; 2] = [64, 32];
/// Smallest accepted field of view in degrees: below it the projection's
/// focal length overflows 32-bit floats.
pub const MIN_FOV_Y: f64 = 1e-3;
/// Default point-light attenuation `[constant, linear, quadratic]`:
/// inverse-square far away, but finite at the light.
pub const DEFAULT_ATTENUATION: [f32; 3] = [1.0, 0.0, 1.0];

// Numbers are read as f64 and narrowed to f32 by the checks below, so a
// value that overflows or underflows f32 (1e308, 1e-300) is reported as
// out of range rather than as "inf" or "0".
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    ambient: [f64; 3],
    #[serde(default = "default_light_cutoff")]
    light_cutoff: f64,
    #[serde(default)]
    output: OutputFile,
    camera: CameraFile,
    #[serde(default)]
    tone_map: ToneMapFile,
    #[serde(default)]
    lights: Vec<LightFile>,
    #[serde(default)]
    materials: Vec<MaterialFile>,
    #[serde(default)]
    objects: Vec<ObjectFile>,
    sun: Option<super::sky::SunFile>,
    atmosphere: Option<super::sky::AtmosphereFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct OutputFile {
    width: u32,
    height: u32,
    hdr_format: HdrFormat,
    texture_filter: TextureFilter,
    lighting: Lighting,
    depth_prepass: DepthPrepass,
    debug_view: Option<DebugView>,
    static_lights: bool,
    max_pixel_error: f64,
    shadow_map: u32,
    shadow_filter: ShadowFilter,
    shadow_cascades: toml::Value,
}

/// The defaults are [`Output`]'s, so they are written once.
impl Default for OutputFile {
    fn default() -> Self {
        let output = Output::default();
        OutputFile {
            width: output.width,
            height: output.height,
            hdr_format: output.hdr_format,
            texture_filter: output.texture_filter,
            lighting: output.lighting,
            depth_prepass: output.depth_prepass,
            debug_view: output.debug_view,
            static_lights: output.static_lights,
            max_pixel_error: f64::from(output.max_pixel_error),
            shadow_map: output.shadow_map,
            shadow_filter: output.shadow_filter,
            shadow_cascades: toml::Value::String(output.shadow_cascades.name()),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    eye: [f64; 3],
    look_at: [f64; 3],
    #[serde(default = "default_up")]
    up: [f64; 3],
    #[serde(default = "default_fov_y")]
    fov_y: f64,
    #[serde(default = "default_near")]
    near: f64,
    far: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ToneMapFile {
    operator: ToneMapOperator,
    exposure: ExposureFile,
    bloom: Option<BloomFile>,
}

/// `bloom = { intensity = 0.04, levels = 6, radius = 1 }`; `bloom = {}`
/// takes the defaults.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BloomFile {
    intensity: Option<f64>,
    levels: Option<i64>,
    radius: Option<f64>,
}

/// `exposure = 1.5` or `exposure = "auto"`.
#[derive(Deserialize)]
#[serde(untagged)]
enum ExposureFile {
    Number(f64),
    Text(String),
}

impl Default for ToneMapFile {
    fn default() -> Self {
        ToneMapFile {
            operator: ToneMapOperator::Reinhard,
            exposure: ExposureFile::Number(1.0),
            bloom: None,
        }
    }
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum LightKind {
    Point,
    Directional,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightFile {
    #[serde(rename = "type")]
    kind: LightKind,
    position: Option<[f64; 3]>,
    direction: Option<[f64; 3]>,
    #[serde(default = "white")]
    color: [f64; 3],
    #[serde(default = "one")]
    intensity: f64,
    attenuation: Option<[f64; 3]>,
    #[serde(default)]
    shadows: bool,
}

/// Resolves a file field (named, as given) against the scene's folder.
type FileField<'a> = dyn Fn(&str, Option<PathBuf>) -> Result<Option<PathBuf>> + 'a;

material_file_with_maps! {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct MaterialFile {
        name: String,
        ka: Option<[f64; 3]>,
        kd: [f64; 3],
        #[serde(default)]
        ks: [f64; 3],
        #[serde(default = "default_shininess")]
        shininess: f64,
        // The normal map's source properties (its file is a map field).
        normal_map_green: Option<GreenFile>,
        height_map: Option<PathBuf>,
        height_scale: Option<f64>,
        #[serde(default = "one")]
        opacity: f64,
        #[serde(default = "default_shading")]
        shading: ShadingModel,
        #[serde(default)]
        two_sided: bool,
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectFile {
    name: String,
    // Required except for an `obj` shape, whose MTL materials apply when it
    // is absent.
    material: Option<String>,
    shape: ShapeFile,
    smoothing: Option<SmoothingFile>,
    crease_angle: Option<f64>,
    weld_tolerance: Option<f64>,
    tangents: Option<TangentsFile>,
    // Parametric shapes only (default `DEFAULT_TESSELLATION`); an OBJ
    // model brings its own triangles, so giving it one is an error. `[u, v]`
    // or "auto", read as any TOML value so that a wrong one is reported
    // here with the field's name rather than as a failed untagged enum.
    tessellation: Option<toml::Value>,
    #[serde(default)]
    translate: [f64; 3],
    rotate: Option<RotateFile>,
    #[serde(default = "ones")]
    scale: [f64; 3],
    #[serde(default)]
    two_sided: bool,
    #[serde(default = "super::sky::yes")]
    casts_shadows: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotateFile {
    axis: [f64; 3],
    degrees: f64,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum ShapeKind {
    Sphere,
    Torus,
    Plane,
    Cylinder,
    Flag,
    Obj,
}

#[derive(Clone, Copy, Deserialize, PartialEq)]
#[serde(rename_all = "lowercase")]
enum GreenFile {
    Up,
    Down,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum TangentsFile {
    Aerial,
    Mikktspace,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum SmoothingFile {
    Face,
    Object,
    Model,
    File,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeFile {
    #[serde(rename = "type")]
    kind: ShapeKind,
    radius: Option<f64>,
    major_radius: Option<f64>,
    minor_radius: Option<f64>,
    width: Option<f64>,
    depth: Option<f64>,
    height: Option<f64>,
    amplitude: Option<f64>,
    frequency: Option<f64>,
    phase: Option<f64>,
    path: Option<PathBuf>,
}

impl ShapeFile {
    /// Every size field by its file name, given or not.
    fn sizes(&self) -> [(&'static str, Option<f64>); 9] {
        [
            ("radius", self.radius),
            ("major_radius", self.major_radius),
            ("minor_radius", self.minor_radius),
            ("width", self.width),
            ("depth", self.depth),
            ("height", self.height),
            ("amplitude", self.amplitude),
            ("frequency", self.frequency),
            ("phase", self.phase),
        ]
    }
}

fn default_light_cutoff() -> f64 {
    DEFAULT_LIGHT_CUTOFF as f64
}
fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov_y() -> f64 {
    45.0
}
fn default_near() -> f64 {
    0.1
}
fn white() -> [f64; 3] {
    [1.0; 3]
}
fn ones() -> [f64; 3] {
    [1.0; 3]
}
fn one() -> f64 {
    1.0
}
fn default_shininess() -> f64 {
    32.0
}
fn default_shading() -> ShadingModel {
    ShadingModel::Phong
}

/// A parsed and validated scene file: the scene, except that its objects
/// are still [`ObjectDescription`]s, so OBJ models are named but not read.
pub(super) struct Description {
    /// Everything but `objects` (empty) and `files` (empty), final; the
    /// sky's warnings are in `warnings`.
    pub(super) scene: Scene,
    /// The objects in file order.
    pub(super) objects: Vec<ObjectDescription>,
}

/// One `[[objects]]` entry after validation.
pub(super) enum ObjectDescription {
    /// A parametric shape, complete.
    Shape(Object),
    /// A parametric shape whose material is not a scene material: after a
    /// model it may be one of the model's (`object/material`), known only
    /// once the model is read. `object.material` is set then.
    ShapeWithModelMaterial(Object, PendingMaterial),
    /// An `obj` shape: becomes one object per object or group of the file
    /// when the model is read.
    Model(ModelObject),
}

/// An `obj` object as the scene file describes it, every field checked.
pub(super) struct ModelObject {
    /// Where the object is in the file, e.g. `objects[2]`.
    pub(super) field: String,
    /// The object's name, the prefix of its parts' names.
    pub(super) name: String,
    /// The model file, resolved against the scene file's folder.
    pub(super) path: PathBuf,
    /// The material that replaces the model's MTL materials.
    pub(super) material: Option<MaterialRef>,
    /// Smoothing, crease angle, weld tolerance and tangent method.
    pub(super) options: obj::ModelOptions,
    /// The transform every part shares.
    pub(super) transform: Transform,
    /// Every part is drawn into the shadow map (`Object::casts_shadows`).
    pub(super) casts_shadows: bool,
    /// Every part drawn from both sides (`Object::two_sided`).
    pub(super) two_sided: bool,
}

/// The materials an object can name while the file is checked.
struct Materials<'a> {
    /// The scene's materials, in file order.
    materials: &'a [Material],
    /// Their indices by name.
    by_name: &'a HashMap<String, usize>,
    /// Whether an `obj` object came before: its materials are not known
    /// yet (see [`PendingMaterial`]).
    after_model: bool,
}

/// A material an object names.
pub(super) enum MaterialRef {
    /// A scene material, by index.
    Index(usize),
    /// Not a scene material, named by an object after a model: see
    /// [`PendingMaterial`].
    Pending(PendingMaterial),
}

/// A material name that is not a scene material's, given after an `obj`
/// object. The models read before the object add their materials as
/// `object/material`, so the name is looked up once they are read, and
/// refused then, with every material known at that point, if it is still
/// unknown.
pub(super) struct PendingMaterial {
    /// Where the name is, e.g. `objects[3].material`.
    pub(super) field: String,
    pub(super) name: String,
}

impl Check<'_> {
    /// Parses and validates a scene file's text. See [`Scene::from_toml`].
    pub(super) fn parse(&self, text: &str) -> Result<Description> {
        let raw: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
            file: self.file.to_owned(),
            message: e.to_string().trim_end().to_owned(),
        })?;
        self.scene(raw)
    }

    /// A number keeps the checks every positive field has; a string must
    /// be `auto`.
    fn exposure(&self, raw: ExposureFile) -> Result<Exposure> {
        const FIELD: &str = "tone_map.exposure";
        match raw {
            ExposureFile::Number(x) => Ok(Exposure::Fixed(self.positive(FIELD, x)?)),
            ExposureFile::Text(t) if t == "auto" => Ok(Exposure::Auto),
            ExposureFile::Text(t) => Err(self.invalid(
                FIELD,
                format!("expected \"auto\" or a number greater than 0, got \"{t}\""),
            )),
        }
    }

    /// Each field checked; an absent one takes [`Bloom::default`]'s value.
    fn bloom(&self, raw: Option<BloomFile>) -> Result<Option<Bloom>> {
        let Some(raw) = raw else {
            return Ok(None);
        };
        let default = Bloom::default();
        let field = |name: &str| {
            let path = format!("tone_map.bloom.{name}");
            move |reason: String| self.invalid(path, reason)
        };
        Ok(Some(Bloom {
            intensity: match raw.intensity {
                Some(x) => Bloom::intensity_from(x).map_err(field("intensity"))?,
                None => default.intensity,
            },
            levels: match raw.levels {
                Some(x) => Bloom::levels_from(x).map_err(field("levels"))?,
                None => default.levels,
            },
            radius: match raw.radius {
                Some(x) => Bloom::radius_from(x).map_err(field("radius"))?,
                None => default.radius,
            },
        }))
    }

    fn scene(&self, raw: SceneFile) -> Result<Description> {
        let shadow_light = self.shadow_light(&raw)?;
        let ambient = self.colour("ambient", raw.ambient)?;
        let light_cutoff = self.non_negative("light_cutoff", raw.light_cutoff)?;
        let output = self.output(raw.output)?;
        let camera = self.camera(raw.camera)?;
        let tone_map = ToneMap {
            operator: raw.tone_map.operator,
            exposure: self.exposure(raw.tone_map.exposure)?,
            bloom: self.bloom(raw.tone_map.bloom)?,
        };
        let lights = raw
            .lights
            .into_iter()
            .enumerate()
            .map(|(i, light)| self.light(&format!("lights[{i}]"), light))
            .collect::<Result<Vec<_>>>()?;

        let mut materials = Vec::with_capacity(raw.materials.len());
        let mut by_name = HashMap::new();
        for (i, material) in raw.materials.into_iter().enumerate() {
            let path = format!("materials[{i}]");
            let material = self.material(&path, material)?;
            if let Some(first) = by_name.insert(material.name.clone(), i) {
                return Err(self.invalid(
                    format!("{path}.name"),
                    format!(
                        "duplicate material name \"{}\" (already used by materials[{first}])",
                        material.name
                    ),
                ));
            }
            materials.push(material);
        }

        let mut objects = Vec::with_capacity(raw.objects.len());
        let mut after_model = false;
        for (i, object) in raw.objects.into_iter().enumerate() {
            let path = format!("objects[{i}]");
            let models = Materials {
                materials: &materials,
                by_name: &by_name,
                after_model,
            };
            objects.push(if matches!(object.shape.kind, ShapeKind::Obj) {
                after_model = true;
                ObjectDescription::Model(self.model_object(&path, object, &models)?)
            } else {
                self.object(&path, object, &models)?
            });
        }

        let mut warnings = Vec::new();
        let sky = self.sky(raw.sun, raw.atmosphere, &mut warnings)?;

        Ok(Description {
            scene: Scene {
                output,
                camera,
                ambient,
                tone_map,
                lights,
                materials,
                objects: Vec::new(),
                light_cutoff,
                sky,
                shadow_light,
                warnings,
                files: Vec::new(),
            },
            objects,
        })
    }

    fn output(&self, raw: OutputFile) -> Result<Output> {
        for (field, size) in [("output.width", raw.width), ("output.height", raw.height)] {
            if !(1..=MAX_OUTPUT_SIZE).contains(&size) {
                return Err(self.invalid(
                    field,
                    format!("must be between 1 and {MAX_OUTPUT_SIZE}, got {size}"),
                ));
            }
        }
        Ok(Output {
            width: raw.width,
            height: raw.height,
            hdr_format: raw.hdr_format,
            texture_filter: raw.texture_filter,
            lighting: raw.lighting,
            depth_prepass: raw.depth_prepass,
            debug_view: raw.debug_view,
            static_lights: raw.static_lights,
            max_pixel_error: self.positive("output.max_pixel_error", raw.max_pixel_error)?,
            shadow_map: super::shadow_map_side(raw.shadow_map)
                .map_err(|e| self.invalid("output.shadow_map", e))?,
            shadow_filter: raw.shadow_filter,
            shadow_cascades: self.shadow_cascades(&raw.shadow_cascades)?,
        })
    }

    fn camera(&self, raw: CameraFile) -> Result<Camera> {
        let eye = self.coordinates("camera.eye", raw.eye)?;
        let look_at = self.coordinates("camera.look_at", raw.look_at)?;
        let up = self.direction("camera.up", raw.up, "up")?.as_vec3();
        if raw.fov_y.is_finite() && !(raw.fov_y > 0.0 && raw.fov_y < 180.0) {
            return Err(self.invalid(
                "camera.fov_y",
                format!(
                    "must be between 0 and 180 degrees (exclusive), got {}",
                    raw.fov_y
                ),
            ));
        }
        if raw.fov_y < MIN_FOV_Y || 180.0 - raw.fov_y < MIN_FOV_Y {
            return Err(self.invalid(
                "camera.fov_y",
                format!(
                    "must be between {MIN_FOV_Y} and {} degrees, got {:e}",
                    180.0 - MIN_FOV_Y,
                    raw.fov_y
                ),
            ));
        }
        let fov = self.finite("camera.fov_y", raw.fov_y)?;
        let near = self.length("camera.near", raw.near)?;
        let far = match raw.far {
            None => None,
            Some(far) => {
                let far = self.finite("camera.far", far)?;
                if far <= near {
                    return Err(self.invalid(
                        "camera.far",
                        format!(
                            "must be greater than camera.near ({near}), got {far} \
                             (omit far for an infinite far plane)"
                        ),
                    ));
                }
                Some(far)
            }
        };
        let forward = (look_at - eye).try_normalize().ok_or_else(|| {
            self.invalid(
                "camera.look_at",
                "equals camera.eye, so there is no view direction",
            )
        })?;
        let up_dir = up.as_dvec3();
        // sin of the angle between them; below ~0.06 degrees the look-at
        // basis is numerically meaningless.
        if forward.cross(up_dir).length() < 1e-3 {
            return Err(self.invalid(
                "camera.up",
                "is parallel to the view direction (look_at - eye)",
            ));
        }
        Ok(Camera {
            eye,
            look_at,
            up,
            fov_y_degrees: fov,
            near,
            far,
        })
    }

    /// The light with `shadows = true`: at most one (a point light, a
    /// directional light or the sun).
    fn shadow_light(&self, raw: &SceneFile) -> Result<Option<ShadowLight>> {
        let mut casters = Vec::new();
        for (i, light) in raw.lights.iter().enumerate() {
            if !light.shadows {
                continue;
            }
            casters.push((format!("lights[{i}].shadows"), ShadowLight::Light(i)));
        }
        if raw.sun.as_ref().is_some_and(|sun| sun.shadows) {
            casters.push(("sun.shadows".to_owned(), ShadowLight::Sun));
        }
        if let [(first, _), (second, _), ..] = casters.as_slice() {
            return Err(self.invalid(
                second.clone(),
                format!("only one light may cast shadows, and {first} is already set"),
            ));
        }
        if let (Some((field, _)), Lighting::Deferred) = (casters.first(), raw.output.lighting) {
            return Err(self.invalid(field.clone(), super::SHADOWS_NEED_FORWARD));
        }
        Ok(casters.first().map(|&(_, light)| light))
    }

    /// `[output] shadow_cascades`: `"auto"` or a whole count, read from
    /// any TOML value so a wrong type is reported with the field's name.
    fn shadow_cascades(&self, raw: &toml::Value) -> Result<ShadowCascades> {
        let text = match raw {
            toml::Value::String(s) => s.clone(),
            toml::Value::Integer(n) => n.to_string(),
            other => format!("{other}"),
        };
        ShadowCascades::parse(&text).map_err(|e| self.invalid("output.shadow_cascades", e))
    }

    fn light(&self, path: &str, raw: LightFile) -> Result<Light> {
        let field = |name: &str| format!("{path}.{name}");
        let base = self.colour(&field("color"), raw.color)?;
        let intensity = self.non_negative(&field("intensity"), raw.intensity)?;
        let peak = raw.color.iter().fold(0f64, |m, c| m.max(*c)) * raw.intensity;
        if peak > MAX_COLOUR {
            return Err(self.invalid(
                field("intensity"),
                format!(
                    "color * intensity must be at most {MAX_COLOUR:e} per channel, got {peak:e}"
                ),
            ));
        }
        let color = base * intensity;
        match raw.kind {
            LightKind::Point => {
                if raw.direction.is_some() {
                    return Err(self.invalid(
                        field("direction"),
                        "point lights have no direction (use type = \"directional\")",
                    ));
                }
                let position = raw
                    .position
                    .ok_or_else(|| self.invalid(field("position"), "required for a point light"))?;
                let position = self.coordinates(&field("position"), position)?;
                let attenuation = self.colour(
                    &field("attenuation"),
                    raw.attenuation
                        .unwrap_or(DEFAULT_ATTENUATION.map(f64::from)),
                )?;
                if attenuation == Vec3::ZERO {
                    return Err(self.invalid(
                        field("attenuation"),
                        "all three terms are zero, which would make the light infinitely bright",
                    ));
                }
                // A term is either off (0) or large enough that 1 / term
                // stays far from overflowing.
                let attenuation_file = raw
                    .attenuation
                    .unwrap_or(DEFAULT_ATTENUATION.map(f64::from));
                if let Some(i) = attenuation_file
                    .iter()
                    .position(|&t| t != 0.0 && t < MIN_LENGTH)
                {
                    return Err(self.invalid(
                        field("attenuation"),
                        format!(
                            "term {i} must be 0 or at least {MIN_LENGTH:e}, got {:e}",
                            attenuation_file[i]
                        ),
                    ));
                }
                Ok(Light::Point {
                    position,
                    color,
                    attenuation,
                })
            }
            LightKind::Directional => {
                for (name, given) in [
                    ("position", raw.position.is_some()),
                    ("attenuation", raw.attenuation.is_some()),
                ] {
                    if given {
                        return Err(self.invalid(
                            field(name),
                            format!("directional lights have no {name} (use type = \"point\")"),
                        ));
                    }
                }
                let direction = raw.direction.ok_or_else(|| {
                    self.invalid(field("direction"), "required for a directional light")
                })?;
                Ok(Light::Directional {
                    direction: self
                        .direction(&field("direction"), direction, "direction")?
                        .as_vec3(),
                    color,
                })
            }
        }
    }

    fn material(&self, path: &str, mut raw: MaterialFile) -> Result<Material> {
        let field = |name: &str| format!("{path}.{name}");
        if raw.name.trim().is_empty() {
            return Err(self.invalid(field("name"), "must not be empty"));
        }
        let kd = self.colour(&field("kd"), raw.kd)?;
        // Ambient reflectance defaults to the diffuse colour, the usual
        // choice when a material has one base colour.
        let ka = match raw.ka {
            Some(ka) => self.colour(&field("ka"), ka)?,
            None => kd,
        };
        let ks = self.colour(&field("ks"), raw.ks)?;
        let shininess = self.positive(&field("shininess"), raw.shininess);
        // Zero gets its own explanation: it looks like a natural way to ask
        // for "no highlight", but the shader's pow(0, 0) is undefined.
        let shininess = match shininess {
            Err(_) if raw.shininess == 0.0 => {
                return Err(self.invalid(
                    field("shininess"),
                    "must be greater than 0, got 0 (pow(0, 0) is undefined in GLSL; \
                     use ks = [0, 0, 0] for no highlight)",
                ))
            }
            other => other?,
        };
        let opacity = self.finite(&field("opacity"), raw.opacity)?;
        if !(0.0..=1.0).contains(&opacity) {
            return Err(self.invalid(
                field("opacity"),
                format!("must be between 0 and 1, got {opacity}"),
            ));
        }
        let file_at = |name: &str, given: Option<PathBuf>| -> Result<Option<PathBuf>> {
            let Some(given) = given else { return Ok(None) };
            let resolved = self.base_dir.join(&given);
            match crate::safe_files::input_file_problem(&resolved) {
                Some(problem) => Err(self.invalid(field(name), problem)),
                None => Ok(Some(resolved)),
            }
        };
        let mut maps = MaterialMaps::default();
        for (kind, given) in raw.map_files() {
            maps.set(
                kind,
                file_at(kind.info().field, given)?.map(MapSource::file),
            );
        }
        self.normal_map_source(&field, &file_at, &mut maps, &raw)?;
        Ok(Material {
            name: raw.name,
            ka,
            kd,
            ks,
            shininess,
            maps,
            opacity,
            shading: raw.shading,
            two_sided: raw.two_sided,
        })
    }

    /// The normal map's source properties: the green axis of a normal map,
    /// or a height map with its scale in the normal map's place; `file_at`
    /// resolves a file field.
    fn normal_map_source(
        &self,
        field: &dyn Fn(&str) -> String,
        file_at: &FileField<'_>,
        maps: &mut MaterialMaps,
        raw: &MaterialFile,
    ) -> Result<()> {
        let normal_map = maps.get(MapKind::Normal).is_some();
        if raw.normal_map_green.is_some() && !normal_map {
            return Err(self.invalid(field("normal_map_green"), "given without a normal_map"));
        }
        let height_map = file_at("height_map", raw.height_map.clone())?;
        let height_scale = match (&height_map, raw.height_scale) {
            (Some(_), _) if normal_map => {
                return Err(self.invalid(
                    field("height_map"),
                    "give a normal_map or a height_map, not both",
                ))
            }
            (None, Some(_)) => {
                return Err(self.invalid(field("height_scale"), "given without a height_map"))
            }
            (Some(_), scale) => {
                let scale = scale.unwrap_or(1.0);
                if !(scale.is_finite() && scale > 0.0 && scale <= MAX_LENGTH) {
                    return Err(self.invalid(
                        field("height_scale"),
                        format!("must be greater than 0 and at most {MAX_LENGTH:e}, got {scale}"),
                    ));
                }
                Some(scale as f32)
            }
            (None, None) => None,
        };
        if let Some(path) = height_map {
            maps.set(
                MapKind::Normal,
                Some(MapSource {
                    height_scale,
                    ..MapSource::file(path)
                }),
            );
        } else if let Some(source) = maps.get(MapKind::Normal) {
            let source = MapSource {
                green_down: raw.normal_map_green == Some(GreenFile::Down),
                ..source.clone()
            };
            maps.set(MapKind::Normal, Some(source));
        }
        Ok(())
    }

    fn object(
        &self,
        path: &str,
        raw: ObjectFile,
        materials: &Materials<'_>,
    ) -> Result<ObjectDescription> {
        let field = |name: &str| format!("{path}.{name}");
        if raw.name.trim().is_empty() {
            return Err(self.invalid(field("name"), "must not be empty"));
        }
        for (given, name) in [
            (raw.smoothing.is_some(), "smoothing"),
            (raw.crease_angle.is_some(), "crease_angle"),
            (raw.weld_tolerance.is_some(), "weld_tolerance"),
            (raw.tangents.is_some(), "tangents"),
        ] {
            if given {
                return Err(self.invalid(field(name), "only an obj shape takes this"));
            }
        }
        let material = self.material_ref(&field("material"), raw.material.as_deref(), materials)?;
        let shape = self.shape(&field("shape"), &raw.shape)?;
        let (tessellation, auto_tessellation) =
            self.tessellation(&field("tessellation"), raw.tessellation.as_ref())?;
        let transform = self.transform(path, &raw)?;
        let mut object = Object {
            name: raw.name,
            shape,
            tessellation,
            auto_tessellation,
            // Replaced when a pending name is resolved.
            material: usize::MAX,
            transform,
            two_sided: raw.two_sided,
            casts_shadows: raw.casts_shadows,
        };
        Ok(match material {
            MaterialRef::Index(i) => {
                object.material = i;
                ObjectDescription::Shape(object)
            }
            MaterialRef::Pending(name) => ObjectDescription::ShapeWithModelMaterial(object, name),
        })
    }

    /// An object's `tessellation`: `[u, v]` (each in
    /// `MIN_SEGMENTS..=MAX_SEGMENTS`) or `"auto"`, as `(grid, auto)`; an
    /// auto object keeps the default grid for a numeric `tessellation` knob.
    fn tessellation(&self, field: &str, raw: Option<&toml::Value>) -> Result<((u32, u32), bool)> {
        let default = (DEFAULT_TESSELLATION[0], DEFAULT_TESSELLATION[1]);
        let expected = "expected [u, v] (two integers) or \"auto\"";
        let items = match raw {
            None => return Ok((default, false)),
            Some(toml::Value::String(word)) if word == "auto" => return Ok((default, true)),
            Some(toml::Value::String(word)) => {
                return Err(self.invalid(field, format!("{expected}, got \"{word}\"")))
            }
            Some(toml::Value::Array(items)) if items.len() == 2 => items,
            Some(other) => return Err(self.invalid(field, format!("{expected}, got {other}"))),
        };
        let mut grid = [0u32; 2];
        for ((direction, item), count) in ["u", "v"].into_iter().zip(items).zip(&mut grid) {
            let segments = item.as_integer().ok_or_else(|| {
                self.invalid(
                    field,
                    format!("{direction} segments: {expected}, got {item}"),
                )
            })?;
            *count = u32::try_from(segments)
                .ok()
                .filter(|s| (MIN_SEGMENTS..=MAX_SEGMENTS).contains(s))
                .ok_or_else(|| {
                    self.invalid(
                        field,
                        format!(
                            "{direction} segments must be between {MIN_SEGMENTS} and \
                             {MAX_SEGMENTS}, got {segments}"
                        ),
                    )
                })?;
        }
        Ok(((grid[0], grid[1]), false))
    }

    /// An `obj` object: every field is checked here, and the model is
    /// read after parsing (`models.rs`). It takes `smoothing`,
    /// `crease_angle`, `weld_tolerance` and `tangents`, not sizes or a
    /// tessellation; its `material` is optional (the model's MTL materials
    /// apply without it).
    fn model_object(
        &self,
        path: &str,
        raw: ObjectFile,
        materials: &Materials<'_>,
    ) -> Result<ModelObject> {
        let field = |name: &str| format!("{path}.{name}");
        if raw.name.trim().is_empty() {
            return Err(self.invalid(field("name"), "must not be empty"));
        }
        let shape = &raw.shape;
        if let Some((name, _)) = shape.sizes().iter().find(|(_, v)| v.is_some()) {
            return Err(self.invalid(
                field(&format!("shape.{name}")),
                format!("an obj has no {name} (it takes path)"),
            ));
        }
        if raw.tessellation.is_some() {
            return Err(self.invalid(
                field("tessellation"),
                "an obj model brings its own triangles; tessellation is for parametric shapes",
            ));
        }
        let model_path = shape
            .path
            .as_ref()
            .ok_or_else(|| self.invalid(field("shape.path"), "required for an obj"))?;
        let crease_degrees = match raw.crease_angle {
            None => obj::DEFAULT_CREASE_DEGREES,
            Some(x) => {
                let x = self.finite(&field("crease_angle"), x)?;
                if !(0.0..=180.0).contains(&x) {
                    return Err(self.invalid(
                        field("crease_angle"),
                        format!("must be between 0 and 180 degrees, got {x}"),
                    ));
                }
                x
            }
        };
        let weld_tolerance = match raw.weld_tolerance {
            None => obj::DEFAULT_WELD_TOLERANCE,
            Some(x) => {
                let x = self.finite(&field("weld_tolerance"), x)?;
                // Up to 1e-3: welding further apart merges real features,
                // and the hash cells would hold so many points that welding
                // turns quadratic.
                if !(0.0..=1e-3).contains(&x) {
                    return Err(self.invalid(
                        field("weld_tolerance"),
                        format!(
                            "must be between 0 and 0.001 (a fraction of the model's \
                             bounding-box diagonal), got {x}"
                        ),
                    ));
                }
                x
            }
        };
        let options = obj::ModelOptions {
            smoothing: raw.smoothing.map(|s| match s {
                SmoothingFile::Face => Smoothing::Face,
                SmoothingFile::Object => Smoothing::Object,
                SmoothingFile::Model => Smoothing::Model,
                SmoothingFile::File => Smoothing::File,
            }),
            crease_degrees,
            weld_tolerance,
            tangents: match raw.tangents {
                None | Some(TangentsFile::Aerial) => obj::TangentMethod::Aerial,
                Some(TangentsFile::Mikktspace) => obj::TangentMethod::Mikktspace,
            },
        };
        let transform = self.transform(path, &raw)?;
        let material = match &raw.material {
            Some(name) => Some(self.material_ref(&field("material"), Some(name), materials)?),
            None => None,
        };
        Ok(ModelObject {
            field: path.to_owned(),
            path: self.base_dir.join(model_path),
            name: raw.name,
            material,
            options,
            transform,
            two_sided: raw.two_sided,
            casts_shadows: raw.casts_shadows,
        })
    }

    /// The material `name` (at `field`), which is required: a scene
    /// material, or, after a model, pending until the model is read.
    fn material_ref(
        &self,
        field: &str,
        name: Option<&str>,
        materials: &Materials<'_>,
    ) -> Result<MaterialRef> {
        match name {
            Some(name) if materials.after_model && !materials.by_name.contains_key(name) => {
                Ok(MaterialRef::Pending(PendingMaterial {
                    field: field.to_owned(),
                    name: name.to_owned(),
                }))
            }
            name => self
                .material_index(field, name, materials.materials, materials.by_name)
                .map(MaterialRef::Index),
        }
    }

    /// The index of the material `name` (at `field`), which is required.
    pub(super) fn material_index(
        &self,
        field: &str,
        name: Option<&str>,
        materials: &[Material],
        by_name: &HashMap<String, usize>,
    ) -> Result<usize> {
        let name = name.ok_or_else(|| {
            self.invalid(field, "required (only an obj shape has its own materials)")
        })?;
        let material = *by_name.get(name).ok_or_else(|| {
            let known: Vec<_> = materials
                .iter()
                .map(|m| format!("\"{}\"", m.name))
                .collect();
            let known = if known.is_empty() {
                "none are defined".to_owned()
            } else {
                format!("defined: {}", known.join(", "))
            };
            self.invalid(field, format!("unknown material \"{name}\" ({known})"))
        })?;
        Ok(material)
    }

    /// The object transform of `raw` (object at `path`).
    fn transform(&self, path: &str, raw: &ObjectFile) -> Result<Transform> {
        let field = |name: &str| format!("{path}.{name}");
        let translate = self.coordinates(&field("translate"), raw.translate)?;
        let (rotate_axis, rotate_degrees) = match &raw.rotate {
            None => (Vec3::Y, 0.0),
            Some(rotate) => {
                let axis = self
                    .direction(&field("rotate.axis"), rotate.axis, "axis")?
                    .as_vec3();
                if !rotate.degrees.is_finite() {
                    self.finite(&field("rotate.degrees"), rotate.degrees)?;
                }
                // Reduced in f64 first: 1e30 degrees is a valid angle, but
                // its f32 radians are not a meaningful one.
                (axis, rotate.degrees.rem_euclid(360.0) as f32)
            }
        };
        let scale = self.vec3(&field("scale"), raw.scale)?;
        for (i, s) in scale.to_array().into_iter().enumerate() {
            // A subnormal scale is as bad as zero: its reciprocal, needed
            // for the normal matrix, overflows.
            if s == 0.0 || !s.recip().is_finite() {
                return Err(self.invalid(
                    field("scale"),
                    format!(
                        "component {i} is zero (or too small to invert), which flattens the object"
                    ),
                ));
            }
            // The bounds are checked on the value as written: rounded to
            // f32, 1e-6 is just below 1e-6, and the documented bound
            // itself would be refused.
            if s > 0.0 && !(MIN_LENGTH..=MAX_LENGTH).contains(&raw.scale[i]) {
                return Err(self.invalid(
                    field("scale"),
                    format!(
                        "component {i} must be between {MIN_LENGTH:e} and {MAX_LENGTH:e}, got {:e}",
                        raw.scale[i]
                    ),
                ));
            }
            if s < 0.0 {
                return Err(self.invalid(
                    field("scale"),
                    format!(
                        "component {i} is negative ({s}); a mirroring scale turns front \
                         faces into back faces (use rotate to flip an object)"
                    ),
                ));
            }
        }
        Ok(Transform {
            translate,
            rotate_axis,
            rotate_degrees,
            scale,
        })
    }

    fn shape(&self, path: &str, raw: &ShapeFile) -> Result<Shape> {
        if raw.path.is_some() {
            return Err(self.invalid(format!("{path}.path"), "only an obj shape has a path"));
        }
        let (kind, required, optional): (&str, &[&str], &[&str]) = match raw.kind {
            ShapeKind::Obj => return Err(self.invalid(path, "an obj is described by model_object")),
            ShapeKind::Sphere => ("sphere", &["radius"], &[]),
            ShapeKind::Torus => ("torus", &["major_radius", "minor_radius"], &[]),
            ShapeKind::Plane => ("plane", &["width", "depth"], &[]),
            ShapeKind::Cylinder => ("cylinder", &["radius", "height"], &[]),
            ShapeKind::Flag => (
                "flag",
                &["width", "height", "amplitude", "frequency"],
                &["phase"],
            ),
        };
        let given = raw.sizes();
        for (name, value) in given {
            if value.is_some() && !required.contains(&name) && !optional.contains(&name) {
                let takes: Vec<_> = required.iter().chain(optional).copied().collect();
                return Err(self.invalid(
                    format!("{path}.{name}"),
                    format!("a {kind} has no {name} (it takes {})", takes.join(", ")),
                ));
            }
        }
        // Looks a parameter up by name; the list above is the single source
        // of truth for which names exist.
        let get = |name: &str| given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v);
        let size = |name: &str| -> Result<f32> {
            let field = format!("{path}.{name}");
            let value =
                get(name).ok_or_else(|| self.invalid(&field, format!("required for a {kind}")))?;
            self.length(&field, value)
        };
        let number = |name: &str| -> Result<f32> {
            let field = format!("{path}.{name}");
            let value =
                get(name).ok_or_else(|| self.invalid(&field, format!("required for a {kind}")))?;
            let v = self.finite(&field, value)?;
            if value.abs() > MAX_LENGTH {
                return Err(self.invalid(
                    &field,
                    format!("must be between -{MAX_LENGTH:e} and {MAX_LENGTH:e}, got {value:e}"),
                ));
            }
            Ok(v)
        };
        Ok(match raw.kind {
            ShapeKind::Obj => return Err(self.invalid(path, "an obj is described by model_object")),
            ShapeKind::Sphere => Shape::Sphere {
                radius: size("radius")?,
            },
            ShapeKind::Torus => Shape::Torus {
                major_radius: size("major_radius")?,
                minor_radius: size("minor_radius")?,
            },
            ShapeKind::Plane => Shape::Plane {
                width: size("width")?,
                depth: size("depth")?,
            },
            ShapeKind::Cylinder => Shape::Cylinder {
                radius: size("radius")?,
                height: size("height")?,
            },
            ShapeKind::Flag => Shape::Flag {
                width: size("width")?,
                height: size("height")?,
                amplitude: number("amplitude")?,
                frequency: number("frequency")?,
                phase: match get("phase") {
                    Some(phase) => {
                        self.finite(&format!("{path}.phase"), phase)?;
                        // Reduced in f64 so a large phase keeps its meaning.
                        phase.rem_euclid(std::f64::consts::TAU) as f32
                    }
                    None => 0.0,
                },
            },
        })
    }
}
