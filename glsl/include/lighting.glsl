// Local illumination shared by the vertex (Gouraud) and fragment (Phong,
// toon) paths. Requires scene_data.glsl.

// Direction to the light and the attenuated radiance it brings to `p`.
// Point lights (w = 1) and directional lights (w = 0) share one formula.
void light_at(Light light, vec3 p, out vec3 l, out vec3 radiance) {
    vec3 to_light = light.position.xyz - p * light.position.w;
    float d = length(to_light);
    l = d > 0.0 ? to_light / d : vec3(0.0, 0.0, 1.0);
    float att = 1.0;
    if (light.position.w > 0.5) {
        vec3 a = light.attenuation.xyz;
        att = 1.0 / max(a.x + a.y * d + a.z * d * d, 1e-6);
    }
    radiance = light.color.rgb * att;
}

float specular_power(float cos_nh, float shininess) {
    // pow(0, 0) is undefined in GLSL; cos^0 is 1 by continuity.
    return shininess > 0.0 ? pow(max(cos_nh, 0.0), shininess) : 1.0;
}

// Blinn-Phong: sum over lights of Le * (kd cos+theta + ks cos+(N.H)^shine)
// plus ka * La. Specular is only lit where the light is in front (cos theta > 0).
vec3 blinn_phong(vec3 p, vec3 n, vec3 v, vec3 kd, vec3 ka) {
    vec3 color = ka * frame.ambient.rgb;
    for (uint i = 0u; i < LIGHT_COUNT; ++i) {
        vec3 l, radiance;
        light_at(object.lights[i], p, l, radiance);
        float cos_theta = dot(n, l);
        if (cos_theta > 0.0) {
            vec3 h = normalize(l + v);
            color += radiance * (kd * cos_theta + object.ks.rgb * specular_power(dot(n, h), object.ks.a));
        }
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
