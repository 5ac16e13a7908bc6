// The sRGB encode of IEC 61966-2-1, computed in the shader: the 8-bit
// output is a UNORM image holding encoded values, so its bytes depend on
// this arithmetic alone. A CPU driver's encode of an _SRGB attachment may
// use an approximate reciprocal square root whose last bits differ between
// CPU vendors; log2, exp2, multiplies and adds do not.
#ifndef SRGB_GLSL
#define SRGB_GLSL

// Linear [0, 1] to encoded [0, 1]: 12.92 x up to 0.0031308, then
// 1.055 x^(1/2.4) - 0.055. Values outside [0, 1] are clamped and NaN is 0,
// as a UNORM store of a linear value would have them.
vec3 srgb_encode(vec3 linear) {
    bvec3 nan = isnan(linear);
    vec3 c = mix(clamp(linear, 0.0, 1.0), vec3(0.0), nan);
    vec3 curve = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
    return mix(12.92 * c, curve, greaterThan(c, vec3(0.0031308)));
}
#endif
