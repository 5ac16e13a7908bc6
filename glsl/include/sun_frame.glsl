// A point of the bakes of the multiple-scattering and sky-irradiance
// tables (multiple_scattering.comp, sky_irradiance.comp): each texel is an
// altitude h and a cosine mu_s of the sun's zenith angle, placed under a
// fixed sun (SUN_DIRECTION, defined by each bake before it includes
// atmosphere.glsl, whose sun lookups then serve unchanged). The tables
// depend on (h, mu_s) alone, so they hold for any sun, bit for bit: a
// frame that moves the sun keeps them, and draws what a new renderer
// would.
struct SunFrame {
    vec3 o;         // the point, relative to the centre
    float c_bottom; // |o|^2 - Rb^2, exact
    float c_top;    // |o|^2 - Rt^2, exact
    vec3 up;        // o / |o|
    vec3 towards;   // horizontal, in the plane of the zenith and the sun, away from it
    vec3 across;    // horizontal, perpendicular to that plane
};

SunFrame sun_frame(float h, float mu_s) {
    vec3 s = SUN_DIRECTION;
    vec3 a = abs(s.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    vec3 e = normalize(cross(s, a));
    float sine = sqrt(max(1.0 - mu_s * mu_s, 0.0));
    float rb = STATIC_RADII.x;
    float rt = STATIC_RADII.y;
    float r = rb + h;
    SunFrame f;
    f.up = mu_s * s + sine * e;
    f.towards = mu_s * e - sine * s;
    f.across = cross(s, e);
    f.o = r * f.up;
    f.c_bottom = h * (2.0 * rb + h);
    f.c_top = -(rt - r) * (rt + r);
    return f;
}

// The direction at cosine cos_zenith from the zenith and azimuth phi from
// the side away from the sun.
vec3 sun_frame_direction(SunFrame f, float cos_zenith, float phi) {
    float sine = sqrt(max(1.0 - cos_zenith * cos_zenith, 0.0));
    return cos_zenith * f.up + sine * (cos(phi) * f.towards + sin(phi) * f.across);
}

// The sun's transmittance to p (relative to the centre) at altitude h and
// radius r, zero in the planet's shadow.
vec3 sun_transmittance(float h, float r, vec3 p) {
    bool lit;
    vec3 tau = sun_optical_depth(h, r, p, lit);
    return lit ? exp(-tau) : vec3(0.0);
}

// The ground at p lit by the sun alone, per unit solar irradiance.
vec3 ground_sunlit(vec3 p) {
    float cos_sun = max(dot(normalize(p), SUN_DIRECTION), 0.0);
    return STATIC_GROUND_ALBEDO.xyz / PI * cos_sun * sun_transmittance(0.0, STATIC_RADII.x, p);
}
