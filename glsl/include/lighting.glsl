// Local illumination by one light, shared by the forward object shaders
// and the deferred lighting pass. Requires frame_data.glsl.
#include "shadow_map.glsl"

// Direction to the light and the attenuated radiance it brings to `p`.
// Point lights (w = 1) and directional lights (w = 0) share one formula.
// A point light's attenuation is windowed: 1 / (c + l d + q d^2) minus
// cutoff / peak colour, clamped at 0, so it reaches exactly 0 at the
// culling range (Light::window in src/scene/lights.rs) and culling per
// object or per tile changes nothing.
void light_at(Light light, vec3 p, out vec3 l, out vec3 radiance) {
    vec3 to_light = light.position.xyz - p * light.position.w;
    float d = length(to_light);
    l = d > 0.0 ? to_light / d : vec3(0.0, 0.0, 1.0);
    float att = 1.0;
    if (light.position.w > 0.5) {
        vec3 a = light.attenuation.xyz;
        att = max(1.0 / max(a.x + a.y * d + a.z * d * d, 1e-6) - light.attenuation.w, 0.0);
    }
    radiance = light.color.rgb * att;
#ifdef SHADOWS
    // The shadow-casting light (see shadow_map.glsl).
    if (light.color.w > 0.5) {
        radiance *= shadow_light_visibility;
    }
#endif
}

// A whole-number shininess of at most 1023 (MAX_SHININESS_EXPONENT in
// src/render/plan.rs), as a specialization constant of the object shaders
// (0: none; the deferred lighting pass reads shininess per pixel and
// leaves it 0). cos^n is then at most 18 multiplications, where pow is
// exp2(n * log2(cos)): on lavapipe that cut a full-screen plane lit by six
// lights by about 15 %.
layout(constant_id = SPEC_SHININESS_EXPONENT) const uint SHININESS_EXPONENT = 0u;

// x^SHININESS_EXPONENT by squaring, written out: the conditions are
// constants, so only the multiplications the exponent's bits need remain
// (lavapipe does not unroll the loop form of this, which was slower than
// pow).
float power_by_squaring(float x) {
    float r = (SHININESS_EXPONENT & 1u) != 0u ? x : 1.0;
    float b = x;
// Squares the base and multiplies it in where the exponent has `bit`.
#define SQUARE_AND_MULTIPLY(bit) b *= b; r = (SHININESS_EXPONENT & (bit)) != 0u ? r * b : r
    SQUARE_AND_MULTIPLY(2u);
    SQUARE_AND_MULTIPLY(4u);
    SQUARE_AND_MULTIPLY(8u);
    SQUARE_AND_MULTIPLY(16u);
    SQUARE_AND_MULTIPLY(32u);
    SQUARE_AND_MULTIPLY(64u);
    SQUARE_AND_MULTIPLY(128u);
    SQUARE_AND_MULTIPLY(256u);
    SQUARE_AND_MULTIPLY(512u);
#undef SQUARE_AND_MULTIPLY
    return r;
}

float specular_power(float cos_nh, float shininess) {
    float x = max(cos_nh, 0.0);
    if (SHININESS_EXPONENT != 0u) {
        return power_by_squaring(x);
    }
    // pow(0, 0) is undefined in GLSL; cos^0 is 1 by continuity.
    return shininess > 0.0 ? pow(x, shininess) : 1.0;
}

// Blinn-Phong for one light: Le * (kd cos+theta + ks cos+(N.H)^shine).
// Specular is only lit where the light is in front (cos theta > 0).
vec3 blinn_phong_light(Light light, vec3 p, vec3 n, vec3 v, vec3 kd, vec4 ks_shininess) {
    vec3 l, radiance;
    light_at(light, p, l, radiance);
    float cos_theta = dot(n, l);
    if (cos_theta > 0.0) {
        vec3 h = normalize(l + v);
        return radiance * (kd * cos_theta + ks_shininess.rgb * specular_power(dot(n, h), ks_shininess.a));
    }
    return vec3(0.0);
}
