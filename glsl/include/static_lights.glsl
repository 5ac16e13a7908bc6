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
// point light), colour, attenuation.
#define STATIC_LIGHT_CONSTANTS(k) \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 0) const float STATIC_LIGHT_##k##_0 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 1) const float STATIC_LIGHT_##k##_1 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 2) const float STATIC_LIGHT_##k##_2 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 3) const float STATIC_LIGHT_##k##_3 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 4) const float STATIC_LIGHT_##k##_4 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 5) const float STATIC_LIGHT_##k##_5 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 6) const float STATIC_LIGHT_##k##_6 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 7) const float STATIC_LIGHT_##k##_7 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 8) const float STATIC_LIGHT_##k##_8 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 9) const float STATIC_LIGHT_##k##_9 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 10) const float STATIC_LIGHT_##k##_10 = 0.0; \
    layout(constant_id = SPEC_STATIC_LIGHT_DATA + 12 * k + 11) const float STATIC_LIGHT_##k##_11 = 0.0;

STATIC_LIGHT_CONSTANTS(0)
STATIC_LIGHT_CONSTANTS(1)
STATIC_LIGHT_CONSTANTS(2)
STATIC_LIGHT_CONSTANTS(3)
STATIC_LIGHT_CONSTANTS(4)
STATIC_LIGHT_CONSTANTS(5)
STATIC_LIGHT_CONSTANTS(6)
STATIC_LIGHT_CONSTANTS(7)

// Light k of the pipeline's constants.
#define STATIC_LIGHT(k) Light( \
    vec4(vec3(STATIC_LIGHT_##k##_0, STATIC_LIGHT_##k##_1, STATIC_LIGHT_##k##_2) \
             + frame.light_origin.xyz * STATIC_LIGHT_##k##_3, STATIC_LIGHT_##k##_3), \
    vec4(STATIC_LIGHT_##k##_4, STATIC_LIGHT_##k##_5, STATIC_LIGHT_##k##_6, STATIC_LIGHT_##k##_7), \
    vec4(STATIC_LIGHT_##k##_8, STATIC_LIGHT_##k##_9, STATIC_LIGHT_##k##_10, STATIC_LIGHT_##k##_11))

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
