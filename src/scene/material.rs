//! Blinn-Phong [`Material`]s and the [`ShadingModel`] that selects where
//! lighting is evaluated.

use std::path::{Path, PathBuf};

use super::material_maps::{MapKind, MapSource, MaterialMaps};

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
    /// Its maps (base colour, normal map, ...; see
    /// [`super::material_maps`]), each a file resolved relative to the
    /// scene file's folder (which existed when the scene was loaded), or,
    /// for a model's base colour that is missing or unreadable, the
    /// placeholder.
    pub maps: MaterialMaps,
    /// Opacity in `[0, 1]`; 1 is opaque.
    pub opacity: f32,
    /// Shading model.
    pub shading: ShadingModel,
    /// Both sides of every face are drawn (back faces are not culled) and
    /// a face seen from behind is shaded with its normal reversed, so the
    /// back of an open sheet is lit as its other side.
    pub two_sided: bool,
}

/// The image of a map: a file, or the placeholder.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Texture {
    /// An image file (PNG or JPEG, recognised by content).
    File(PathBuf),
    /// The placeholder for a texture that could not be used: a magenta and
    /// black checker ([`PLACEHOLDER_TEXTURE`]), unmistakable on any model.
    Placeholder,
}

impl Texture {
    /// The file, unless this is the placeholder.
    pub fn file(&self) -> Option<&Path> {
        match self {
            Texture::File(path) => Some(path),
            Texture::Placeholder => None,
        }
    }
}

/// The placeholder texture: side in texels, and squares per side.
pub const PLACEHOLDER_TEXTURE: (u32, u32) = (64, 8);

/// The RGBA8 (sRGB) texels of [`Texture::Placeholder`], top row first:
/// magenta (255, 0, 255) and black squares.
pub fn placeholder_texels() -> Vec<u8> {
    let (side, squares) = PLACEHOLDER_TEXTURE;
    let cell = side / squares;
    (0..side * side)
        .flat_map(|i| {
            let (x, y) = (i % side, i / side);
            if (x / cell + y / cell) % 2 == 0 {
                [255, 0, 255, 255]
            } else {
                [0, 0, 0, 255]
            }
        })
        .collect()
}

impl Material {
    /// True when the material needs blending (opacity below 1).
    pub fn is_transparent(&self) -> bool {
        self.opacity < 1.0
    }

    /// Its map of `kind`, if it has one.
    pub fn map(&self, kind: MapKind) -> Option<&MapSource> {
        self.maps.get(kind)
    }
}
