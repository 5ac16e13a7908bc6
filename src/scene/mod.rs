//! Scene description: camera, lights, materials and objects, loaded from a
//! TOML file and validated so that the renderer can trust every value.
//!
//! The file format is documented on [`Scene::from_toml`]; example scenes are
//! in `assets/scenes/`.

mod camera;
mod error;
mod file;
mod knobs;
mod lights;
mod material;
pub mod material_maps;
mod model_scene;
mod models;
mod object;
mod screen_tessellation;
mod sky;
mod value_checks;

use std::path::Path;

use glam::{DVec3, Vec3};
use serde::Deserialize;

pub use crate::atmosphere::model::{
    AerialPerspective, Atmosphere, OzoneDepth, Sky, Sun, TableFilter, TableMapping,
    DEFAULT_ATMOSPHERE_SAMPLES, DEFAULT_TABLE_SIZE, MAX_ATMOSPHERE_SAMPLES, MAX_TABLE_SIDE,
    MIN_TABLE_SIDE,
};
pub use crate::mesh::obj::AssetWarning;
pub use camera::Camera;
pub use error::SceneError;
pub use file::{
    DEFAULT_ATTENUATION, DEFAULT_LIGHT_CUTOFF, DEFAULT_TESSELLATION, MAX_OUTPUT_SIZE, MIN_SEGMENTS,
};
pub use knobs::{settings as knob_settings, Best, Knob, KnobError, KNOBS};
pub use lights::{Light, LightRange};
pub use material::{placeholder_texels, Material, ShadingModel, Texture, PLACEHOLDER_TEXTURE};
pub use model_scene::{
    is_model_file, model_scene_toml, ModelSceneOptions, MODEL_FOV_Y, MODEL_VIEW_AZIMUTH,
    MODEL_VIEW_ELEVATION,
};
pub use object::{Object, Shape, Transform};
pub use screen_tessellation::{
    ladder_up, required_segments, segments_for_error, surface_bounds, SurfaceBounds,
    DEFAULT_MAX_PIXEL_ERROR,
};

use crate::mesh::{tessellate, Mesh};

/// A complete, validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Render target size and format.
    pub output: Output,
    /// The camera.
    pub camera: Camera,
    /// Ambient light `La`, linear RGB.
    pub ambient: Vec3,
    /// HDR to display mapping.
    pub tone_map: ToneMap,
    /// Light sources.
    pub lights: Vec<Light>,
    /// Materials, with unique names.
    pub materials: Vec<Material>,
    /// Objects to draw; each refers to a material by index.
    pub objects: Vec<Object>,
    /// A point light is skipped for an object when its strongest colour
    /// component, attenuated to the object's bounding sphere, is below this.
    pub light_cutoff: f32,
    /// The sun and atmosphere (`[sun]`, `[atmosphere]`), drawn by the
    /// atmosphere pass; `None` without them.
    pub sky: Option<Sky>,
    /// The one light that casts shadows, if any.
    pub shadow_light: Option<ShadowLight>,
    /// What was wrong with the models' assets (MTL libraries, textures)
    /// and what is drawn instead; see [`Scene::strict`].
    pub warnings: Vec<SceneWarning>,
    /// Every file the scene was read from: the scene file (when loaded
    /// with [`Scene::load`]), OBJ models, their MTL libraries, textures,
    /// normal and height maps. Empty for scenes built in code. A command
    /// must never write over one of them (see [`crate::safe_files::protect_inputs`]).
    pub files: Vec<std::path::PathBuf>,
}

/// The longest scene file read: far above any hand-written scene, and a
/// bound on what an endless input (`/dev/zero`) can make the reader hold.
pub const MAX_SCENE_FILE_BYTES: u64 = 64 << 20;

/// An [`AssetWarning`] of one of the scene's objects.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneWarning {
    /// The scene file (or name given to [`Scene::from_toml`]).
    pub file: String,
    /// The field that names the model, e.g. `objects[0].shape.path`.
    pub field: String,
    /// The problem and its fallback.
    pub warning: AssetWarning,
}

impl std::fmt::Display for SceneWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.warning.fmt(f)
    }
}

