// The per-frame block and the light layout, shared by every shader that
// lights surfaces. Layouts mirror src/render/gpu_types.rs.
#include "constants.glsl"

struct Light {
    vec4 position;     // xyz: position (w = 1) or unit direction towards the light (w = 0)
    vec4 color;        // rgb: emitted colour times intensity
    vec4 attenuation;  // x: constant, y: linear, z: quadratic, w: window (point lights only)
};

layout(set = FRAME_SET, binding = 0) uniform Frame {
    mat4 view_projection;
    vec4 camera_position;  // xyz
    vec4 ambient;          // rgb: La
    mat4 inverse_view_projection;
    vec4 viewport;         // width, height, 1/width, 1/height
    vec4 light_origin;     // xyz: the point static lights are placed from, relative to the camera
} frame;

// The number of lights a draw evaluates, a specialization constant: the
// light loop then has a fixed trip count the driver can unroll, and every
// light is read at a constant offset.
layout(constant_id = SPEC_LIGHT_COUNT) const uint LIGHT_COUNT = 0u;
// The declared length of the light array: LIGHT_COUNT, but at least 1, since
// a GLSL array cannot be empty.
layout(constant_id = SPEC_LIGHT_ARRAY_LENGTH) const uint LIGHT_ARRAY_LENGTH = 1u;

#include "static_lights.glsl"
