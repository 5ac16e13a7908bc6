// The forward shading models over the lights in the object's block.
// Requires scene_data.glsl and lighting.glsl.

// Blinn-Phong: ka * La plus the sum over the object's lights.
vec3 blinn_phong(vec3 p, vec3 n, vec3 v, vec3 kd, vec3 ka) {
    vec3 color = ka * frame.ambient.rgb;
#define PHONG_TERM(light) color += blinn_phong_light(light, p, n, v, kd, object.ks)
    FOR_EACH_LIGHT(object, PHONG_TERM)
#undef PHONG_TERM
    return color;
}

// Adds one light's toon terms to `color`: a diffuse tone and the specular
// spot.
void add_toon_light(inout vec3 color, Light light, vec3 p, vec3 n, vec3 v, vec3 kd) {
    vec3 l, radiance;
    light_at(light, p, l, radiance);
    float cos_theta = dot(n, l);
    float tone = cos_theta > 0.5 ? 1.0 : (cos_theta > 0.0 ? 0.4 : 0.0);
    color += radiance * kd * tone;
    if (cos_theta > 0.0 && specular_power(dot(n, normalize(l + v)), object.ks.a) > 0.5) {
        color += radiance * object.ks.rgb;
    }
}

// Toon: two diffuse tones and a hard specular spot; the silhouette is drawn
// by the caller where |N.V| is small.
vec3 toon(vec3 p, vec3 n, vec3 v, vec3 kd, vec3 ka) {
    vec3 color = ka * frame.ambient.rgb;
#define TOON_TERM(light) add_toon_light(color, light, p, n, v, kd)
    FOR_EACH_LIGHT(object, TOON_TERM)
#undef TOON_TERM
    return color;
}

const float TOON_SILHOUETTE = 0.2;
