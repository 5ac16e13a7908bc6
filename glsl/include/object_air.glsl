// The light of an atmosphere's sun and sky on objects, per shaded point
// (per pixel; per vertex for Gouraud), from the tables the atmosphere pass
// reads: the sun's transmittance from the optical-depth table (and the
// ozone in closed form, as the march does), and, with SKY_LIGHT, the
// sky's irradiance from the sky-irradiance table. Included by the object
// shaders only in their SUN_LIGHT variants: scenes without an atmosphere
// compile none of it and bind no table. Requires frame_data.glsl.
//
// The atmosphere's block and tables are its own set (SKY_SET), and its
// specialization constants sit SPEC_OBJECT_SKY_OFFSET above their ids in
// the atmosphere's shaders, clear of the object pipelines' own.
#define SKY_BLOCK_SET SKY_SET
#define SKY_SPEC_OFFSET SPEC_OBJECT_SKY_OFFSET
#ifdef SKY_LIGHT
// Declares the sky-irradiance table and its lookup (GROUND_SKY_LIGHT).
#define MULTIPLE_SCATTERING
#endif
#include "atmosphere.glsl"

// A shaded point seen from the planet: p relative to the centre, its
// altitude h (at least 0: a point below the ground is lit as if on it)
// and radius r = Rb + h, and the local up.
struct AirPoint {
    vec3 p;
    float h;
    float r;
    vec3 up;
};

// The point x (camera-relative world space, as the object shaders work).
// Its altitude comes from r^2 - Rb^2 = c + x.(2o + x), with c = |o|^2 -
// Rb^2 exact from the CPU, as the march's altitudes: no planet-scale
// coordinate is squared in float32.
AirPoint air_point(vec3 x) {
    vec3 o = sky.origin.xyz;
    float rb = STATIC_RADII.x;
    float c = sky.terms.x + dot(x, 2.0 * o + x);
    float r = sqrt(max(rb * rb + c, 0.0));
    AirPoint a;
    a.p = o + x;
    a.h = max(c / (r + rb), 0.0);
    a.r = rb + a.h;
    a.up = normalize(a.p);
    return a;
}

// The sun's transmittance to the point (per unit of irradiance at the top
// of the atmosphere), zero in the planet's shadow (the model's hard
// shadow of the sun's centre). Above the atmosphere the ray towards the
// sun is followed to where it enters the air, or is fully transmitted
// when it misses it (the Moon of a view from the Moon).
vec3 air_sun_transmittance(AirPoint a) {
    vec3 s = SUN_DIRECTION;
    float rb = STATIC_RADII.x;
    float rt = STATIC_RADII.y;
    float h = a.h;
    float r = a.r;
    float b = dot(a.p, s);
    float mu = b / r;
    if (h > rt - rb) {
        // Distance of the sun ray's line from the centre, as in sphere().
        float perp = length(a.p - b * s);
        if (b >= 0.0 || perp >= rt) {
            return vec3(1.0);
        }
        // The entry point on the top sphere: cosine -sqrt(Rt^2 - p^2) / Rt.
        h = rt - rb;
        r = rt;
        mu = -sqrt((rt - perp) * (rt + perp)) / rt;
    }
    bool lit;
    // sun_optical_depth reads the point only through dot(p, sun) / r.
    vec3 tau = sun_optical_depth(h, r, s * (mu * r), lit);
    return lit ? exp(-tau) : vec3(0.0);
}

// The sun as a directional light of the point's own colour.
Light air_sun_light(vec3 transmittance) {
#ifdef SHADOWS
    // Marks the sun as the shadow-casting light when it is.
    float shadowed = SHADOW_SUN ? 1.0 : 0.0;
#else
    float shadowed = 0.0;
#endif
    return Light(vec4(SUN_DIRECTION, 0.0),
                 vec4(sky.sun_irradiance.xyz * transmittance, shadowed),
                 vec4(1.0, 0.0, 0.0, 0.0));
}

#ifdef SKY_LIGHT
// The irradiance from the sky (every order, the direct sun excluded) on a
// surface of normal n at the point, from the horizontal irradiance E_h of
// the sky-irradiance table, after Reindl et al. (1990) without their
// circumsolar term: E_h (1 + n.up) / 2 (1 + f sin^3(beta / 2)) from the
// sky, as if its radiance were uniform over the upper hemisphere but for
// a brighter band along the horizon (beta the surface's tilt, f =
// sqrt(E_sun,h / (E_sun,h + E_h)): the clearer the air, the brighter the
// band), plus the light the ground reflects, albedo (E_sun,h + E_h)
// (1 - n.up) / 2, the ground taken as a uniform Lambertian plane under
// the point lit like the point itself (E_sun,h the sun's irradiance on a
// horizontal surface there). docs/atmosphere.md gives its error against
// full light transport.
//
// Only inside the atmosphere, where the table is: above it the sky light
// is zero (the light the planet and its air reflect into space is left
// out, as on the Moon of a view from the Moon).
vec3 air_sky_irradiance(AirPoint a, vec3 n, vec3 sun_transmittance) {
    if (a.h > STATIC_RADII.y - STATIC_RADII.x) {
        return vec3(0.0);
    }
    float mu_s = dot(a.p, SUN_DIRECTION) / a.r;
    vec3 irradiance = sky.sun_irradiance.xyz;
    vec3 horizontal = irradiance * sky_irradiance(a.h, mu_s);
    vec3 sun_horizontal = irradiance * sun_transmittance * max(mu_s, 0.0);
    vec3 global = sun_horizontal + horizontal;
    vec3 f = sqrt(sun_horizontal / max(global, vec3(1e-30)));
    float c = dot(n, a.up);
    // sin(beta / 2) = sqrt((1 - cos beta) / 2).
    float half_tilt = sqrt(max(0.5 - 0.5 * c, 0.0));
    return horizontal * (0.5 + 0.5 * c) * (1.0 + f * (half_tilt * half_tilt * half_tilt))
        + STATIC_GROUND_ALBEDO.xyz * global * (0.5 - 0.5 * c);
}
#endif

// What the atmosphere brings to a point q (relative to the camera) with
// normal n: the sun as a directional light of the point's own colour, and
// the sky's irradiance (zero without SKY_LIGHT), which every shading
// model adds times kd.
struct AirLights {
    Light sun;
    vec3 sky;
};

AirLights air_lights(vec3 q, vec3 n) {
    AirPoint air = air_point(q);
    vec3 transmittance = air_sun_transmittance(air);
    AirLights lights;
    lights.sun = air_sun_light(transmittance);
#ifdef SKY_LIGHT
    lights.sky = air_sky_irradiance(air, n, transmittance);
#else
    lights.sky = vec3(0.0);
#endif
    return lights;
}
