//! Descriptor set and binding numbers and specialization-constant ids the
//! shaders declare, named once: `glsl/include/constants.glsl` holds the
//! same list as `#define`s, and the test below checks that they agree, so
//! a renumbering cannot leave one side behind.

/// The frame block (camera, ambient), set 0 of object pipelines.
pub const FRAME_SET: u32 = 0;
/// The object's block, bound with a dynamic offset.
pub const OBJECT_SET: u32 = 1;
/// The material's images, with fixed bindings.
pub const MATERIAL_SET: u32 = 2;
pub const BASE_COLOR_BINDING: u32 = 0;
pub const NORMAL_MAP_BINDING: u32 = 1;
pub const SPECULAR_MAP_BINDING: u32 = 2;
/// Object pipelines lit by an atmosphere's sun and sky: the atmosphere's
/// own set (`SkyResources::set`), after the material set.
pub const SKY_SET: u32 = 3;
/// Added to the atmosphere shaders' specialization-constant ids in object
/// pipelines, past the object pipelines' own ids (the static lights end at
/// `SPEC_STATIC_LIGHT_DATA + 12 * MAX_STATIC_LIGHTS`).
pub const SPEC_OBJECT_SKY_OFFSET: u32 = 128;

/// Object and lighting pipelines' specialization constants.
pub const SPEC_SHADING_MODEL: u32 = 0;
pub const SPEC_LIGHT_COUNT: u32 = 1;
pub const SPEC_LIGHT_ARRAY_LENGTH: u32 = 2;
pub const SPEC_DEBUG_ATTRIBUTE: u32 = 3;
pub const SPEC_SHININESS_EXPONENT: u32 = 4;
/// Whether an object pipeline draws both sides (back faces shaded with
/// the normal reversed).
pub const SPEC_TWO_SIDED: u32 = 6;
/// The material maps an object pipeline reads that are selected by a
/// constant rather than a shader variant: a bit mask
/// (`scene::material_maps::Selection::Constant`).
pub const SPEC_MATERIAL_MAPS: u32 = 7;
/// The specular map's bit of `SPEC_MATERIAL_MAPS`.
pub const SPECULAR_MAP_BIT: u32 = 1;
/// Whether an object pipeline draws straight into the 8-bit output, whose
/// values the shader then sRGB-encodes (the output is UNORM).
pub const SPEC_ENCODE_SRGB: u32 = 15;
/// Whether a pipeline's lights are specialization constants
/// (`render::static_lights`), and the first of their ids, 12 per light.
pub const SPEC_STATIC_LIGHTS: u32 = 5;
pub const SPEC_STATIC_LIGHT_DATA: u32 = 16;
/// The most lights a pipeline carries as constants.
pub const MAX_STATIC_LIGHTS: u32 = 8;

/// The tone map's specialization constants.
pub const SPEC_TONEMAP_OPERATOR: u32 = 0;
pub const SPEC_TONEMAP_EXPOSURE: u32 = 1;

/// The atmosphere shaders' specialization constants.
pub const SPEC_TABLE_MAPPING: u32 = 0;
pub const SPEC_TABLE_FILTER: u32 = 1;
pub const SPEC_OZONE_EXACT: u32 = 2;
pub const SPEC_SKY_VIEW_HARDWARE_FILTER: u32 = 3;
pub const SPEC_TRANSPARENT_OVER_SKY: u32 = 4;
/// Whether the multiple-scattering and sky-irradiance tables are read
/// through the sampler's bilinear filter.
pub const SPEC_SUN_TABLES_LINEAR_FILTER: u32 = 5;
/// The first of the sky block's unchanging fields, 4 ids per field
/// (`sky_resources::static_constants`).
pub const SPEC_SKY_STATIC: u32 = 8;

/// The atmosphere's set 0: the aerial-perspective volume written by its
/// compute pass (storage image) and read by the atmosphere subpass
/// (sampled), present only in frames with the volume.
pub const AERIAL_VOLUME_WRITE_BINDING: u32 = 8;
pub const AERIAL_VOLUME_BINDING: u32 = 9;