impl SceneWarning {
    /// The warning as the error `--strict` makes of it.
    pub fn to_error(&self) -> SceneError {
        SceneError::Invalid {
            file: self.file.clone(),
            field: self.field.clone(),
            reason: self.warning.problem.clone(),
        }
    }
}

/// Render target description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// Width in pixels, `1..=16384`.
    pub width: u32,
    /// Height in pixels, `1..=16384`.
    pub height: u32,
    /// Format of the HDR colour target.
    pub hdr_format: HdrFormat,
    /// How base-colour textures are filtered.
    pub texture_filter: TextureFilter,
    /// Forward or deferred lighting.
    pub lighting: Lighting,
    /// Whether opaque surfaces are first drawn depth-only, so the colour
    /// pass shades each visible pixel once (`render::plan::depth_prepass`).
    pub depth_prepass: DepthPrepass,
    /// Draw one surface attribute instead of the lit image.
    pub debug_view: Option<DebugView>,
    /// Lights the frame never changes as specialization constants rather
    /// than uniform reads (`render::static_lights`); off only to measure
    /// what that saves.
    pub static_lights: bool,
    /// Pixels a `tessellation = "auto"` object's triangles may stray from
    /// its exact surface; finite and > 0.
    pub max_pixel_error: f32,
    /// The shadow map's width and height in texels, in
    /// `MIN_SHADOW_MAP..=MAX_SHADOW_MAP` (used only when a light casts
    /// shadows).
    pub shadow_map: u32,
    /// How the shadow map is filtered.
    pub shadow_filter: ShadowFilter,
    /// How many shadow maps split the view's depth.
    pub shadow_cascades: ShadowCascades,
}

/// The most shadow cascades.
pub const MAX_SHADOW_CASCADES: u32 = 4;

/// How many shadow maps (cascades) split the view's depth for the
/// shadow-casting light (`[output] shadow_cascades`): each covers a range
/// of distances from the camera, nearer ones finer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowCascades {
    /// From how deep the view is: one while the farthest object in view is
    /// within 30 times the nearest's distance, one more for each further
    /// factor of ten, at most [`MAX_SHADOW_CASCADES`] (`"auto"`, the
    /// default).
    Auto,
    /// This many, `1..=MAX_SHADOW_CASCADES`.
    Count(u32),
}

impl ShadowCascades {
    /// Parses `auto` or a count in `1..=MAX_SHADOW_CASCADES`.
    pub fn parse(value: &str) -> Result<ShadowCascades, String> {
        if value == "auto" {
            return Ok(ShadowCascades::Auto);
        }
        match value.parse::<u32>() {
            Ok(n) if (1..=MAX_SHADOW_CASCADES).contains(&n) => Ok(ShadowCascades::Count(n)),
            _ => Err(format!(
                "expected \"auto\" or a count from 1 to {MAX_SHADOW_CASCADES}, got \"{value}\""
            )),
        }
    }

    /// The setting as the scene file and the knob write it.
    pub fn name(self) -> String {
        match self {
            ShadowCascades::Auto => "auto".into(),
            ShadowCascades::Count(n) => n.to_string(),
        }
    }
}

/// Why a scene with a shadow-casting light cannot be lit deferred.
pub const SHADOWS_NEED_FORWARD: &str =
    "shadows need lighting = \"forward\" (the deferred lighting pass does not read the shadow map)";

/// The smallest `[output] shadow_map`.
pub const MIN_SHADOW_MAP: u32 = 512;
/// The largest `[output] shadow_map`.
pub const MAX_SHADOW_MAP: u32 = 8192;

/// A shadow map side in `MIN_SHADOW_MAP..=MAX_SHADOW_MAP`, or why not (the
/// scene file's field and the knob both check with it).
pub fn shadow_map_side(side: u32) -> Result<u32, String> {
    if (MIN_SHADOW_MAP..=MAX_SHADOW_MAP).contains(&side) {
        Ok(side)
    } else {
        Err(format!(
            "must be between {MIN_SHADOW_MAP} and {MAX_SHADOW_MAP} texels, got {side}"
        ))
    }
}

/// How a shadow map is filtered (`[output] shadow_filter`): depth
/// comparisons at the nearest texel and its neighbours, averaged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShadowFilter {
    /// One comparison at the nearest texel: hard, stair-stepped edges
    /// (`"none"`).
    None,
    /// 3x3 comparisons (`"pcf3"`, the default).
    Pcf3,
    /// 5x5 comparisons (`"pcf5"`).
    Pcf5,
}

