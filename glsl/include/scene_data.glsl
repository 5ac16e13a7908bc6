// Data shared by the object shaders: the per-frame block and the per-object
// block with its lights. Layouts mirror src/render/gpu_types.rs.

struct Light {
    vec4 position;     // xyz: position (w = 1) or unit direction towards the light (w = 0)
    vec4 color;        // rgb: emitted colour times intensity
    vec4 attenuation;  // x: constant, y: linear, z: quadratic (point lights only)
};

layout(set = 0, binding = 0) uniform Frame {
    mat4 view_projection;
    vec4 camera_position;  // xyz
    vec4 ambient;          // rgb: La
} frame;

// Shading models, chosen per pipeline by a specialization constant so the
// shader holds no branch for the models a material does not use.
const int SHADING_PHONG = 0;
const int SHADING_GOURAUD = 1;
const int SHADING_TOON = 2;
layout(constant_id = 0) const int SHADING_MODEL = SHADING_PHONG;
// The number of lights in the object's block, also a specialization constant:
// the light loop then has a fixed trip count the driver can unroll, and every
// light is read at a constant offset.
layout(constant_id = 1) const uint LIGHT_COUNT = 0u;
// The declared length of the light array: LIGHT_COUNT, but at least 1, since
// a GLSL array cannot be empty.
layout(constant_id = 2) const uint LIGHT_ARRAY_LENGTH = 1u;

// One block per object: its transform, its material and exactly the lights
// that can reach it (see Scene::lights_reaching), bound with a dynamic offset.
// A uniform block rather than a storage buffer: with constant offsets the
// driver reads uniform data once per draw instead of once per invocation.
layout(std140, set = 1, binding = 0) uniform ObjectBlock {
    mat4 model;
    mat4 normal_matrix;  // inverse transpose of the model matrix
    vec4 ka;             // rgb
    vec4 kd;             // rgb, a: opacity
    vec4 ks;             // rgb, a: shininess
    uvec4 counts;        // x: number of lights in `lights` (= LIGHT_COUNT)
    Light lights[LIGHT_ARRAY_LENGTH];
} object;
