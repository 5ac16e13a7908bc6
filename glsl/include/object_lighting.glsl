// The forward shading models over the lights in the object's block.
// Requires scene_data.glsl and lighting.glsl.

// Blinn-Phong: ka * La plus the sum over the object's lights.
vec3 blinn_phong(vec3 p, vec3 n, vec3 v, vec3 kd, vec3 ka) {
    vec3 color = ka * frame.ambient.rgb;
    for (uint i = 0u; i < LIGHT_COUNT; ++i) {
        color += blinn_phong_light(object.lights[i], p, n, v, kd, object.ks);
    }
    return color;
}

// Toon: two diffuse tones and a hard specular spot; the silhouette is drawn
// by the caller where |N.V| is small.
vec3 toon(vec3 p, vec3 n, vec3 v, vec3 kd, vec3 ka) {
    vec3 color = ka * frame.ambient.rgb;
    for (uint i = 0u; i < LIGHT_COUNT; ++i) {
        vec3 l, radiance;
        light_at(object.lights[i], p, l, radiance);
        float cos_theta = dot(n, l);
        float tone = cos_theta > 0.5 ? 1.0 : (cos_theta > 0.0 ? 0.4 : 0.0);
        color += radiance * kd * tone;
        if (cos_theta > 0.0 && specular_power(dot(n, normalize(l + v)), object.ks.a) > 0.5) {
            color += radiance * object.ks.rgb;
        }
    }
    return color;
}

const float TOON_SILHOUETTE = 0.2;
