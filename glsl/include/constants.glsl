// Descriptor set and binding numbers and specialization-constant ids that
// the Rust side names too (`render::shader_ids`, whose test checks that the
// two lists agree). Included first by the shaders that use them.
#ifndef CONSTANTS_GLSL
#define CONSTANTS_GLSL

// Object pipelines: the frame block, the object's block (dynamic offset),
// the material's images (fixed bindings; 1x1 defaults for a missing one).
#define FRAME_SET 0
#define OBJECT_SET 1
#define MATERIAL_SET 2
#define BASE_COLOR_BINDING 0
#define NORMAL_MAP_BINDING 1
#define SPECULAR_MAP_BINDING 2
// Object pipelines lit by an atmosphere's sun and sky (object_air.glsl):
// the atmosphere's own set (its block and tables, atmosphere.glsl), with
// the atmosphere shaders' specialization constants moved up by
// SPEC_OBJECT_SKY_OFFSET, past the object pipelines' own ids (the static
// lights end at SPEC_STATIC_LIGHT_DATA + 12 * MAX_STATIC_LIGHTS = 112).
#define SKY_SET 3
#define SPEC_OBJECT_SKY_OFFSET 128

// Object and lighting pipelines' specialization constants.
#define SPEC_SHADING_MODEL 0
#define SPEC_LIGHT_COUNT 1
#define SPEC_LIGHT_ARRAY_LENGTH 2
#define SPEC_DEBUG_ATTRIBUTE 3
#define SPEC_SHININESS_EXPONENT 4
// Object pipelines: both sides drawn, back faces shaded with the normal
// reversed.
#define SPEC_TWO_SIDED 6
// Object pipelines: the material maps selected by this bit mask rather
// than by a shader variant (scene::material_maps).
#define SPEC_MATERIAL_MAPS 7
#define SPECULAR_MAP_BIT 1
// Object pipelines drawing straight into the 8-bit output: the shader
// encodes sRGB.
#define SPEC_ENCODE_SRGB 15
// Static lights: whether a pipeline's lights are specialization constants
// (static_lights.glsl), and the first of their ids, 12 per light.
#define SPEC_STATIC_LIGHTS 5
#define SPEC_STATIC_LIGHT_DATA 16
#define MAX_STATIC_LIGHTS 8

// The tone map's specialization constants.
#define SPEC_TONEMAP_OPERATOR 0
#define SPEC_TONEMAP_EXPOSURE 1

// The atmosphere shaders' specialization constants.
#define SPEC_TABLE_MAPPING 0
#define SPEC_TABLE_FILTER 1
#define SPEC_OZONE_EXACT 2
#define SPEC_SKY_VIEW_HARDWARE_FILTER 3
#define SPEC_TRANSPARENT_OVER_SKY 4
#define SPEC_SUN_TABLES_LINEAR_FILTER 5
// The first of the sky block's unchanging fields, 4 ids per field.
#define SPEC_SKY_STATIC 8

// The atmosphere's set 0: the aerial-perspective volume, written by
// aerial_volume.comp and read by atmosphere.frag's AERIAL_VOLUME variant.
#define AERIAL_VOLUME_WRITE_BINDING 8
#define AERIAL_VOLUME_BINDING 9

// Four float specialization constants NAME_0 .. NAME_3 with ids ID ..
// ID + 3, read back as one vector by SPEC_VEC4(NAME): the static lights
// and the sky's unchanging fields are declared with these.
#define SPEC_VEC4_CONSTANTS(NAME, ID) \
    layout(constant_id = (ID) + 0) const float NAME##_0 = 0.0; \
    layout(constant_id = (ID) + 1) const float NAME##_1 = 0.0; \
    layout(constant_id = (ID) + 2) const float NAME##_2 = 0.0; \
    layout(constant_id = (ID) + 3) const float NAME##_3 = 0.0;
#define SPEC_VEC4(NAME) vec4(NAME##_0, NAME##_1, NAME##_2, NAME##_3)
#endif
