//! Material maps as one table: every kind of image a material can carry
//! (base colour, normal map, ...) is one row of [`MAP_KINDS`], which says
//! where it comes from (scene-file field, MTL statements), how its texels
//! are stored (colour space, 16-bit), where the shaders find it
//! (descriptor binding) and how a pipeline selects it (shader feature or a
//! bit of a specialization constant), what vertex data it needs, what a
//! model's missing file becomes, and how the CPU reference applies it.
//!
//! The loaders, the draw list, the scene resources, the preflight memory
//! estimate, the surface pass, the CPU reference and the viewer's knobs
//! iterate over the table. To add a kind: a [`MapKind`] variant and its
//! row, its field in [`material_file_with_maps`], its binding (and bit)
//! in `glsl/interface.toml`, and its sampling in `glsl/object.frag`
//! (`docs/scenes.md` has the steps).

use std::path::{Path, PathBuf};

use crate::shader_ids::{
    BASE_COLOR_BINDING, NORMAL_MAP_BINDING, SPECULAR_MAP_BINDING, SPECULAR_MAP_BIT,
};
use crate::shaders::{ObjectFragFeatures, ObjectVertFeatures};
use crate::vk::Format;

use super::material::Texture;

/// A kind of material map, in table order (its index in [`MAP_KINDS`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MapKind {
    /// The base colour: multiplies `kd` and `ka`, and its alpha the
    /// opacity.
    BaseColor,
    /// A tangent-space normal map (or a height map converted to one).
    Normal,
    /// A specular map: multiplies `ks`.
    Specular,
}

/// How many kinds [`MAP_KINDS`] has.
pub const MAP_KIND_COUNT: usize = 3;

/// How a map's texels are decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// Colours, stored sRGB-encoded and decoded to linear when sampled.
    Srgb,
    /// Values read as stored (vectors, factors).
    Linear,
}

/// How an object pipeline selects the code that reads a map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    /// A shader feature (a compiled variant of `object.vert` and
    /// `object.frag`, the flag of each): for maps that change the vertex
    /// interface or much of the shader.
    Feature(ObjectVertFeatures, ObjectFragFeatures),
    /// This bit of the specialization constant `SPEC_MATERIAL_MAPS`: the
    /// driver folds the dead branch away at pipeline creation, and no
    /// variant is compiled for it. Such a map is read in the variants that
    /// have the material set and UVs; a material with none of the
    /// feature-selected maps takes the first one's variant (the base
    /// colour's), whose slot then holds its 1x1 default.
    Constant(u32),
}

/// How the CPU reference (`render::cpu_renderer`) treats a map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceUse {
    /// Not modelled: a material with it has no reference (the message
    /// names it with this phrase).
    Unsupported(&'static str),
    /// Sampled at the hit's UV (nearest texel) and multiplied into `ks`.
    ScalesSpecular,
}

/// One kind of map: everything the loaders, renderer and reference need to
/// know about it.
#[derive(Clone, Copy, Debug)]
pub struct MapKindInfo {
    pub kind: MapKind,
    /// Its field in a scene file's `[[materials]]`.
    pub field: &'static str,
    /// The MTL statements that give it, in order of preference.
    pub mtl: &'static [&'static str],
    /// What a warning about a model's map calls it.
    pub mtl_name: &'static str,
    pub color_space: ColorSpace,
    /// Whether a file with 16 bits per channel keeps them on the GPU
    /// (otherwise every file is uploaded at 8 bits). Either way the
    /// preflight counts the file's decoded texels (4 or 8 bytes), their
    /// staging copy and the mip chain.
    pub keeps_sixteen_bit: bool,
    /// Its binding in the material set (`MATERIAL_SET`).
    pub binding: u32,
    pub selection: Selection,
    /// Whether its pipelines read the vertex tangents (all maps read UVs).
    pub needs_tangents: bool,
    /// Whether it varies within a triangle in a way per-vertex (Gouraud)
    /// lighting cannot use: such a material then leaves the map out, with
    /// a warning.
    pub per_pixel_only: bool,
    /// The RGBA8 texel of the 1x1 image in the slot of a material set
    /// without this map (in the map's colour space): the value that
    /// changes nothing, when a variant reads it at all.
    pub empty_slot: [u8; 4],
    /// For a model's map that is missing or unreadable: drawn with the
    /// magenta/black placeholder (true) or left out (false).
    pub placeholder_when_missing: bool,
    /// The warning's "drawn with ... instead" for such a map.
    pub missing_fallback: &'static str,
    pub reference: ReferenceUse,
}

