//! Blinn-Phong [`Material`]s and the [`ShadingModel`] that selects where
//! lighting is evaluated.

use std::path::PathBuf;

use glam::Vec3;
use serde::Deserialize;

/// Where and how lighting is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShadingModel {
    /// Per fragment.
    Phong,
    /// Per vertex, interpolated.
    Gouraud,
    /// Per fragment, quantised into bands.
    Toon,
}

/// A surface material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Unique name that objects refer to.
    pub name: String,
    /// Ambient reflectance (multiplies the scene's ambient light), >= 0.
    pub ka: Vec3,
    /// Diffuse reflectance, >= 0.
    pub kd: Vec3,
    /// Specular reflectance, >= 0.
    pub ks: Vec3,
    /// Blinn-Phong exponent, > 0 (0 is rejected because `pow(0, 0)` is
    /// undefined in GLSL).
    pub shininess: f32,
    /// Base-colour texture, resolved relative to the scene file's folder;
    /// the file existed when the scene was loaded.
    pub texture: Option<PathBuf>,
    /// Opacity in `[0, 1]`; 1 is opaque.
    pub opacity: f32,
    /// Tangent-space normal map (read as linear, not sRGB), resolved like
    /// `texture`. T follows increasing u, B increasing v, N outward; a texel
    /// stores `0.5 + 0.5 * c`.
    pub normal_map: Option<PathBuf>,
    /// True when the map's green channel points down the image (`-v`,
    /// DirectX style, `normal_map_green = "down"`).
    pub normal_map_green_down: bool,
    /// When set, `normal_map` is a height map (`height_map`) turned into a
    /// normal map when the scene is rendered, with this `height_scale`
    /// (texel widths spanned by the full height range; see
    /// `crate::mesh::height`).
    pub height_scale: Option<f32>,
    /// Shading model.
    pub shading: ShadingModel,
}

impl Material {
    /// True when the material needs blending (opacity below 1).
    pub fn is_transparent(&self) -> bool {
        self.opacity < 1.0
    }
}
