#version 450
// feature: AUTO_EXPOSURE BLOOM
#include "constants.glsl"
// Tone-map subpass: reads the HDR colour of this pixel as an input
// attachment and writes display colour, sRGB-encoded here into the UNORM
// output (srgb.glsl says why not by the attachment).
#include "tonemap.glsl"
#include "srgb.glsl"

layout(input_attachment_index = 0, set = 0, binding = 0) uniform subpassInput hdr;
layout(location = 0) out vec4 out_color;

const int TONEMAP_REINHARD = 0;
const int TONEMAP_ACES = 1;
// No curve: the exposed value clamped to [0, 1] (LDR output with --hdr).
const int TONEMAP_NONE = 2;
// Debug views: a signed attribute v shown as 0.5 + 0.5 v in the PNG,
// written as it is (no sRGB encode).
const int TONEMAP_DEBUG = 3;
layout(constant_id = SPEC_TONEMAP_OPERATOR) const int OPERATOR = TONEMAP_REINHARD;
#ifdef AUTO_EXPOSURE
// Measured from this frame's HDR image by the exposure pass.
layout(set = EXPOSURE_SET, binding = 0, std430) readonly buffer Exposure {
    float exposure;
};
#define EXPOSURE exposure
#define BLOOM_SET (EXPOSURE_SET + 1)
#else
layout(constant_id = SPEC_TONEMAP_EXPOSURE) const float EXPOSURE = 1.0;
#define BLOOM_SET EXPOSURE_SET
#endif
#ifdef BLOOM
// Level 0 of the bloom pass's chain (a quarter of the output's size), in the set
// after the exposure's (or in its place without one).
layout(set = BLOOM_SET, binding = 0) uniform sampler2D bloom;
layout(constant_id = SPEC_TONEMAP_BLOOM_INTENSITY) const float BLOOM_INTENSITY = 0.04;

// (1 - intensity) * hdr + intensity * bloom, the HDR colour sanitized
// first so that a NaN pixel still shows the light around it. Pixel x of
// the output is at x/4 in level 0 (whose texel q covers pixels 4q to
// 4q+3), sampled bilinearly.
vec3 with_bloom(vec3 hdr) {
    vec2 uv = gl_FragCoord.xy * 0.25 / vec2(textureSize(bloom, 0));
    return mix(sanitize_hdr(hdr), textureLod(bloom, uv, 0.0).rgb, BLOOM_INTENSITY);
}
#define HDR_IN(c) with_bloom(c)
#else
#define HDR_IN(c) (c)
#endif

void main() {
    if (OPERATOR == TONEMAP_DEBUG) {
        vec3 v = subpassLoad(hdr).rgb;
        bvec3 nan = isnan(v);
        v = vec3(nan.x ? 0.0 : v.x, nan.y ? 0.0 : v.y, nan.z ? 0.0 : v.z);
        out_color = vec4(clamp(0.5 + 0.5 * v, 0.0, 1.0), 1.0);
        return;
    }
    // Exposure first, then sanitize: the product of a large exposure and a
    // bright value can overflow to +Inf (and the curves then divide Inf by
    // Inf, giving NaN = black), so it is clamped after scaling. That keeps
    // the curve monotonic for every finite exposure.
    vec3 c = sanitize_hdr(HDR_IN(subpassLoad(hdr).rgb) * EXPOSURE);
    if (OPERATOR == TONEMAP_ACES) {
        c = aces_fit(c);
    } else if (OPERATOR == TONEMAP_NONE) {
        c = clamp(c, 0.0, 1.0);
    } else {
        c = reinhard(c);
    }
    out_color = vec4(srgb_encode(c), 1.0);
}