impl MapKindInfo {
    /// The image format a map of this kind is uploaded in: 8 bits per
    /// channel, or `sixteen_bit` for a 16-bit file of a kind that keeps
    /// it.
    pub fn format(&self, sixteen_bit: bool) -> Format {
        match (self.color_space, sixteen_bit && self.keeps_sixteen_bit) {
            (_, true) => Format::R16G16B16A16_UNORM,
            (ColorSpace::Srgb, false) => Format::R8G8B8A8_SRGB,
            (ColorSpace::Linear, false) => Format::R8G8B8A8_UNORM,
        }
    }
}

/// Every map kind, in [`MapKind`] order.
pub const MAP_KINDS: [MapKindInfo; MAP_KIND_COUNT] = [
    MapKindInfo {
        kind: MapKind::BaseColor,
        field: "texture",
        mtl: &["map_Kd"],
        mtl_name: "map_Kd",
        color_space: ColorSpace::Srgb,
        keeps_sixteen_bit: false,
        binding: BASE_COLOR_BINDING,
        selection: Selection::Feature(
            ObjectVertFeatures::BASE_COLOR_TEXTURE,
            ObjectFragFeatures::BASE_COLOR_TEXTURE,
        ),
        needs_tangents: false,
        per_pixel_only: false,
        empty_slot: [255; 4],
        placeholder_when_missing: true,
        missing_fallback: "drawn with a magenta/black checker instead",
        reference: ReferenceUse::Unsupported("a texture"),
    },
    MapKindInfo {
        kind: MapKind::Normal,
        field: "normal_map",
        // `map_Bump` and `bump` arrive as one (the MTL parser merges them).
        mtl: &["map_Bump", "bump", "norm"],
        mtl_name: "normal map",
        // Vectors, not colours: decoding them as sRGB would bend every
        // normal.
        color_space: ColorSpace::Linear,
        // An 8-bit map quantizes directions to about 0.2 degrees, a
        // 16-bit one to 0.001.
        keeps_sixteen_bit: true,
        binding: NORMAL_MAP_BINDING,
        selection: Selection::Feature(
            ObjectVertFeatures::NORMAL_MAP,
            ObjectFragFeatures::NORMAL_MAP,
        ),
        needs_tangents: true,
        per_pixel_only: true,
        empty_slot: [128, 128, 255, 255],
        placeholder_when_missing: false,
        missing_fallback:
            "drawn with the flat normal (0, 0, 1) instead (the surface's own normals)",
        reference: ReferenceUse::Unsupported("a normal map"),
    },
    MapKindInfo {
        kind: MapKind::Specular,
        field: "specular_map",
        mtl: &["map_Ks"],
        mtl_name: "map_Ks",
        // A colour, sRGB-encoded like `map_Kd` (the MTL convention: both
        // scale a colour, `Ks` and `Kd`).
        color_space: ColorSpace::Srgb,
        keeps_sixteen_bit: false,
        binding: SPECULAR_MAP_BINDING,
        // UVs only, no new vertex data: no variant of its own.
        selection: Selection::Constant(SPECULAR_MAP_BIT),
        needs_tangents: false,
        // Gouraud lights the vertices, highlight included.
        per_pixel_only: true,
        empty_slot: [255; 4],
        placeholder_when_missing: false,
        missing_fallback: "drawn with the material's ks alone instead",
        reference: ReferenceUse::ScalesSpecular,
    },
];

impl MapKind {
    /// Every kind, in table order.
    pub fn all() -> impl Iterator<Item = MapKind> {
        MAP_KINDS.iter().map(|info| info.kind)
    }

    /// Its row of [`MAP_KINDS`].
    pub fn info(self) -> &'static MapKindInfo {
        &MAP_KINDS[self as usize]
    }

    /// Its bit in a [`MapMask`].
    fn bit(self) -> u32 {
        1 << self as u32
    }
}

/// Where one material map comes from.
#[derive(Clone, Debug, PartialEq)]
pub struct MapSource {
    /// The image file, or the placeholder for a model's missing one.
    pub texture: Texture,
    /// A normal map whose green channel points down the image (`-v`,
    /// DirectX style, `normal_map_green = "down"`).
    pub green_down: bool,
    /// A height map turned into a normal map when the scene is rendered,
    /// with this scale (texel widths spanned by the full height range; see
    /// `crate::mesh::height`).
    pub height_scale: Option<f32>,
}

impl MapSource {
    /// A map read from `path` as it is.
    pub fn file(path: PathBuf) -> MapSource {
        MapSource {
            texture: Texture::File(path),
            green_down: false,
            height_scale: None,
        }
    }

