// The shadow of the one shadow-casting light (SHADOWS): the fraction of
// the light a point receives, from depth comparisons against the shadow
// map the shadow pass drew from the light. Requires constants.glsl.
//
// The light's term is scaled by `shadow_light_visibility`, which the
// shader sets once per pixel (before any light is evaluated) with
// `shadow_visibility`; the scene light it belongs to carries
// attenuation.w = 1 (directional lights use no attenuation otherwise), the
// sun is marked by the block's params.z.

#ifdef SHADOWS
layout(set = SHADOW_SET, binding = SHADOW_MAP_BINDING) uniform sampler2DShadow shadow_map;
layout(std140, set = SHADOW_SET, binding = SHADOW_BLOCK_BINDING) uniform ShadowBlock {
    mat4 view_projection;  // camera-relative position to the light's clip space (orthographic)
    vec4 params;           // x: 1 / map side; y: a texel's world width; z: 1 for the sun
} shadow;

// Texels across the filter's square: 1 (one comparison), 3 or 5.
layout(constant_id = SPEC_SHADOW_TAPS) const int SHADOW_TAPS = 3;

float shadow_light_visibility = 1.0;

// The fraction of SHADOW_TAPS^2 comparisons around the point's texel that
// find nothing nearer the light. The point is first moved along its
// normal `n` by as many texels as the filter reaches plus one, so a lit
// surface does not shadow itself where its own depth, rasterized at
// texel centres, is compared a few texels away (the shadow pass adds a
// slope-scaled depth bias for the texel it is in).
float shadow_visibility(vec3 p, vec3 n) {
    float reach = float(SHADOW_TAPS / 2) + 1.0;
    vec3 q = p + n * (shadow.params.y * reach);
    vec4 clip = shadow.view_projection * vec4(q, 1.0);
    vec2 uv = clip.xy * 0.5 + 0.5;
    // Beyond the farthest receiver the map was fitted to: nothing there.
    float depth = min(clip.z, 1.0);
    int r = SHADOW_TAPS / 2;
    float lit = 0.0;
    for (int y = -r; y <= r; ++y) {
        for (int x = -r; x <= r; ++x) {
            lit += texture(shadow_map, vec3(uv + vec2(x, y) * shadow.params.x, depth));
        }
    }
    return lit / float(SHADOW_TAPS * SHADOW_TAPS);
}
#endif
