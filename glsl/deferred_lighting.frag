#version 450
// Deferred lighting: reads the G-buffer and depth of this pixel as input
// attachments, rebuilds the world position from depth, and adds the light
// of exactly the lights that reach this screen tile (its group's block,
// LIGHT_COUNT of them, as constants when static) to the colour target
// with additive blending.
#include "frame_data.glsl"
#include "lighting.glsl"
#include "octahedral.glsl"

layout(std140, set = 1, binding = 0) uniform TileLights {
    Light lights[LIGHT_ARRAY_LENGTH];
} tile;

layout(input_attachment_index = 0, set = 2, binding = 0) uniform subpassInput g_albedo;
layout(input_attachment_index = 1, set = 2, binding = 1) uniform subpassInput g_normal;
layout(input_attachment_index = 2, set = 2, binding = 2) uniform subpassInput g_material;
layout(input_attachment_index = 3, set = 2, binding = 3) uniform subpassInput g_depth;

layout(location = 0) out vec4 out_color;

void main() {
    float depth = subpassLoad(g_depth).r;
    vec2 ndc = gl_FragCoord.xy * frame.viewport.zw * 2.0 - 1.0;
    vec4 world = frame.inverse_view_projection * vec4(ndc, depth, 1.0);
    vec3 p = world.xyz / world.w;
    vec3 n = octahedral_decode(subpassLoad(g_normal).xy);
    vec3 v = normalize(frame.camera_position.xyz - p);
    vec3 kd = subpassLoad(g_albedo).rgb;
    vec4 ks_shininess = subpassLoad(g_material);
    vec3 color = vec3(0.0);
#define PHONG_TERM(light) color += blinn_phong_light(light, p, n, v, kd, ks_shininess)
    FOR_EACH_LIGHT(tile, PHONG_TERM)
#undef PHONG_TERM
    out_color = vec4(color, 0.0);
}
