// Static lights: a pipeline whose lights the frame never changes carries
// them as specialization constants instead of reading them from a uniform
// block. On lavapipe a fragment shader reads a uniform block once per
// pixel (about 2.6 instructions per float per pixel, measured), so six
// lights of twelve floats cost more than the Blinn-Phong arithmetic
// itself; constants cost nothing. Requires frame_data.glsl.
//
// Positions are relative to `frame.light_origin` (the camera when the
// pipelines were made), so the camera can move without new pipelines: with
// the origin at the camera, the light is exactly the uniform block's.

layout(constant_id = SPEC_STATIC_LIGHTS) const bool STATIC_LIGHTS = false;

// Twelve constants per light, in GpuLight's order: position (w = 1 for a
// point light), colour, attenuation. One line per light up to
// MAX_STATIC_LIGHTS, here and in FOR_EACH_LIGHT.
#define STATIC_LIGHT_CONSTANTS(k) \
    SPEC_VEC4_CONSTANTS(STATIC_LIGHT_##k##_POSITION, SPEC_STATIC_LIGHT_DATA + 12 * k) \
    SPEC_VEC4_CONSTANTS(STATIC_LIGHT_##k##_COLOR, SPEC_STATIC_LIGHT_DATA + 12 * k + 4) \
    SPEC_VEC4_CONSTANTS(STATIC_LIGHT_##k##_ATTENUATION, SPEC_STATIC_LIGHT_DATA + 12 * k + 8)

STATIC_LIGHT_CONSTANTS(0)
STATIC_LIGHT_CONSTANTS(1)
STATIC_LIGHT_CONSTANTS(2)
STATIC_LIGHT_CONSTANTS(3)
STATIC_LIGHT_CONSTANTS(4)
STATIC_LIGHT_CONSTANTS(5)
STATIC_LIGHT_CONSTANTS(6)
STATIC_LIGHT_CONSTANTS(7)

// Light k of the pipeline's constants, its position moved to the origin.
#define STATIC_LIGHT(k) Light( \
    SPEC_VEC4(STATIC_LIGHT_##k##_POSITION) \
        + vec4(frame.light_origin.xyz * STATIC_LIGHT_##k##_POSITION_3, 0.0), \
    SPEC_VEC4(STATIC_LIGHT_##k##_COLOR), \
    SPEC_VEC4(STATIC_LIGHT_##k##_ATTENUATION))

// Runs TERM(light) for each of the draw's LIGHT_COUNT lights: the
// constants when STATIC_LIGHTS (at most MAX_STATIC_LIGHTS of them), else
// BLOCK.lights. Both conditions are constants, so only one path remains.
#define FOR_EACH_LIGHT(BLOCK, TERM) \
    if (STATIC_LIGHTS) { \
        if (LIGHT_COUNT > 0u) { TERM(STATIC_LIGHT(0)); } \
        if (LIGHT_COUNT > 1u) { TERM(STATIC_LIGHT(1)); } \
        if (LIGHT_COUNT > 2u) { TERM(STATIC_LIGHT(2)); } \
        if (LIGHT_COUNT > 3u) { TERM(STATIC_LIGHT(3)); } \
        if (LIGHT_COUNT > 4u) { TERM(STATIC_LIGHT(4)); } \
        if (LIGHT_COUNT > 5u) { TERM(STATIC_LIGHT(5)); } \
        if (LIGHT_COUNT > 6u) { TERM(STATIC_LIGHT(6)); } \
        if (LIGHT_COUNT > 7u) { TERM(STATIC_LIGHT(7)); } \
    } else { \
        for (uint light_index = 0u; light_index < LIGHT_COUNT; ++light_index) { \
            TERM(BLOCK.lights[light_index]); \
        } \
    }
