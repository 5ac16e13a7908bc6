#version 450
// Transforms object vertices to clip space; for Gouraud shading it also
// lights each vertex.
// feature: BASE_COLOR_TEXTURE
// feature: NORMAL_MAP
// feature: DEBUG_VIEW
// feature: GOURAUD
// feature: SUN_LIGHT
// feature: SKY_LIGHT
// feature: INSTANCED
// requires: SKY_LIGHT SUN_LIGHT
// excludes: SUN_LIGHT DEBUG_VIEW
#include "variant_rules.glsl"
#include "scene_data.glsl"
#include "lighting.glsl"
#ifdef SUN_LIGHT
#include "object_air.glsl"
#endif
#include "object_lighting.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
#if defined(NORMAL_MAP) || defined(DEBUG_VIEW)
layout(location = 2) in vec4 in_tangent;
#endif
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP) || defined(DEBUG_VIEW)
layout(location = 3) in vec2 in_uv;
#endif
#ifdef INSTANCED
// A batch of objects drawn as instances: each instance's transforms come
// from the instance buffer; the block holds what they share.
layout(location = INSTANCE_MODEL_LOCATION) in mat4 in_model;
layout(location = INSTANCE_NORMAL_LOCATION) in mat3 in_normal_matrix;
#endif

// Outputs exist only in the variants whose fragment stage reads them.
#if !defined(GOURAUD) && !defined(DEBUG_VIEW)
layout(location = 0) out vec3 out_world_position;
#endif
#ifndef GOURAUD
layout(location = 1) out vec3 out_normal;
#endif
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP) || defined(DEBUG_VIEW)
layout(location = 2) out vec2 out_uv;
#endif
#ifdef GOURAUD
// Only Gouraud pipelines carry the per-vertex colour: every other
// pipeline would interpolate it for nothing.
layout(location = 3) out vec3 out_gouraud;
#endif
#if defined(NORMAL_MAP) || defined(DEBUG_VIEW)
layout(location = 4) out vec4 out_tangent;
#endif
#ifdef GOURAUD
layout(constant_id = SPEC_TWO_SIDED) const bool TWO_SIDED = false;
#endif

void main() {
#ifdef INSTANCED
    mat4 model = in_model;
    mat3 normal_matrix = in_normal_matrix;
#else
    mat4 model = object.model;
    mat3 normal_matrix = mat3(object.normal_matrix);
#endif
    vec4 world = model * vec4(in_position, 1.0);
    vec3 n = normalize(normal_matrix * in_normal);
#if !defined(GOURAUD) && !defined(DEBUG_VIEW)
    out_world_position = world.xyz;
#endif
#ifndef GOURAUD
    out_normal = n;
#endif
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP) || defined(DEBUG_VIEW)
    out_uv = in_uv;
#endif
#if defined(NORMAL_MAP) || defined(DEBUG_VIEW)
    // A tangent lies in the surface, so it moves with the model matrix
    // (not the normal matrix); positive scales keep the handedness.
    out_tangent = vec4(normalize(mat3(model) * in_tangent.xyz), in_tangent.w);
#endif
#ifdef GOURAUD
    vec3 v = normalize(frame.camera_position.xyz - world.xyz);
    // Two-sided, lit per vertex: the side of the vertex facing the camera.
    if (TWO_SIDED && dot(n, v) < 0.0) {
        n = -n;
    }
    // Gouraud lights with the material colour; the fragment stage
    // multiplies in the texture, which is the classic approximation.
    out_gouraud = blinn_phong(world.xyz, n, v, object.kd.rgb, object.ka.rgb, object.ks);
#endif
    gl_Position = frame.view_projection * world;
}
