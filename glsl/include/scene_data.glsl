// Data of the object shaders: the frame block (frame_data.glsl) and the
// per-object block with its lights. Layouts mirror src/render/gpu_types.rs.
#include "frame_data.glsl"

// Shading models, chosen per pipeline by a specialization constant so the
// shader holds no branch for the models a material does not use.
const int SHADING_PHONG = 0;
const int SHADING_GOURAUD = 1;
const int SHADING_TOON = 2;
layout(constant_id = SPEC_SHADING_MODEL) const int SHADING_MODEL = SHADING_PHONG;

// One block per object: its transform, its material and exactly the lights
// that can reach it (see Scene::lights_reaching), bound with a dynamic offset.
// Lavapipe still reads a uniform block once per invocation (about 2.6
// instructions per float per pixel), so lights that fit are carried as
// specialization constants instead (static_lights.glsl) and `lights` is
// read only by draws that cannot.
layout(std140, set = OBJECT_SET, binding = 0) uniform ObjectBlock {
    mat4 model;
    mat4 normal_matrix;  // inverse transpose of the model matrix
    vec4 ka;             // rgb
    vec4 kd;             // rgb, a: opacity
    vec4 ks;             // rgb, a: shininess
    uvec4 counts;        // x: number of lights in `lights` (= LIGHT_COUNT); y: 1 for a normal map with green down
    Light lights[LIGHT_ARRAY_LENGTH];
} object;