impl ShadowFilter {
    /// Texels across the filter's square (1, 3 or 5).
    pub fn taps(self) -> u32 {
        match self {
            ShadowFilter::None => 1,
            ShadowFilter::Pcf3 => 3,
            ShadowFilter::Pcf5 => 5,
        }
    }
}

/// The light whose shadows the frame draws (`shadows = true` on a light,
/// or on `[sun]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowLight {
    /// `Scene::lights[i]`.
    Light(usize),
    /// The atmosphere's sun.
    Sun,
}

/// A surface attribute drawn instead of the lit image (`[output]
/// debug_view`, `render --debug-view`): the HDR image holds the attribute
/// itself (world space and signed for vectors, background 0); the PNG shows
/// 0.5 + 0.5 v.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum DebugView {
    /// The shading normal, after normal mapping, unit length.
    Normals = 1,
    /// The tangent T (along increasing u), orthogonal to the normal.
    Tangents = 2,
    /// The bitangent B = sign * cross(N, T) (along increasing v).
    Bitangents = 3,
    /// Texture coordinates (u, v, 0).
    Uv = 4,
    /// The diffuse albedo kd times the base-colour texture.
    Albedo = 5,
}

/// Where lights are evaluated (`[output] lighting`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Lighting {
    /// Each object's fragments loop over the lights that reach the object
    /// (`"forward"`, the default).
    Forward,
    /// Opaque Phong surfaces write a G-buffer; a full-screen subpass loops
    /// over the lights that reach each screen tile (`"deferred"`).
    Deferred,
}

/// The depth pre-pass setting (`[output] depth_prepass`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DepthPrepass {
    /// Opaque surfaces are shaded as they are drawn, hidden ones included
    /// (`"off"`).
    Off,
    /// Opaque surfaces are drawn depth-only first, then shaded where their
    /// depth equals the nearest (`"on"`).
    On,
    /// On where the plan estimates that the shading it saves outweighs the
    /// second drawing of the geometry (`"auto"`, the default).
    Auto,
}

/// Texture filtering (`[output] texture_filter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TextureFilter {
    /// Nearest texel, nearest mip level (`"nearest"`).
    Nearest,
    /// Bilinear within the nearest mip level (`"bilinear"`).
    Bilinear,
    /// Bilinear within and linear between mip levels (`"trilinear"`, the default).
    Trilinear,
}

/// The `[output]` section's defaults, for every field the file leaves out.
impl Default for Output {
    fn default() -> Self {
        Output {
            width: 640,
            height: 360,
            hdr_format: HdrFormat::Rgba16F,
            texture_filter: TextureFilter::Trilinear,
            lighting: Lighting::Forward,
            depth_prepass: DepthPrepass::Auto,
            debug_view: None,
            static_lights: true,
            max_pixel_error: DEFAULT_MAX_PIXEL_ERROR,
            shadow_map: 2048,
            shadow_filter: ShadowFilter::Pcf3,
            shadow_cascades: ShadowCascades::Auto,
        }
    }
}

impl Output {
    /// `width / height`, the aspect ratio for [`Camera::projection`].
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }
}

/// Format of the HDR colour target.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HdrFormat {
    /// `R16G16B16A16_SFLOAT` (`"rgba16f"`).
    Rgba16F,
    /// `R32G32B32A32_SFLOAT` (`"rgba32f"`).
    Rgba32F,
}

/// Tone mapping from HDR to display values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    /// The curve.
    pub operator: ToneMapOperator,
    /// Linear scale applied before the curve.
    pub exposure: Exposure,
    /// Bloom mixed into the HDR image before exposure and the curve
    /// (`[tone_map] bloom = { ... }`); `None`: no bloom pass.
    pub bloom: Option<Bloom>,
}

