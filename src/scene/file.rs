//! The TOML scene format: serde mirror types that only describe the syntax,
//! and the validation that turns them into a [`Scene`].
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
//! done here instead, with clearer messages.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use super::{
    Camera, HdrFormat, Light, Lighting, Material, Object, Output, Scene, SceneError, ShadingModel,
    Shape, TextureFilter, ToneMap, ToneMapOperator, Transform,
};
use crate::mesh::MAX_SEGMENTS;

/// Largest accepted output width or height.
pub const MAX_OUTPUT_SIZE: u32 = 16384;
/// Fewest segments accepted in either tessellation direction: fewer cannot
/// enclose any volume (a closed surface needs 3 around).
pub const MIN_SEGMENTS: u32 = 3;
/// Default `light_cutoff`.
pub const DEFAULT_LIGHT_CUTOFF: f32 = 1e-3;
/// Default tessellation `[u, v]` when an object does not give one.
pub const DEFAULT_TESSELLATION: [u32; 2] = [64, 32];
/// Default point-light attenuation `[constant, linear, quadratic]`:
/// inverse-square far away, but finite at the light.
pub const DEFAULT_ATTENUATION: [f32; 3] = [1.0, 0.0, 1.0];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    ambient: [f32; 3],
    #[serde(default = "default_light_cutoff")]
    light_cutoff: f32,
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
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct OutputFile {
    width: u32,
    height: u32,
    hdr_format: HdrFormat,
    texture_filter: TextureFilter,
    lighting: Lighting,
}

impl Default for OutputFile {
    fn default() -> Self {
        OutputFile {
            width: 640,
            height: 360,
            hdr_format: HdrFormat::Rgba16F,
            texture_filter: TextureFilter::Trilinear,
            lighting: Lighting::Forward,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    eye: [f32; 3],
    look_at: [f32; 3],
    #[serde(default = "default_up")]
    up: [f32; 3],
    #[serde(default = "default_fov_y")]
    fov_y: f32,
    #[serde(default = "default_near")]
    near: f32,
    far: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ToneMapFile {
    operator: ToneMapOperator,
    exposure: f32,
}

impl Default for ToneMapFile {
    fn default() -> Self {
        ToneMapFile {
            operator: ToneMapOperator::Reinhard,
            exposure: 1.0,
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
    position: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
    #[serde(default = "white")]
    color: [f32; 3],
    #[serde(default = "one")]
    intensity: f32,
    attenuation: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialFile {
    name: String,
    ka: Option<[f32; 3]>,
    kd: [f32; 3],
    #[serde(default)]
    ks: [f32; 3],
    #[serde(default = "default_shininess")]
    shininess: f32,
    texture: Option<PathBuf>,
    #[serde(default = "one")]
    opacity: f32,
    #[serde(default = "default_shading")]
    shading: ShadingModel,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectFile {
    name: String,
    material: String,
    shape: ShapeFile,
    #[serde(default = "default_tessellation")]
    tessellation: [u32; 2],
    #[serde(default)]
    translate: [f32; 3],
    rotate: Option<RotateFile>,
    #[serde(default = "ones")]
    scale: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotateFile {
    axis: [f32; 3],
    degrees: f32,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum ShapeKind {
    Sphere,
    Torus,
    Plane,
    Cylinder,
    Flag,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeFile {
    #[serde(rename = "type")]
    kind: ShapeKind,
    radius: Option<f32>,
    major_radius: Option<f32>,
    minor_radius: Option<f32>,
    width: Option<f32>,
    depth: Option<f32>,
    height: Option<f32>,
    amplitude: Option<f32>,
    frequency: Option<f32>,
    phase: Option<f32>,
}

fn default_light_cutoff() -> f32 {
    DEFAULT_LIGHT_CUTOFF
}
fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov_y() -> f32 {
    45.0
}
fn default_near() -> f32 {
    0.1
}
fn white() -> [f32; 3] {
    [1.0; 3]
}
fn ones() -> [f32; 3] {
    [1.0; 3]
}
fn one() -> f32 {
    1.0
}
fn default_shininess() -> f32 {
    32.0
}
fn default_shading() -> ShadingModel {
    ShadingModel::Phong
}
fn default_tessellation() -> [u32; 2] {
    DEFAULT_TESSELLATION
}

/// Parses and validates a scene. See [`Scene::from_toml`].
pub(super) fn parse(text: &str, file: &str, base_dir: &Path) -> Result<Scene> {
    let raw: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
        file: file.to_owned(),
        message: e.to_string().trim_end().to_owned(),
    })?;
    Check { file, base_dir }.scene(raw)
}

/// Validation context: where messages say the error is, and where textures
/// are looked up.
struct Check<'a> {
    file: &'a str,
    base_dir: &'a Path,
}

type Result<T> = std::result::Result<T, SceneError>;

impl Check<'_> {
    fn invalid(&self, field: impl Into<String>, reason: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_owned(),
            field: field.into(),
            reason: reason.into(),
        }
    }

    fn finite(&self, field: &str, x: f32) -> Result<f32> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(field, format!("must be a finite number, got {x}")))
        }
    }

    fn vec3(&self, field: &str, v: [f32; 3]) -> Result<Vec3> {
        for (i, x) in v.iter().enumerate() {
            if !x.is_finite() {
                return Err(self.invalid(
                    field,
                    format!("component {i} must be a finite number, got {x}"),
                ));
            }
        }
        Ok(Vec3::from(v))
    }

    /// A colour or other per-channel factor: finite and >= 0 (> 1 is fine,
    /// the pipeline is HDR).
    fn colour(&self, field: &str, v: [f32; 3]) -> Result<Vec3> {
        let c = self.vec3(field, v)?;
        match v.iter().position(|&x| x < 0.0) {
            Some(i) => Err(self.invalid(
                field,
                format!("component {i} must not be negative, got {}", v[i]),
            )),
            None => Ok(c),
        }
    }

    fn positive(&self, field: &str, x: f32) -> Result<f32> {
        let x = self.finite(field, x)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(field, format!("must be greater than 0, got {x}")))
        }
    }