/// The specialization entries of consecutive float constants from id
/// `first` on (the shaders' `SPEC_VEC4_CONSTANTS`).
pub fn float_constants(
    first: u32,
    values: impl IntoIterator<Item = f32>,
) -> impl Iterator<Item = (u32, u32)> {
    (first..).zip(values.into_iter().map(f32::to_bits))
}

const _: () = assert!(
    SPEC_STATIC_LIGHT_DATA + 12 * MAX_STATIC_LIGHTS <= SPEC_OBJECT_SKY_OFFSET,
    "the atmosphere's constants in object pipelines overlap the static lights"
);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every `#define NAME N` of constants.glsl is a constant here with the
    /// same value, and every constant here is defined there.
    #[test]
    fn the_glsl_constants_agree() {
        let ours = [
            ("FRAME_SET", FRAME_SET),
            ("OBJECT_SET", OBJECT_SET),
            ("MATERIAL_SET", MATERIAL_SET),
            ("BASE_COLOR_BINDING", BASE_COLOR_BINDING),
            ("NORMAL_MAP_BINDING", NORMAL_MAP_BINDING),
            ("SPECULAR_MAP_BINDING", SPECULAR_MAP_BINDING),
            ("SKY_SET", SKY_SET),
            ("SPEC_OBJECT_SKY_OFFSET", SPEC_OBJECT_SKY_OFFSET),
            ("SPEC_SHADING_MODEL", SPEC_SHADING_MODEL),
            ("SPEC_LIGHT_COUNT", SPEC_LIGHT_COUNT),
            ("SPEC_LIGHT_ARRAY_LENGTH", SPEC_LIGHT_ARRAY_LENGTH),
            ("SPEC_DEBUG_ATTRIBUTE", SPEC_DEBUG_ATTRIBUTE),
            ("SPEC_SHININESS_EXPONENT", SPEC_SHININESS_EXPONENT),
            ("SPEC_TWO_SIDED", SPEC_TWO_SIDED),
            ("SPEC_MATERIAL_MAPS", SPEC_MATERIAL_MAPS),
            ("SPECULAR_MAP_BIT", SPECULAR_MAP_BIT),
            ("SPEC_ENCODE_SRGB", SPEC_ENCODE_SRGB),
            ("SPEC_STATIC_LIGHTS", SPEC_STATIC_LIGHTS),
            ("SPEC_STATIC_LIGHT_DATA", SPEC_STATIC_LIGHT_DATA),
            ("MAX_STATIC_LIGHTS", MAX_STATIC_LIGHTS),
            ("SPEC_TONEMAP_OPERATOR", SPEC_TONEMAP_OPERATOR),
            ("SPEC_TONEMAP_EXPOSURE", SPEC_TONEMAP_EXPOSURE),
            ("SPEC_TABLE_MAPPING", SPEC_TABLE_MAPPING),
            ("SPEC_TABLE_FILTER", SPEC_TABLE_FILTER),
            ("SPEC_OZONE_EXACT", SPEC_OZONE_EXACT),
            (
                "SPEC_SKY_VIEW_HARDWARE_FILTER",
                SPEC_SKY_VIEW_HARDWARE_FILTER,
            ),
            ("SPEC_TRANSPARENT_OVER_SKY", SPEC_TRANSPARENT_OVER_SKY),
            (
                "SPEC_SUN_TABLES_LINEAR_FILTER",
                SPEC_SUN_TABLES_LINEAR_FILTER,
            ),
            ("SPEC_SKY_STATIC", SPEC_SKY_STATIC),
            ("AERIAL_VOLUME_WRITE_BINDING", AERIAL_VOLUME_WRITE_BINDING),
            ("AERIAL_VOLUME_BINDING", AERIAL_VOLUME_BINDING),
        ];
        let glsl = include_str!("../../glsl/include/constants.glsl");
        let defined: Vec<(&str, u32)> = glsl
            .lines()
            .filter_map(|l| l.trim().strip_prefix("#define "))
            .filter_map(|rest| {
                let mut words = rest.split_whitespace();
                let name = words.next()?;
                let value = words.next()?.parse().ok()?;
                Some((name, value))
            })
            .collect();
        assert_eq!(defined.len(), ours.len(), "{defined:?}");
        for (name, value) in ours {
            assert!(
                defined.contains(&(name, value)),
                "{name} = {value} is not in constants.glsl: {defined:?}"
            );
        }
    }
}
