//! Descriptor set and binding numbers and specialization-constant ids the
//! shaders declare, generated from `glsl/interface.toml` (the GLSL side's
//! `constants.glsl` is generated from the same description, so the two
//! cannot disagree), and the compile-time checks that each uniform block's
//! Rust struct has the std140 layout the shaders were compiled with.

include!(concat!(env!("OUT_DIR"), "/shader_interface.rs"));

// A field moved, renamed or resized on either side fails here, at compile
// time, naming the block, the member and the shader.
include!(concat!(env!("OUT_DIR"), "/layout_checks.rs"));

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
