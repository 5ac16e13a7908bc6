// The shadow of the one shadow-casting light (SHADOWS): the fraction of
// the light a point receives, from depth comparisons against the shadow
// map the shadow pass drew from the light. Requires constants.glsl.
//
// The light's term is scaled by `shadow_light_visibility`, which the
// shader sets once per pixel (before any light is evaluated) with
// `shadow_visibility`; the light it belongs to carries colour w = 1 (a
// scene light's block, or the sun's light when SHADOW_SUN
// says the sun casts the shadows).

#ifdef SHADOWS
layout(set = SHADOW_SET, binding = SHADOW_MAP_BINDING) uniform sampler2DShadow shadow_map;
// The map holds one tile per view: per cascade (nearest first) or per
// cube face, across then down.
// A storage buffer, not a uniform block: lavapipe (Mesa 22.3) inlines a
// uniform block's values into the shader at draw time, and crashes doing
// so for the sun-lit objects' variant with two cascades or more (a
// segmentation fault or "stack smashing detected", on earth_objects with
// the sun's shadows), even with the block read at constant indices and no
// branch on its values. A uniform block would make the lookup about 100
// instructions a pixel cheaper (docs/performance.md, "Shadows").
layout(std430, set = SHADOW_SET, binding = SHADOW_BLOCK_BINDING) readonly buffer ShadowBlock {
    mat4 view_projection[6];  // per cascade (and cube face, which the lookup projects with `face`): camera-relative position to its clip space
    vec4 reach;               // per cascade: the distance from the camera where it ends
    vec4 texel;               // per cascade: a texel's world width (x, point light: per unit distance)
    vec4 light;               // xyz: a point light's camera-relative position, w = 1; w = 0 otherwise
    vec4 face;                // a point light's face projection: x: 1 / tan(half-angle); y: far / (near - far); z: y * near
} shadow;

// Texels across the filter's square: 1 (one comparison), 3 or 5.
layout(constant_id = SPEC_SHADOW_TAPS) const int SHADOW_TAPS = 3;
// The views the block holds: cascades (1 to 4) or 6 cube faces.
layout(constant_id = SPEC_SHADOW_VIEWS) const int SHADOW_VIEWS = 1;
// Six views are a point light's faces (cascades are at most four).
const bool SHADOW_POINT = SHADOW_VIEWS == 6;
// Whether the atmosphere's sun casts the shadows.
layout(constant_id = SPEC_SHADOW_SUN) const bool SHADOW_SUN = false;
// One texel of a tile in tile coordinates, and the tiles across and down.
layout(constant_id = SPEC_SHADOW_TILE_TEXEL) const float SHADOW_TILE_TEXEL = 1.0 / 2048.0;
layout(constant_id = SPEC_SHADOW_TILES_ACROSS) const int SHADOW_TILES_ACROSS = 1;
layout(constant_id = SPEC_SHADOW_TILES_DOWN) const int SHADOW_TILES_DOWN = 1;

float shadow_light_visibility = 1.0;

// Where the point `p` (moved along its normal `n`) falls in the map: its
// view (a cascade by distance from the camera, or a point light's cube
// face by the direction from the light), its coordinates in that view's
// tile, and its depth there.
struct ShadowLookup {
    int view;
    vec2 uv;
    float depth;
};

// View `view`'s matrix. The block is read at constant indices and the
// matrix chosen per pixel: indexed by a per-pixel view, lavapipe loads
// each element lane by lane (with one view and no filter that cost 630
// instructions a pixel, as much as all six lights of a textured object).
mat4 shadow_view_projection(int view) {
    mat4 m = shadow.view_projection[0];
    for (int i = 1; i < SHADOW_VIEWS; ++i) {
        m = view == i ? shadow.view_projection[i] : m;
    }
    return m;
}

ShadowLookup shadow_lookup(vec3 p, vec3 n) {
    // The normal offset: as many texels as the filter reaches, plus one.
    float offset = float(SHADOW_TAPS / 2) + 1.0;
    ShadowLookup at;
    vec4 clip;
    if (SHADOW_POINT) {
        vec3 from_light = p - shadow.light.xyz;
        vec3 q = p + n * (length(from_light) * shadow.texel.x * offset);
        vec3 d = q - shadow.light.xyz;
        vec3 a = abs(d);
        // The face the direction leaves the cube through, the direction in
        // that face's view (the axes `shadow_view::cube_faces` looks along
        // and up with: x, y across, and the distance along the face's
        // axis), then the faces' shared projection. The six matrices would
        // be 96 reads of the block per pixel.
        vec3 v;
        if (a.x >= a.y && a.x >= a.z) {
            at.view = d.x >= 0.0 ? 0 : 1;
            v = vec3(d.x >= 0.0 ? d.z : -d.z, d.y, a.x);
        } else if (a.y >= a.z) {
            at.view = d.y >= 0.0 ? 2 : 3;
            v = vec3(d.y >= 0.0 ? d.x : -d.x, d.z, a.y);
        } else {
            at.view = d.z >= 0.0 ? 4 : 5;
            v = vec3(d.z >= 0.0 ? -d.x : d.x, d.y, a.z);
        }
        vec4 face = shadow.face;
        clip = vec4(face.x * v.xy, face.z - face.y * v.z, v.z);
        clip.xyz /= clip.w;
    } else {
        at.view = 0;
        float texel = shadow.texel[0];
        if (SHADOW_VIEWS > 1) {
            bvec3 beyond = greaterThan(vec3(length(p)), shadow.reach.xyz);
            at.view = int(dot(vec3(beyond), vec3(1.0)));
            vec4 texels = shadow.texel;
            texel = texels[at.view];
        }
        vec3 q = p + n * (texel * offset);
        clip = shadow_view_projection(at.view) * vec4(q, 1.0);
    }
    at.uv = clip.xy * 0.5 + 0.5;
    // Beyond the farthest receiver the map was fitted to: nothing there.
    at.depth = min(clip.z, 1.0);
    return at;
}

// The fraction of SHADOW_TAPS^2 comparisons around the point's texel that
// find nothing nearer the light. The point is first moved along its
// normal `n` by as many texels as the filter reaches plus one, so a lit
// surface does not shadow itself where its own depth, rasterized at
// texel centres, is compared a few texels away (the shadow pass adds a
// slope-scaled depth bias for the texel it is in). A point outside its
// view's tile is lit (a cascade's tile covers every caster that can
// shadow what the camera sees; a cube face's covers its quarter of the
// directions and a margin).
float shadow_visibility(vec3 p, vec3 n) {
    ShadowLookup at = shadow_lookup(p, n);
    if (any(lessThan(at.uv, vec2(0.0))) || any(greaterThan(at.uv, vec2(1.0)))) {
        return 1.0;
    }
    vec2 tiles = vec2(SHADOW_TILES_ACROSS, SHADOW_TILES_DOWN);
    float view = float(at.view);
    vec2 tile = vec2(mod(view, tiles.x), floor(view / tiles.x));
    vec2 uv = (at.uv + tile) / tiles;
    vec2 step = vec2(SHADOW_TILE_TEXEL) / tiles;
    int r = SHADOW_TAPS / 2;
    float lit = 0.0;
    for (int y = -r; y <= r; ++y) {
        for (int x = -r; x <= r; ++x) {
            lit += texture(shadow_map, vec3(uv + vec2(x, y) * step, at.depth));
        }
    }
    return lit / float(SHADOW_TAPS * SHADOW_TAPS);
}
#endif
