#version 450
// Transforms object vertices to clip space; for Gouraud shading it also
// lights each vertex.
// feature: BASE_COLOR_TEXTURE
// feature: NORMAL_MAP
#include "scene_data.glsl"
#include "lighting.glsl"
#include "object_lighting.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
#ifdef NORMAL_MAP
layout(location = 2) in vec4 in_tangent;
#endif
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP)
layout(location = 3) in vec2 in_uv;
#endif

layout(location = 0) out vec3 out_world_position;
layout(location = 1) out vec3 out_normal;
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP)
layout(location = 2) out vec2 out_uv;
#endif
layout(location = 3) out vec3 out_gouraud;
#ifdef NORMAL_MAP
layout(location = 4) out vec4 out_tangent;
#endif

void main() {
    vec4 world = object.model * vec4(in_position, 1.0);
    vec3 n = normalize(mat3(object.normal_matrix) * in_normal);
    out_world_position = world.xyz;
    out_normal = n;
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP)
    out_uv = in_uv;
#endif
#ifdef NORMAL_MAP
    // A tangent lies in the surface, so it moves with the model matrix
    // (not the normal matrix); positive scales keep the handedness.
    out_tangent = vec4(normalize(mat3(object.model) * in_tangent.xyz), in_tangent.w);
#endif
    out_gouraud = vec3(0.0);
    if (SHADING_MODEL == SHADING_GOURAUD) {
        vec3 v = normalize(frame.camera_position.xyz - world.xyz);
        // Gouraud lights with the material colour; the fragment stage
        // multiplies in the texture, which is the classic approximation.
        out_gouraud = blinn_phong(world.xyz, n, v, object.kd.rgb, object.ka.rgb);
    }
    gl_Position = frame.view_projection * world;
}