/// Physically based bloom: a chain of half-size levels of the HDR image,
/// blurred down and back up, mixed in as
/// `(1 - intensity) * hdr + intensity * bloom`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bloom {
    /// The fraction of the blurred image in the mix: finite, in (0, 1].
    pub intensity: f32,
    /// Levels of the chain asked for, 1..=[`Bloom::MAX_LEVELS`]; the frame
    /// uses fewer when the smallest would be under 1x1 texel.
    pub levels: u32,
    /// The width of the box that blurs each level up, in texels of it:
    /// finite, in (0, [`Bloom::MAX_RADIUS`]].
    pub radius: f32,
}

impl Default for Bloom {
    fn default() -> Self {
        Bloom {
            intensity: 0.04,
            levels: 6,
            radius: 1.0,
        }
    }
}

impl Bloom {
    /// Most levels a chain may ask for.
    pub const MAX_LEVELS: u32 = 10;
    /// Largest upsampling box width, in texels.
    pub const MAX_RADIUS: f64 = 4.0;

    /// An intensity from a number (the scene field and the knob share the
    /// check); the error is the reason.
    pub fn intensity_from(x: f64) -> Result<f32, String> {
        if !x.is_finite() || x <= 0.0 || x > 1.0 {
            return Err(format!(
                "must be a finite number greater than 0 and at most 1 (the fraction of the blurred image mixed in), got {x}"
            ));
        }
        Ok(x as f32)
    }

    /// A level count from a number: 1..=[`Bloom::MAX_LEVELS`].
    pub fn levels_from(x: i64) -> Result<u32, String> {
        if !(1..=i64::from(Bloom::MAX_LEVELS)).contains(&x) {
            return Err(format!("must be in 1..={}, got {x}", Bloom::MAX_LEVELS));
        }
        Ok(x as u32)
    }

    /// A radius from a number: finite, in (0, [`Bloom::MAX_RADIUS`]].
    pub fn radius_from(x: f64) -> Result<f32, String> {
        if !x.is_finite() || x <= 0.0 || x > Bloom::MAX_RADIUS {
            return Err(format!(
                "must be greater than 0 and at most {} texels, got {x}",
                Bloom::MAX_RADIUS
            ));
        }
        Ok(x as f32)
    }

    /// The levels a `width`×`height` frame's chain has: the ones asked for,
    /// but no more than leave the smallest level at least 1x1 texel (level
    /// k is `width >> (k + 2)` by `height >> (k + 2)`); 0 when the frame is
    /// under 4 pixels in either direction.
    pub fn chain_levels(&self, width: u32, height: u32) -> u32 {
        let smaller = width.min(height);
        let fit = if smaller == 0 {
            0
        } else {
            smaller.ilog2().saturating_sub(1)
        };
        self.levels.min(fit)
    }

    /// The knob syntax: `on` for the defaults, else the intensity.
    pub fn name(bloom: Option<Bloom>) -> String {
        match bloom {
            None => "off".into(),
            Some(b) if b == Bloom::default() => "on".into(),
            Some(b) => b.intensity.to_string(),
        }
    }

    /// Parses the knob: `off`, `on` (the defaults) or an intensity, which
    /// keeps `current`'s levels and radius.
    pub fn parse(value: &str, current: Option<Bloom>) -> Result<Option<Bloom>, String> {
        match value {
            "off" => Ok(None),
            "on" => Ok(Some(current.unwrap_or_default())),
            _ => {
                let x: f64 = value.parse().map_err(|_| {
                    format!("expected off, on or an intensity in (0, 1], got '{value}'")
                })?;
                Ok(Some(Bloom {
                    intensity: Bloom::intensity_from(x)?,
                    ..current.unwrap_or_default()
                }))
            }
        }
    }
}

/// The linear scale the tone map applies before its curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    /// This factor, finite and > 0.
    Fixed(f32),
    /// Measured from each frame's HDR image by the exposure pass: 0.18
    /// (middle grey) over the log-average luminance.
    Auto,
}

impl Exposure {
    /// The fixed factor, or `None` for [`Exposure::Auto`].
    pub fn fixed(self) -> Option<f32> {
        match self {
            Exposure::Fixed(x) => Some(x),
            Exposure::Auto => None,
        }
    }

    /// Parses `auto` or a finite number > 0 (the scene field and the knob
    /// share it); the error is the reason.
    pub fn parse(value: &str) -> Result<Exposure, String> {
        if value == "auto" {
            return Ok(Exposure::Auto);
        }
        let x: f64 = value
            .parse()
            .map_err(|_| format!("expected \"auto\" or a number > 0, got '{value}'"))?;
        Exposure::from_number(x)
    }

