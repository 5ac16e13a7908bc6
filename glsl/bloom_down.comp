#version 450
// feature: FROM_HDR FETCH_TEXELS
// requires: FETCH_TEXELS FROM_HDR
#include "constants.glsl"
// Bloom, downsampling: one level of the chain from the image above it.
//
// From the HDR image (FROM_HDR), level 0 is a quarter of the output's
// size and each of its texels the mean of the 4x4 HDR texels it covers:
// four 2x2 boxes, each one bilinear fetch at the boxes' shared corner
// (FETCH_TEXELS: four texel fetches, for HDR formats the device cannot
// filter). Each box is clamped to [0, 65504] (NaN becomes 0), so a
// non-finite or negative pixel cannot spread through the chain: the box
// it is in is dropped or capped. A box is the cheapest read of the HDR
// image (one fetch per four texels), and the 13-tap filter below, which
// reads each texel nine times, costs as much as the atmosphere at level
// 0; the levels below keep its smoothness (docs/performance.md, "Bloom").
//
// Every other level is half the one above, with the 13-tap filter of
// Jimenez (2014): the weighted sum of five overlapping 4x4-texel areas,
// each the mean of four 2x2-texel boxes — the centre box (1/8), the four
// boxes one texel diagonally out (1/8 each) and the eight boxes two
// texels out (corners 1/32, edges 1/16). The weights sum to 1, so the
// mean brightness is kept.
//
// Texel x of the level written covers texels 2x and 2x+1 of the one read
// (4x to 4x+3 of the HDR image), and a 2x2 box whose corner is c covers
// texels c-1 and c.

layout(local_size_x = BLOOM_GROUP_SIZE, local_size_y = BLOOM_GROUP_SIZE) in;
layout(set = 0, binding = BLOOM_SOURCE_BINDING) uniform sampler2D source;
layout(set = 0, binding = BLOOM_TARGET_BINDING, rgba16f) uniform writeonly image2D target;

#ifdef FROM_HDR
// The largest half float: the chain's images are RGBA16F.
const float MAX_VALUE = 65504.0;

vec3 sanitized(vec3 c) {
    // A NaN fails the comparison and becomes 0.
    return vec3(c.x > 0.0 ? min(c.x, MAX_VALUE) : 0.0,
                c.y > 0.0 ? min(c.y, MAX_VALUE) : 0.0,
                c.z > 0.0 ? min(c.z, MAX_VALUE) : 0.0);
}

#ifdef FETCH_TEXELS
vec3 texel(ivec2 p, ivec2 size) {
    return texelFetch(source, clamp(p, ivec2(0), size - 1), 0).rgb;
}

vec3 box(ivec2 corner, ivec2 size) {
    return sanitized(0.25 * (texel(corner - 1, size) + texel(corner - ivec2(0, 1), size)
                             + texel(corner - ivec2(1, 0), size) + texel(corner, size)));
}
#else
vec3 box(ivec2 corner, ivec2 size) {
    return sanitized(textureLod(source, vec2(corner) / vec2(size), 0.0).rgb);
}
#endif
#else
vec3 box(ivec2 corner, ivec2 size) {
    return textureLod(source, vec2(corner) / vec2(size), 0.0).rgb;
}
#endif

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(target)))) {
        return;
    }
    ivec2 size = textureSize(source, 0);
#ifdef FROM_HDR
    ivec2 c = 4 * p + 2;
    vec3 sum = 0.25 * (box(c + ivec2(-1, -1), size) + box(c + ivec2(1, -1), size)
                       + box(c + ivec2(-1, 1), size) + box(c + ivec2(1, 1), size));
#else
    ivec2 c = 2 * p + 1;
    vec3 inner = box(c + ivec2(-1, -1), size) + box(c + ivec2(1, -1), size)
                 + box(c + ivec2(-1, 1), size) + box(c + ivec2(1, 1), size);
    vec3 corners = box(c + ivec2(-2, -2), size) + box(c + ivec2(2, -2), size)
                   + box(c + ivec2(-2, 2), size) + box(c + ivec2(2, 2), size);
    vec3 edges = box(c + ivec2(0, -2), size) + box(c + ivec2(-2, 0), size)
                 + box(c + ivec2(2, 0), size) + box(c + ivec2(0, 2), size);
    vec3 sum = 0.125 * box(c, size) + 0.125 * inner + 0.03125 * corners + 0.0625 * edges;
#endif
    imageStore(target, p, vec4(sum, 1.0));
}