    /// The placeholder for a model's missing base colour.
    pub fn placeholder() -> MapSource {
        MapSource {
            texture: Texture::Placeholder,
            green_down: false,
            height_scale: None,
        }
    }

    /// The file, unless this is the placeholder.
    pub fn path(&self) -> Option<&Path> {
        self.texture.file()
    }

    /// Whether `other` is uploaded as the same image (the green axis is
    /// the object's, not the image's).
    pub fn same_image(&self, other: &MapSource) -> bool {
        self.texture == other.texture
            && self.height_scale.map(f32::to_bits) == other.height_scale.map(f32::to_bits)
    }
}

/// A material's maps, at most one of each kind.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialMaps([Option<MapSource>; MAP_KIND_COUNT]);

impl MaterialMaps {
    pub fn get(&self, kind: MapKind) -> Option<&MapSource> {
        self.0[kind as usize].as_ref()
    }

    /// Sets (or, with `None`, removes) the map of `kind`.
    pub fn set(&mut self, kind: MapKind, source: Option<MapSource>) {
        self.0[kind as usize] = source;
    }

    /// The maps present, in table order.
    pub fn iter(&self) -> impl Iterator<Item = (MapKind, &MapSource)> {
        MapKind::all().filter_map(|kind| Some((kind, self.get(kind)?)))
    }

    pub fn is_empty(&self) -> bool {
        self.iter().next().is_none()
    }

    /// The files of the maps present (not the placeholder), in table order.
    pub fn files(&self) -> impl Iterator<Item = &Path> {
        self.iter().filter_map(|(_, source)| source.path())
    }
}

/// A set of map kinds (a bit per kind): which maps a pipeline reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct MapMask(u32);

impl MapMask {
    pub fn with(self, kind: MapKind) -> MapMask {
        MapMask(self.0 | kind.bit())
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    pub fn contains(self, kind: MapKind) -> bool {
        self.0 & kind.bit() != 0
    }

    pub fn kinds(self) -> impl Iterator<Item = &'static MapKindInfo> {
        MAP_KINDS
            .iter()
            .filter(move |info| self.contains(info.kind))
    }

    /// Whether a pipeline reads UVs (every map is sampled at them).
    pub fn needs_uvs(self) -> bool {
        self.0 != 0
    }

    /// Whether a pipeline reads the vertex tangents.
    pub fn needs_tangents(self) -> bool {
        self.kinds().any(|info| info.needs_tangents)
    }

    /// The shader features that select these maps: their own, and, for
    /// maps selected by a constant alone, the first feature-selected kind
    /// that needs no more vertex data than UVs (see
    /// [`Selection::Constant`]).
    pub fn shader_features(self) -> (ObjectVertFeatures, ObjectFragFeatures) {
        let feature = |info: &MapKindInfo| match info.selection {
            Selection::Feature(vert, frag) => Some((vert, frag)),
            Selection::Constant(_) => None,
        };
        let mut features: Vec<_> = self.kinds().filter_map(feature).collect();
        if features.is_empty() && self.needs_uvs() {
            features.extend(
                MAP_KINDS
                    .iter()
                    .filter(|info| !info.needs_tangents)
                    .find_map(feature),
            );
        }
        features.into_iter().fold(
            (ObjectVertFeatures::NONE, ObjectFragFeatures::NONE),
            |(v, f), (vert, frag)| (v | vert, f | frag),
        )
    }

    /// The value of `SPEC_MATERIAL_MAPS`: the bits of the maps selected by
    /// the constant.
    pub fn constant(self) -> u32 {
        self.kinds()
            .filter_map(|info| match info.selection {
                Selection::Constant(bit) => Some(bit),
                Selection::Feature(..) => None,
            })
            .fold(0, |bits, bit| bits | bit)
    }
}

