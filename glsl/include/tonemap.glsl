// Tone-mapping operators, HDR (linear, any value) to [0, 1].

// Inf, NaN and negative values must never reach the 8-bit output as garbage:
// NaN and negatives become 0, +Inf becomes the largest half float, which
// both operators map to (nearly) 1. Applied after exposure, so an overflow
// there saturates too.
vec3 sanitize_hdr(vec3 c) {
    bvec3 nan = isnan(c);
    c = vec3(nan.x ? 0.0 : c.x, nan.y ? 0.0 : c.y, nan.z ? 0.0 : c.z);
    return clamp(c, vec3(0.0), vec3(65504.0));
}

// Reinhard, per channel: L / (1 + L).
vec3 reinhard(vec3 c) {
    return c / (1.0 + c);
}

// Narkowicz's fit of the ACES filmic curve.
vec3 aces_fit(vec3 c) {
    const float a = 2.51, b = 0.03, cc = 2.43, d = 0.59, e = 0.14;
    return clamp((c * (a * c + b)) / (c * (cc * c + d) + e), 0.0, 1.0);
}
