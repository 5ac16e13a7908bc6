//! Descriptor set and binding numbers and specialization-constant ids the
//! shaders declare, generated from `glsl/interface.toml` (the GLSL side's
//! `constants.glsl` is generated from the same description, so the two
//! cannot disagree). Plain numbers that import nothing, so the scene's
//! material-map table and the renderer can both name them; the uniform
//! blocks' layout checks live with the structs (`render::gpu_types`).

include!(concat!(env!("OUT_DIR"), "/shader_interface.rs"));

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
