// The forward shading models over the lights in the object's block, and,
// with SUN_LIGHT, the atmosphere's sun and sky at the shaded point.
// Requires scene_data.glsl and lighting.glsl (and object_air.glsl with
// SUN_LIGHT).

// Blinn-Phong: ka * La plus the sum over the object's lights, then the
// sun (a directional light of the point's own colour) and the sky's
// irradiance times kd (diffuse only: no specular from the sky). `ks`:
// the specular reflectance (rgb) and shininess (a), the object's own or
// scaled by a map.
vec3 blinn_phong(vec3 p, vec3 n, vec3 v, vec3 kd, vec3 ka, vec4 ks) {
    vec3 color = ka * frame.ambient.rgb;
#define PHONG_TERM(light) color += blinn_phong_light(light, p, n, v, kd, ks)
    FOR_EACH_LIGHT(object, PHONG_TERM)
#ifdef SUN_LIGHT
    AirLights air = air_lights(p, n);
    PHONG_TERM(air.sun);
    color += kd * air.sky;
#endif
#undef PHONG_TERM
    return color;
}

// Adds one light's toon terms to `color`: a diffuse tone and the specular
// spot.
void add_toon_light(inout vec3 color, Light light, vec3 p, vec3 n, vec3 v, vec3 kd, vec4 ks) {
    vec3 l, radiance;
    light_at(light, p, l, radiance);
    float cos_theta = dot(n, l);
    float tone = cos_theta > 0.5 ? 1.0 : (cos_theta > 0.0 ? 0.4 : 0.0);
    color += radiance * kd * tone;
    if (cos_theta > 0.0 && specular_power(dot(n, normalize(l + v)), ks.a) > 0.5) {
        color += radiance * ks.rgb;
    }
}

// Toon: two diffuse tones and a hard specular spot; the silhouette is drawn
// by the caller where |N.V| is small. `ks` as for blinn_phong.
vec3 toon(vec3 p, vec3 n, vec3 v, vec3 kd, vec3 ka, vec4 ks) {
    vec3 color = ka * frame.ambient.rgb;
#define TOON_TERM(light) add_toon_light(color, light, p, n, v, kd, ks)
    FOR_EACH_LIGHT(object, TOON_TERM)
#ifdef SUN_LIGHT
    // The sun in tones like any light; the sky's light, which comes from
    // every direction, unbanded.
    AirLights air = air_lights(p, n);
    TOON_TERM(air.sun);
    color += kd * air.sky;
#endif
#undef TOON_TERM
    return color;
}

const float TOON_SILHOUETTE = 0.2;
