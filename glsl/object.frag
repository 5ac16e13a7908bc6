#version 450
// Shades object fragments into the HDR attachment.
// variant: textured BASE_COLOR_TEXTURE
#include "scene_data.glsl"
#include "lighting.glsl"

layout(location = 0) in vec3 in_world_position;
layout(location = 1) in vec3 in_normal;
#ifdef BASE_COLOR_TEXTURE
layout(location = 2) in vec2 in_uv;
#endif
layout(location = 3) in vec3 in_gouraud;

layout(location = 0) out vec4 out_color;

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
    if (SHADING_MODEL == SHADING_GOURAUD) {
        out_color = vec4(in_gouraud * base.rgb, alpha);
        return;
    }
    // Interpolated normals are shorter than 1: re-normalize per pixel.
    vec3 n = normalize(in_normal);
    vec3 v = normalize(frame.camera_position.xyz - in_world_position);
    vec3 kd = object.kd.rgb * base.rgb;
    vec3 ka = object.ka.rgb * base.rgb;
    if (SHADING_MODEL == SHADING_TOON) {
        vec3 c = abs(dot(n, v)) < TOON_SILHOUETTE ? vec3(0.0) : toon(in_world_position, n, v, kd, ka);
        out_color = vec4(c, alpha);
    } else {
        out_color = vec4(blinn_phong(in_world_position, n, v, kd, ka), alpha);
    }
}