    /// A fixed exposure from a number: finite, > 0 and within f32's range.
    pub fn from_number(x: f64) -> Result<Exposure, String> {
        let narrow = x as f32;
        if !x.is_finite() || x <= 0.0 || narrow == 0.0 || !narrow.is_finite() {
            return Err(format!("must be greater than 0 and finite, got {x}"));
        }
        Ok(Exposure::Fixed(narrow))
    }

    /// The scene-file syntax: `auto` or the number.
    pub fn name(self) -> String {
        match self {
            Exposure::Fixed(x) => x.to_string(),
            Exposure::Auto => "auto".into(),
        }
    }
}

/// Tone-mapping curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ToneMapOperator {
    /// `c / (1 + c)`.
    Reinhard,
    /// The ACES filmic approximation.
    Aces,
    /// No curve: exposure, then clamped to [0, 1]. Without `--hdr`, with
    /// an `rgba32f` HDR format, exposure 1, forward lighting, no
    /// transparent object and no atmosphere, the scene is then drawn
    /// straight into the 8-bit output, with no HDR attachment and no
    /// tone-map subpass; the image is the same as through them.
    None,
}

impl Scene {
    /// Reads and validates the scene file at `path`. Textures are resolved
    /// relative to the file's folder.
    ///
    /// # Errors
    ///
    /// [`SceneError::Io`] if the file cannot be read, otherwise as
    /// [`Scene::from_toml`].
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        use crate::safe_files::{read_text, TextReadError};
        let text = read_text(path, MAX_SCENE_FILE_BYTES).map_err(|e| match e {
            TextReadError::Io(reason) => SceneError::Io {
                file: file.clone(),
                reason,
            },
            TextReadError::TooLong(_) => SceneError::Parse {
                file: file.clone(),
                message: format!(
                    "{e}; a scene file is text of a few kilobytes, and models go in OBJ \
                     files it names"
                ),
            },
            TextReadError::NotUtf8 { .. } => SceneError::Parse {
                file: file.clone(),
                message: format!("{e} (save the file as UTF-8)"),
            },
        })?;
        let base_dir = path.parent().unwrap_or_else(|| Path::new(""));
        let mut scene = Scene::from_toml(&text, &file, base_dir)?;
        scene.files.insert(0, path.to_path_buf());
        Ok(scene)
    }

    /// Parses and validates a scene from TOML text. `file` is only used in
    /// messages; `base_dir` is the folder textures are resolved against.
    ///
    /// Format (every table rejects unknown keys; defaults in brackets):
    ///
    /// ```toml
    /// ambient = [0.03, 0.03, 0.03]        # [0, 0, 0]; >= 0
    /// light_cutoff = 0.001                 # [0.001]; >= 0, 0 disables culling
    /// [output]                             # optional table
    /// width = 640                          # [640]; 1..=16384
    /// height = 360                         # [360]; 1..=16384
    /// hdr_format = "rgba16f"               # ["rgba16f"] | "rgba32f"
    /// texture_filter = "trilinear"         # ["trilinear"] | "bilinear" | "nearest"
    /// max_pixel_error = 0.5                # [0.5]; > 0, pixels, for tessellation = "auto"
    /// shadow_map = 2048                    # [2048]; 512..=8192 texels, when a light casts shadows
    /// shadow_filter = "pcf3"               # ["pcf3"] | "pcf5" | "none"
    /// shadow_cascades = "auto"             # ["auto"] | 1..=4 shadow maps split along the view
    /// [camera]                             # required
    /// eye = [0.0, 2.0, 6.0]                # required
    /// look_at = [0.0, 0.0, 0.0]            # required, != eye
    /// up = [0.0, 1.0, 0.0]                 # [0, 1, 0]; not parallel to look_at - eye
    /// fov_y = 45.0                         # [45]; degrees, in (0, 180)
    /// near = 0.1                           # [0.1]; > 0
    /// far = 100.0                          # > near; omit for an infinite far plane
    /// [tone_map]                           # optional table
    /// operator = "reinhard"                # ["reinhard"] | "aces"
    /// exposure = 1.0                       # [1]; > 0
    /// [[lights]]
    /// type = "point"
    /// position = [2.0, 3.0, 2.0]           # required
    /// color = [1.0, 0.9, 0.8]              # [1, 1, 1]; >= 0
    /// intensity = 20.0                     # [1]; >= 0, multiplies color
    /// attenuation = [1.0, 0.0, 1.0]        # [1, 0, 1]; constant, linear, quadratic; >= 0, not all 0
    /// [[lights]]
    /// type = "directional"
    /// direction = [-1.0, -1.0, -0.5]       # required, the way the light travels
    /// color = [0.3, 0.3, 0.3]              # [1, 1, 1]
    /// intensity = 1.0                      # [1]
    /// shadows = false                      # [false]; a shadow map for this light (one light at most)
    /// [[materials]]
    /// name = "red"                         # required, unique, not empty
    /// kd = [0.8, 0.1, 0.1]                 # required; >= 0
    /// ka = [0.8, 0.1, 0.1]                 # [= kd]; >= 0
    /// ks = [0.5, 0.5, 0.5]                 # [0, 0, 0]; >= 0
    /// shininess = 32.0                     # [32]; > 0
    /// texture = "../textures/checker.png"  # optional, relative to the scene file; must exist
    /// opacity = 1.0                        # [1]; in [0, 1]
    /// shading = "phong"                    # ["phong"] | "gouraud" | "toon"
    /// normal_map = "bumps.png"             # optional tangent-space normal map, relative to the scene file
    /// normal_map_green = "up"              # ["up"] | "down"
    /// specular_map = "shine.png"           # optional, multiplies ks; sRGB, relative to the scene file
    /// two_sided = false                    # [false]; both sides of the faces drawn
    /// [[objects]]
    /// name = "ball"                        # required, not empty
    /// material = "red"                     # required, a material name
    /// shape = { type = "sphere", radius = 1.0 }   # see below
    /// tessellation = [64, 32]              # [64, 32]; u and v segments, each 3..=4096, or "auto"
    /// translate = [0.0, 1.0, 0.0]          # [0, 0, 0]
    /// rotate = { axis = [0.0, 1.0, 0.0], degrees = 30.0 }  # optional; axis not zero
    /// scale = [1.0, 1.0, 1.0]              # [1, 1, 1]; every component > 0
    /// two_sided = false                    # [false]; both sides drawn, whatever the material
    /// casts_shadows = true                 # [true]; drawn into the shadow map
    /// ```
    ///
    /// Shapes (all lengths > 0): `sphere` (`radius`), `torus`
    /// (`major_radius`, `minor_radius`), `plane` (`width`, `depth`; XZ
    /// plane, normal +Y), `cylinder` (`radius`, `height`; open, axis Y),
    /// `flag` (`width`, `height`, `amplitude`, `frequency` in radians over
    /// the width, optional `phase`, default 0), `obj` (`path` to an OBJ
    /// model, relative to the scene file; the object's `material` becomes
    /// optional and it takes `smoothing`, `crease_angle` and
    /// `weld_tolerance`, see `crate::mesh::obj`). Every number must be finite.
    /// A model's missing or unreadable MTL library or texture does not fail
    /// the load: it is drawn with the default material or a placeholder
    /// texture, and recorded in [`Scene::warnings`] (`docs/models-corpus.md`).
    ///
    /// # Errors
    ///
    /// [`SceneError::Parse`] for TOML syntax errors, unknown keys, missing
    /// required keys and wrong types (with the `toml` crate's line/column
    /// message); [`SceneError::Invalid`] for values that break the rules
    /// above, naming the field path (e.g. `objects[2].rotate.axis`).
    pub fn from_toml(text: &str, file: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        // Parsing describes the scene (every field checked, no model file
        // opened); the OBJ models it names are read after.
        let check = value_checks::Check { file, base_dir };
        let description = check.parse(text)?;
        check.load_models(description)
    }

    /// A scene with nothing in it: only an output size and a tone map (for
    /// tone-mapping an existing HDR image).
    pub fn empty(tone_map: ToneMap, width: u32, height: u32) -> Scene {
        Scene {
            output: Output {
                width,
                height,
                hdr_format: HdrFormat::Rgba32F,
                ..Output::default()
            },
            camera: Camera {
                eye: DVec3::Z,
                look_at: DVec3::ZERO,
                up: Vec3::Y,
                fov_y_degrees: 45.0,
                near: 0.1,
                far: None,
            },
            ambient: Vec3::ZERO,
            tone_map,
            lights: Vec::new(),
            materials: Vec::new(),
            objects: Vec::new(),
            light_cutoff: DEFAULT_LIGHT_CUTOFF,
            sky: None,
            shadow_light: None,
            warnings: Vec::new(),
            files: Vec::new(),
        }
    }

    /// Fails with the first asset warning as an error (`--strict`: a run
    /// that must not draw placeholders or default materials).
    pub fn strict(&self) -> Result<(), SceneError> {
        match self.warnings.first() {
            Some(w) => Err(w.to_error()),
            None => Ok(()),
        }
    }

    /// Warns (once per material and map) about each map that a drawn
    /// material lit per vertex cannot use (a kind that is
    /// `per_pixel_only`, such as a normal or height map): Gouraud lights
    /// the vertices, and a map varies within a triangle, so the frame plan
    /// leaves the map out (never loaded, no shader reads it). `file` names
    /// where the setting came from (the scene file, or the knob that set
    /// the shading).
    pub fn warn_unused_maps(&mut self, file: &str) {
        for (i, m) in self.materials.iter().enumerate() {
            let drawn = self.objects.iter().any(|o| o.material == i);
            if m.shading != ShadingModel::Gouraud || !drawn {
                continue;
            }
            for (kind, source) in m.maps.iter() {
                let Some(path) = source.path().filter(|_| kind.info().per_pixel_only) else {
                    continue;
                };
                let name = if source.height_scale.is_some() {
                    "height_map"
                } else {
                    kind.info().field
                };
                let field = format!("materials[{i}].{name}");
                let problem = format!(
                    "{file}: {field}: material \"{}\" has shading = \"gouraud\", which lights \
                     per vertex and cannot use a per-pixel map ({})",
                    m.name,
                    path.display()
                );
                if self.warnings.iter().any(|w| w.warning.problem == problem) {
                    continue;
                }
                self.warnings.push(SceneWarning {
                    file: file.to_string(),
                    field,
                    warning: AssetWarning {
                        problem,
                        fallback: "the map is not used (shading = \"phong\" or \"toon\" shows it)"
                            .to_string(),
                    },
                });
            }
        }
    }

    /// Prints each asset warning to stderr, once, as `warning: ...`.
    pub fn print_warnings(&self) {
        for w in &self.warnings {
            eprintln!("warning: {w}");
        }
    }

    /// Overrides the output size (from the command line), with the same
    /// limits as the scene file's `output.width` / `output.height`.
    pub fn set_output_size(
        &mut self,
        width: Option<u32>,
        height: Option<u32>,
    ) -> Result<(), SceneError> {
        for (field, value, target) in [
            ("output.width", width, &mut self.output.width),
            ("output.height", height, &mut self.output.height),
        ] {
            if let Some(v) = value {
                if v == 0 || v > MAX_OUTPUT_SIZE {
                    return Err(SceneError::Invalid {
                        file: "command line".into(),
                        field: field.into(),
                        reason: format!("{v} is outside 1..={MAX_OUTPUT_SIZE}"),
                    });
                }
                *target = v;
            }
        }
        Ok(())
    }

    /// The built-in default scene (`assets/scenes/default.toml`).
    pub fn default_scene() -> Scene {
        let base_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
        Scene::from_toml(
            include_str!("../../assets/scenes/default.toml"),
            "assets/scenes/default.toml",
            &base_dir,
        )
        // The file is compiled in and a test loads it, so failure here is a
        // build defect, not bad user input.
        .expect("built-in default scene is valid")
    }

    /// Tessellates object `index` in object space. An index out of range
    /// gives an empty mesh.
    pub fn object_mesh(&self, index: usize) -> Mesh {
        let Some(object) = self.objects.get(index) else {
            return Mesh::default();
        };
        if let Shape::Mesh { mesh } = &object.shape {
            // Loaded (and smoothed) once with the scene; this is a copy.
            return mesh.as_ref().clone();
        }
        match object.shape.surface() {
            Some(surface) => {
                let (u, v) = self.object_tessellation(index);
                tessellate(surface.as_ref(), u, v)
            }
            None => Mesh::default(),
        }
    }

    /// For every object, the first object whose mesh is the same: the same
    /// parametric shape and tessellation (as built: an auto object's chosen
    /// grid, [`Scene::tessellations`]), or the same loaded mesh. The
    /// renderer builds and uploads each distinct mesh once and draws every
    /// object that shares it from that copy.
    pub fn mesh_sources(&self) -> Vec<usize> {
        let grids = self.tessellations();
        let same = |a: usize, b: usize| match (&self.objects[a].shape, &self.objects[b].shape) {
            // The same loaded model (its one copy), not a deep comparison.
            (Shape::Mesh { mesh: x }, Shape::Mesh { mesh: y }) => std::sync::Arc::ptr_eq(x, y),
            (Shape::Mesh { .. }, _) | (_, Shape::Mesh { .. }) => false,
            (x, y) => x == y && grids[a] == grids[b],
        };
        let mut distinct: Vec<usize> = Vec::new();
        (0..self.objects.len())
            .map(|i| match distinct.iter().find(|&&d| same(d, i)) {
                Some(&d) => d,
                None => {
                    distinct.push(i);
                    i
                }
            })
            .collect()
    }

    /// The triangles the scene draws, every object's, each distinct mesh
    /// built once ([`Scene::mesh_sources`]).
    pub fn triangle_count(&self) -> u64 {
        let mut per_object: Vec<u64> = Vec::with_capacity(self.objects.len());
        for (i, source) in self.mesh_sources().into_iter().enumerate() {
            let triangles = if source < i {
                per_object[source]
            } else {
                self.object_mesh(i).triangle_count() as u64
            };
            per_object.push(triangles);
        }
        per_object.iter().sum()
    }

    /// World-space bounding sphere `(centre, radius)` of object `index`: its
    /// mesh's bounding sphere moved by the object transform, the radius
    /// scaled by the largest scale component. `None` if out of range.
    ///
    /// This tessellates the object; the renderer builds each mesh once
    /// (`render::SceneGeometry`) and uses [`Scene::world_bounds`].
    pub fn object_bounds(&self, index: usize) -> Option<(DVec3, f32)> {
        self.objects.get(index)?;
        Some(self.world_bounds(index, &self.object_mesh(index)))
    }

    /// The world-space bounding sphere of object `index` given its mesh in
    /// object space. Panics if `index` is out of range.
    pub fn world_bounds(&self, index: usize, mesh: &Mesh) -> (DVec3, f32) {
        let (centre, radius) = mesh.bounding_sphere();
        let transform = &self.objects[index].transform;
        (
            transform.matrix_f64().transform_point3(centre.as_dvec3()),
            radius * transform.max_scale(),
        )
    }

    /// Indices into [`Scene::lights`] of the lights that can noticeably light
    /// object `object`: every directional light, and every point light whose
    /// strongest colour component times `1 / (c + l d + q d^2)` is at least
    /// [`Scene::light_cutoff`], with `d` the distance from the light to the
    /// object's world-space bounding sphere (0 inside it). An object index
    /// out of range gives an empty list.
    pub fn lights_reaching(&self, object: usize) -> Vec<usize> {
        match self.object_bounds(object) {
            Some((centre, radius)) => self.lights_reaching_sphere(centre, radius),
            None => Vec::new(),
        }
    }

    /// [`Scene::lights_reaching`] for the sphere `(centre, radius)`.
    pub fn lights_reaching_sphere(&self, centre: DVec3, radius: f32) -> Vec<usize> {
        self.lights
            .iter()
            .enumerate()
            .filter(|(_, light)| match light {
                Light::Directional { .. } => true,
                Light::Point { position, .. } => {
                    let distance = (position.distance(centre) as f32 - radius).max(0.0);
                    // Written as "not below" so that an infinite strength
                    // (c = 0 at d = 0) counts as reaching.
                    light.strength_at(distance) >= self.light_cutoff
                }
            })
            .map(|(i, _)| i)
            .collect()
    }
}

#[cfg(test)]
mod tests;
