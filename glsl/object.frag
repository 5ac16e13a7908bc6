#version 450
// Shades object fragments. Forward: the lit colour into the colour target.
// With GBUFFER (deferred lighting), Phong surfaces write their ambient term
// to the colour target and their material and normal to the G-buffer, and
// the lighting pass adds the lights; the other shading models are still
// shaded here and write a zero material, so the lighting pass adds nothing
// to them.
// feature: BASE_COLOR_TEXTURE
// feature: GBUFFER
#include "scene_data.glsl"
#include "lighting.glsl"
#include "object_lighting.glsl"
#include "octahedral.glsl"

layout(location = 0) in vec3 in_world_position;
layout(location = 1) in vec3 in_normal;
#ifdef BASE_COLOR_TEXTURE
layout(location = 2) in vec2 in_uv;
#endif
layout(location = 3) in vec3 in_gouraud;

layout(location = 0) out vec4 out_color;
#ifdef GBUFFER
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out vec2 out_normal;
layout(location = 3) out vec4 out_material;
#endif

#ifdef BASE_COLOR_TEXTURE
layout(set = 2, binding = 0) uniform sampler2D base_color;
#endif

void main() {
    vec4 base = vec4(1.0);
#ifdef BASE_COLOR_TEXTURE
    // Surface v grows upwards; image rows grow downwards.
    base = texture(base_color, vec2(in_uv.x, 1.0 - in_uv.y));
#endif
    float alpha = object.kd.a * base.a;
    // Interpolated normals are shorter than 1: re-normalize per pixel.
    vec3 n = normalize(in_normal);
    vec3 kd = object.kd.rgb * base.rgb;
    vec3 ka = object.ka.rgb * base.rgb;
#ifdef GBUFFER
    if (SHADING_MODEL == SHADING_PHONG) {
        out_color = vec4(ka * frame.ambient.rgb, alpha);
        out_albedo = vec4(kd, 1.0);
        out_normal = octahedral_encode(n);
        out_material = object.ks;
        return;
    }
    out_albedo = vec4(0.0);
    out_normal = vec2(0.0);
    out_material = vec4(0.0);
#endif
    if (SHADING_MODEL == SHADING_GOURAUD) {
        out_color = vec4(in_gouraud * base.rgb, alpha);
        return;
    }
    vec3 v = normalize(frame.camera_position.xyz - in_world_position);
    if (SHADING_MODEL == SHADING_TOON) {
        vec3 c = abs(dot(n, v)) < TOON_SILHOUETTE ? vec3(0.0) : toon(in_world_position, n, v, kd, ka);
        out_color = vec4(c, alpha);
    } else {
        out_color = vec4(blinn_phong(in_world_position, n, v, kd, ka), alpha);
    }
}