/// Declares the scene file's material struct with, after the given
/// fields, one optional file field per map kind (its [`MapKindInfo::field`])
/// and a `map_files` method that takes them out by kind, so that the
/// loader walks the table instead of naming each map.
macro_rules! material_file_with_maps {
    ($(#[$meta:meta])* struct $name:ident { $($(#[$fmeta:meta])* $field:ident : $ty:ty,)* }) => {
        $(#[$meta])*
        struct $name {
            $($(#[$fmeta])* $field: $ty,)*
            texture: Option<PathBuf>,
            normal_map: Option<PathBuf>,
            specular_map: Option<PathBuf>,
        }

        impl $name {
            /// The map fields, by kind, in table order.
            fn map_files(&mut self) -> [(MapKind, Option<PathBuf>); MAP_KIND_COUNT] {
                [
                    (MapKind::BaseColor, self.texture.take()),
                    (MapKind::Normal, self.normal_map.take()),
                    (MapKind::Specular, self.specular_map.take()),
                ]
            }
        }
    };
}
pub(super) use material_file_with_maps;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_in_kind_order_with_distinct_bindings_fields_and_bits() {
        for (i, info) in MAP_KINDS.iter().enumerate() {
            assert_eq!(info.kind as usize, i, "{info:?}");
            // No sRGB format has 16 bits per channel.
            assert!(!(info.keeps_sixteen_bit && info.color_space == ColorSpace::Srgb));
            for other in &MAP_KINDS[..i] {
                assert_ne!(info.binding, other.binding);
                assert_ne!(info.field, other.field);
                assert!(info.mtl.iter().all(|s| !other.mtl.contains(s)));
                if let (Selection::Constant(a), Selection::Constant(b)) =
                    (info.selection, other.selection)
                {
                    assert_eq!(a & b, 0);
                }
            }
        }
    }

    /// Every kind is read from its scene-file field and from the first of
    /// its MTL statements, as a map of that kind and no other.
    const CAMERA: &str = "[camera]\neye = [0, 2, 3]\nlook_at = [0, 0, 0]\n";

    #[test]
    fn every_kind_loads_from_its_field_and_its_mtl_statement() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        image::RgbaImage::from_pixel(2, 2, image::Rgba([128, 128, 255, 255]))
            .save(d.join("map.png"))
            .unwrap();
        std::fs::write(
            d.join("quad.obj"),
            "mtllib quad.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 1 1 0\n\
             vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n",
        )
        .unwrap();
        for info in &MAP_KINDS {
            let only = |material: &crate::scene::Material| {
                let kinds: Vec<MapKind> = material.maps.iter().map(|(k, _)| k).collect();
                assert_eq!(kinds, [info.kind], "{info:?}");
                assert_eq!(
                    material.map(info.kind).and_then(|m| m.path()),
                    Some(d.join("map.png").as_path())
                );
            };
            let toml = format!(
                "{CAMERA}[[materials]]\nname = \"m\"\nkd = [1, 1, 1]\n{} = \"map.png\"\n\
                 [[objects]]\nname = \"o\"\nmaterial = \"m\"\n\
                 shape = {{ type = \"plane\", width = 1, depth = 1 }}\n",
                info.field
            );
            let scene = crate::scene::Scene::from_toml(&toml, "t.toml", d).unwrap();
            only(&scene.materials[0]);
            std::fs::write(
                d.join("quad.mtl"),
                format!("newmtl m\nKd 1 1 1\n{} map.png\n", info.mtl[0]),
            )
            .unwrap();
            let toml = format!(
                "{CAMERA}[[objects]]\nname = \"q\"\n\
                 shape = {{ type = \"obj\", path = \"quad.obj\" }}\n"
            );
            let scene = crate::scene::Scene::from_toml(&toml, "t.toml", d).unwrap();
            assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
            only(&scene.materials[scene.objects[0].material]);
        }
    }

    #[test]
    fn a_constant_selected_map_alone_rides_on_a_variant_with_uvs_only() {
        const BASE_COLOR: (ObjectVertFeatures, ObjectFragFeatures) = (
            ObjectVertFeatures::BASE_COLOR_TEXTURE,
            ObjectFragFeatures::BASE_COLOR_TEXTURE,
        );
        const NORMAL: (ObjectVertFeatures, ObjectFragFeatures) = (
            ObjectVertFeatures::NORMAL_MAP,
            ObjectFragFeatures::NORMAL_MAP,
        );
        let base = MapMask::default().with(MapKind::BaseColor);
        assert_eq!(base.shader_features(), BASE_COLOR);
        assert_eq!(base.constant(), 0);
        let normal = MapMask::default().with(MapKind::Normal);
        assert_eq!(normal.shader_features(), NORMAL);
        assert!(normal.needs_tangents() && !base.needs_tangents());
        assert_eq!(
            MapMask::default().shader_features(),
            (ObjectVertFeatures::NONE, ObjectFragFeatures::NONE)
        );
        // The specular map alone reads UVs through the base colour's
        // variant (over its white default); with a normal map, that one's.
        let specular = MapMask::default().with(MapKind::Specular);
        assert_eq!(specular.shader_features(), BASE_COLOR);
        assert_eq!(specular.constant(), SPECULAR_MAP_BIT);
        assert!(!specular.needs_tangents());
        let both = normal.with(MapKind::Specular);
        assert_eq!(both.shader_features(), NORMAL);
        assert_eq!(both.constant(), SPECULAR_MAP_BIT);
    }
}
