#version 450
// Transforms object vertices to clip space; for Gouraud shading it also
// lights each vertex.
#include "scene_data.glsl"
#include "lighting.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv;

layout(location = 0) out vec3 out_world_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) out vec3 out_gouraud;

void main() {
    vec4 world = object.model * vec4(in_position, 1.0);
    vec3 n = normalize(mat3(object.normal_matrix) * in_normal);
    out_world_position = world.xyz;
    out_normal = n;
    out_uv = in_uv;
    out_gouraud = vec3(0.0);
    if (SHADING_MODEL == SHADING_GOURAUD) {
        vec3 v = normalize(frame.camera_position.xyz - world.xyz);
        // Gouraud lights with the material colour; the fragment stage
        // multiplies in the texture, which is the classic approximation.
        out_gouraud = blinn_phong(world.xyz, n, v, object.kd.rgb, object.ka.rgb);
    }
    gl_Position = frame.view_projection * world;
}