    fn non_negative(&self, field: &str, x: f32) -> Result<f32> {
        let x = self.finite(field, x)?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(field, format!("must not be negative, got {x}")))
        }
    }

    /// A direction or axis, returned normalised.
    fn direction(&self, field: &str, v: [f32; 3], what: &str) -> Result<Vec3> {
        self.vec3(field, v)?
            .try_normalize()
            .ok_or_else(|| self.invalid(field, format!("{what} has zero length")))
    }

    fn scene(&self, raw: SceneFile) -> Result<Scene> {
        let ambient = self.colour("ambient", raw.ambient)?;
        let light_cutoff = self.non_negative("light_cutoff", raw.light_cutoff)?;
        let output = self.output(raw.output)?;
        let camera = self.camera(raw.camera)?;
        let tone_map = ToneMap {
            operator: raw.tone_map.operator,
            exposure: self.positive("tone_map.exposure", raw.tone_map.exposure)?,
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

        let objects = raw
            .objects
            .into_iter()
            .enumerate()
            .map(|(i, object)| self.object(&format!("objects[{i}]"), object, &materials, &by_name))
            .collect::<Result<Vec<_>>>()?;

        Ok(Scene {
            output,
            camera,
            ambient,
            tone_map,
            lights,
            materials,
            objects,
            light_cutoff,
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
        })
    }

    fn camera(&self, raw: CameraFile) -> Result<Camera> {
        let eye = self.vec3("camera.eye", raw.eye)?;
        let look_at = self.vec3("camera.look_at", raw.look_at)?;
        let up = self.vec3("camera.up", raw.up)?;
        let fov = self.finite("camera.fov_y", raw.fov_y)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.invalid(
                "camera.fov_y",
                format!("must be between 0 and 180 degrees (exclusive), got {fov}"),
            ));
        }
        let near = self.positive("camera.near", raw.near)?;
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
        let up_dir = up
            .try_normalize()
            .ok_or_else(|| self.invalid("camera.up", "up has zero length"))?;
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
            up: up_dir,
            fov_y_degrees: fov,
            near,
            far,
        })
    }

    fn light(&self, path: &str, raw: LightFile) -> Result<Light> {
        let field = |name: &str| format!("{path}.{name}");
        let base = self.colour(&field("color"), raw.color)?;
        let intensity = self.non_negative(&field("intensity"), raw.intensity)?;
        let color = base * intensity;
        if !color.is_finite() {
            return Err(self.invalid(field("intensity"), "color * intensity overflows"));
        }
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
                let position = self.vec3(&field("position"), position)?;
                let attenuation = self.colour(
                    &field("attenuation"),
                    raw.attenuation.unwrap_or(DEFAULT_ATTENUATION),
                )?;
                if attenuation == Vec3::ZERO {
                    return Err(self.invalid(
                        field("attenuation"),
                        "all three terms are zero, which would make the light infinitely bright",
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
                    direction: self.direction(&field("direction"), direction, "direction")?,
                    color,
                })
            }
        }
    }

    fn material(&self, path: &str, raw: MaterialFile) -> Result<Material> {
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
        let texture = match raw.texture {
            None => None,
            Some(texture) => {
                let resolved = self.base_dir.join(&texture);
                if !resolved.exists() {
                    return Err(self.invalid(
                        field("texture"),
                        format!("file not found: {}", resolved.display()),
                    ));
                }
                if !resolved.is_file() {
                    return Err(self.invalid(
                        field("texture"),
                        format!("not a file: {}", resolved.display()),
                    ));
                }
                Some(resolved)
            }
        };
        Ok(Material {
            name: raw.name,
            ka,
            kd,
            ks,
            shininess,
            texture,
            opacity,
            shading: raw.shading,
        })
    }

    fn object(
        &self,
        path: &str,
        raw: ObjectFile,
        materials: &[Material],
        by_name: &HashMap<String, usize>,
    ) -> Result<Object> {
        let field = |name: &str| format!("{path}.{name}");
        if raw.name.trim().is_empty() {
            return Err(self.invalid(field("name"), "must not be empty"));
        }
        let material = *by_name.get(&raw.material).ok_or_else(|| {
            let known: Vec<_> = materials
                .iter()
                .map(|m| format!("\"{}\"", m.name))
                .collect();
            let known = if known.is_empty() {
                "none are defined".to_owned()
            } else {
                format!("defined: {}", known.join(", "))
            };
            self.invalid(
                field("material"),
                format!("unknown material \"{}\" ({known})", raw.material),
            )
        })?;
        let shape = self.shape(&field("shape"), &raw.shape)?;
        for (direction, segments) in ["u", "v"].into_iter().zip(raw.tessellation) {
            if !(MIN_SEGMENTS..=MAX_SEGMENTS).contains(&segments) {
                return Err(self.invalid(
                    field("tessellation"),
                    format!(
                        "{direction} segments must be between {MIN_SEGMENTS} and \
                         {MAX_SEGMENTS}, got {segments}"
                    ),
                ));
            }
        }
        let translate = self.vec3(&field("translate"), raw.translate)?;
        let (rotate_axis, rotate_degrees) = match raw.rotate {
            None => (Vec3::Y, 0.0),
            Some(rotate) => (
                self.direction(&field("rotate.axis"), rotate.axis, "axis")?,
                self.finite(&field("rotate.degrees"), rotate.degrees)?,
            ),
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
        Ok(Object {
            name: raw.name,
            shape,
            tessellation: (raw.tessellation[0], raw.tessellation[1]),
            material,
            transform: Transform {
                translate,
                rotate_axis,
                rotate_degrees,
                scale,
            },
        })
    }

    fn shape(&self, path: &str, raw: &ShapeFile) -> Result<Shape> {
        let (kind, required, optional): (&str, &[&str], &[&str]) = match raw.kind {
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
        let given = [
            ("radius", raw.radius),
            ("major_radius", raw.major_radius),
            ("minor_radius", raw.minor_radius),
            ("width", raw.width),
            ("depth", raw.depth),
            ("height", raw.height),
            ("amplitude", raw.amplitude),
            ("frequency", raw.frequency),
            ("phase", raw.phase),
        ];
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
            self.positive(&field, value)
        };
        let number = |name: &str| -> Result<f32> {
            let field = format!("{path}.{name}");
            let value =
                get(name).ok_or_else(|| self.invalid(&field, format!("required for a {kind}")))?;
            self.finite(&field, value)
        };
        Ok(match raw.kind {
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
                    Some(phase) => self.finite(&format!("{path}.phase"), phase)?,
                    None => 0.0,
                },
            },
        })
    }
}
