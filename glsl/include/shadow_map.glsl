// The shadow of the one shadow-casting light (SHADOWS): the fraction of
// the light a point receives, from depth comparisons against the shadow
// map the shadow pass drew from the light. Requires constants.glsl.
//
// The light's term is scaled by `shadow_light_visibility`, which the
// shader sets once per pixel (before any light is evaluated) with
// `shadow_visibility`; the scene light it belongs to carries
// attenuation.w = 1 (directional lights use no attenuation otherwise), the
// sun is marked by the block's params.w.

#ifdef SHADOWS
layout(set = SHADOW_SET, binding = SHADOW_MAP_BINDING) uniform sampler2DShadow shadow_map;
// The map holds one tile per cascade (nearest first, across then down).
// A storage buffer, not a uniform block: lavapipe (Mesa 22.3) inlines a
// uniform block's values into the shader at draw time, and crashed doing
// so for the sun-lit objects' variant once a cascade indexed the block.
layout(std430, set = SHADOW_SET, binding = SHADOW_BLOCK_BINDING) readonly buffer ShadowBlock {
    mat4 view_projection[4];  // per cascade: camera-relative position to its clip space (orthographic)
    vec4 reach;               // per cascade: the distance from the camera where it ends
    vec4 texel;               // per cascade: a texel's world width
    vec4 params;              // x: 1 / tile side; y, z: tiles across and down; w: 1 for the sun
} shadow;

// Texels across the filter's square: 1 (one comparison), 3 or 5.
layout(constant_id = SPEC_SHADOW_TAPS) const int SHADOW_TAPS = 3;

float shadow_light_visibility = 1.0;

// The fraction of SHADOW_TAPS^2 comparisons around the point's texel that
// find nothing nearer the light, in the cascade the point's distance from
// the camera falls in. The point is first moved along its normal `n` by as
// many texels as the filter reaches plus one, so a lit surface does not
// shadow itself where its own depth, rasterized at texel centres, is
// compared a few texels away (the shadow pass adds a slope-scaled depth
// bias for the texel it is in). A point outside its cascade's tile is lit
// (the tile covers every caster that can shadow what the camera sees).
float shadow_visibility(vec3 p, vec3 n) {
    float dist = length(p);
    // The cascade, and its matrix and texel selected by constant indices:
    // lavapipe (Mesa 22.3) crashed drawing sun-lit objects when these
    // arrays were indexed by a computed cascade.
    bvec3 beyond = greaterThan(vec3(dist), shadow.reach.xyz);
    float cascade = dot(vec3(beyond), vec3(1.0));
    mat4 view_projection = beyond.x
        ? (beyond.y ? (beyond.z ? shadow.view_projection[3] : shadow.view_projection[2])
                    : shadow.view_projection[1])
        : shadow.view_projection[0];
    float texel = beyond.x ? (beyond.y ? (beyond.z ? shadow.texel.w : shadow.texel.z)
                                       : shadow.texel.y)
                           : shadow.texel.x;
    float reach = float(SHADOW_TAPS / 2) + 1.0;
    vec3 q = p + n * (texel * reach);
    vec4 clip = view_projection * vec4(q, 1.0);
    vec2 uv = clip.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) {
        return 1.0;
    }
    vec2 tiles = shadow.params.yz;
    vec2 tile = vec2(mod(cascade, tiles.x), floor(cascade / tiles.x));
    vec2 at = (uv + tile) / tiles;
    vec2 step = vec2(shadow.params.x) / tiles;
    // Beyond the farthest receiver the map was fitted to: nothing there.
    float depth = min(clip.z, 1.0);
    int r = SHADOW_TAPS / 2;
    float lit = 0.0;
    for (int y = -r; y <= r; ++y) {
        for (int x = -r; x <= r; ++x) {
            lit += texture(shadow_map, vec3(at + vec2(x, y) * step, depth));
        }
    }
    return lit / float(SHADOW_TAPS * SHADOW_TAPS);
}
#endif
