#version 450
#include "constants.glsl"
// Bloom, upsampling: a level of the chain becomes the weighted mean of its
// own downsample (OWN_WEIGHT = 1 / the levels from it to the smallest) and
// the level below it (already upsampled the same way), blurred up with a
// 2x2 box RADIUS texels of that level wide over its bilinear
// reconstruction: four bilinear taps at (+-RADIUS/2, +-RADIUS/2). So each
// level ends as the mean of every level from it down, each blurred up to
// it, and level 0 keeps the HDR image's mean brightness.
//
// Jimenez (2014) blurs up with a 3x3 tent (nine taps); the box is the
// tent's half (the tent is the box convolved with itself), at under half
// the reads, and the chain's levels below each add their own blur.
//
// Texel x of this level is at x/2 + 1/4 in the level below (its texel q
// covers texels 2q and 2q+1 here).

layout(local_size_x = BLOOM_GROUP_SIZE, local_size_y = BLOOM_GROUP_SIZE) in;
layout(set = 0, binding = BLOOM_SOURCE_BINDING) uniform sampler2D below;
layout(set = 0, binding = BLOOM_TARGET_BINDING, rgba16f) uniform image2D level;
layout(constant_id = SPEC_BLOOM_RADIUS) const float RADIUS = 1.0;
layout(constant_id = SPEC_BLOOM_OWN_WEIGHT) const float OWN_WEIGHT = 0.5;

vec3 tap(vec2 uv) {
    return textureLod(below, uv, 0.0).rgb;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(level)))) {
        return;
    }
    vec2 size = vec2(textureSize(below, 0));
    vec2 uv = (vec2(p) + 0.5) * 0.5 / size;
    vec2 d = 0.5 * RADIUS / size;
    vec3 box = tap(uv - d) + tap(uv + vec2(d.x, -d.y)) + tap(uv + vec2(-d.x, d.y)) + tap(uv + d);
    vec3 own = imageLoad(level, p).rgb;
    imageStore(level, p, vec4(mix(0.25 * box, own, OWN_WEIGHT), 1.0));
}
