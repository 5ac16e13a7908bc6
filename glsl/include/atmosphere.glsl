// Single scattering through a spherical atmosphere, shared by the
// atmosphere subpass (glsl/atmosphere.frag) and the sky-view table
// (glsl/sky_view.comp): the uniform block, the optical-depth table, the
// cancellation-free ray-sphere test, the ray march, and the sky-view
// table's layout, so both shaders march and map directions identically.
//
// Positions are camera-relative: the CPU gives the camera's offset from
// the planet centre and the exact c = |o|^2 - R^2 of both spheres (from
// doubles), so no planet-scale coordinate is squared in float32. Sun
// transmittance at each sample comes from the optical-depth table (manual
// bilinear of four texels); the view path's optical depth is accumulated
// on the same samples (trapezoid between samples, while the scattering
// uses each sample as a midpoint: two different rules, as the seed asks,
// so both sums do not share one bias).
//
// With MULTIPLE_SCATTERING defined, every march sample also gathers the
// light scattered two or more times, from Hillaire's (2020)
// multiple-scattering table (baked by multiple_scattering.comp), and the
// ground is lit by the sky as well as the sun (GROUND_SKY_LIGHT, from the
// sky-irradiance table baked by sky_irradiance.comp). Without it none of
// that code is compiled, and the single-scattering image is unchanged.
#include "constants.glsl"

// The set of the block and tables below, and an offset added to this
// file's specialization-constant ids: 0 and 0 in the atmosphere's own
// shaders; the object shaders, whose set 0 and low ids are their own,
// define both first (object_air.glsl).
#ifndef SKY_BLOCK_SET
#define SKY_BLOCK_SET 0
#endif
#ifndef SKY_SPEC_OFFSET
#define SKY_SPEC_OFFSET 0
#endif

#if defined(MULTIPLE_SCATTERING) && !defined(BAKING_SKY_IRRADIANCE)
#define GROUND_SKY_LIGHT
#endif

// The direction towards the sun that the march's sun lookups use: the
// frame's, unless a table bake fixes its own (include/sun_frame.glsl), so
// that the tables do not depend on the sun a frame happened to have.
#ifndef SUN_DIRECTION
#define SUN_DIRECTION sky.sun_direction.xyz
#endif

layout(std140, set = SKY_BLOCK_SET, binding = 0) uniform Sky {
    vec4 forward;          // xyz: camera forward (unit)
    vec4 right;            // xyz: camera right * aspect / f
    vec4 up;               // xyz: camera up / f
    vec4 origin;           // xyz: camera - planet centre; w: its length
    vec4 terms;            // x: |o|^2 - Rb^2, y: |o|^2 - Rt^2 (exact), z, w: depth = z + w / view_depth
    vec4 radii;            // x: Rb, y: Rt, z: sqrt(Rt^2 - Rb^2), w: sample count
    vec4 rayleigh;         // xyz: scattering; w: 1 / scale height
    vec4 mie_scattering;   // xyz; w: 1 / scale height
    vec4 mie_extinction;   // xyz; w: g
    vec4 ozone_absorption; // xyz; w: layer start
    vec4 ozone_layer;      // x: peak, y: end; z, w: table width, height
    vec4 sun_direction;    // xyz: towards the sun; w: cos(angular radius)
    vec4 sun_irradiance;   // xyz; w: disc radiance per unit irradiance (0: no disc)
    vec4 ground_albedo;    // xyz; w: the table's log offset
    vec4 viewport;         // width, height, 1/width, 1/height
    vec4 zenith;           // xyz: the camera's up (from the planet centre); w: nadir angle of the ground's horizon
    vec4 azimuth_zero;     // xyz: unit, perpendicular to zenith, towards the sun; w: nadir angle of the atmosphere's edge (pi inside)
    vec4 sky_view;         // x, y: sky-view table width, height (directions)
} sky;

// The block's fields the frame never changes (the atmosphere, the tables'
// sizes, the viewport) are read from specialization constants instead, 4
// per field from SPEC_SKY_STATIC on, in the order glsl/interface.toml
// gives (read as STATIC_RADII and so on): lavapipe reads a uniform block
// once per pixel and per march sample, where constants cost nothing
// (static_lights.glsl).
// The camera, the sun and the table frame stay in the block.
DECLARE_SKY_STATIC(SKY_SPEC_OFFSET)

// The optical-depth table, one RGBA32F texel per (direction, altitude),
// read with texelFetch, or filtered by the sampler (TABLE_FILTER 2).
layout(set = SKY_BLOCK_SET, binding = 1) uniform sampler2D od_table;

#ifdef MULTIPLE_SCATTERING
// Hillaire's Psi_ms per unit solar irradiance, by (cosine of the sun's
// zenith angle, altitude): the isotropic radiance of every order above
// the first that a unit of scattering coefficient sends on.
layout(set = SKY_BLOCK_SET, binding = 4) uniform sampler2D ms_table;
#endif
#ifdef GROUND_SKY_LIGHT
// The sky's irradiance on a horizontal surface per unit solar irradiance,
// by (cosine of the sun's zenith angle, altitude): every order of the
// sky's light, the direct sun excluded.
layout(set = SKY_BLOCK_SET, binding = 5) uniform sampler2D irradiance_table;
#endif
// Whether the two tables above are read through the sampler's bilinear
// filter (the device filters RGBA32F) or by four fetches and a blend.
layout(constant_id = SKY_SPEC_OFFSET + SPEC_SUN_TABLES_LINEAR_FILTER) const bool SUN_TABLES_LINEAR_FILTER = false;

// The table's mapping (0: horizon, Bruneton-style, split at the
// horizontal; 1: the seed's linear altitude × linear cosine) and filter
// (0: manual bilinear; 1: nearest; 2: the sampler's bilinear filter).
layout(constant_id = SKY_SPEC_OFFSET + SPEC_TABLE_MAPPING) const int TABLE_MAPPING = 0;
layout(constant_id = SKY_SPEC_OFFSET + SPEC_TABLE_FILTER) const int TABLE_FILTER = 0;
// The ozone's integral towards the sun: in closed form (true) or from the
// table's third channel (false).
layout(constant_id = SKY_SPEC_OFFSET + SPEC_OZONE_EXACT) const bool OZONE_EXACT = true;

const float PI = 3.14159265358979;
const float INF = 1.0 / 0.0;

// Roots of |o + t d| = R, nearest first; c = |o|^2 - R^2 given exactly.
// The discriminant is R^2 - p^2 from the distance p of the line to the
// centre, as (R - p)(R + p); the smaller root is c / q (no cancellation).
bool sphere(vec3 o, vec3 d, float c, float radius, out float t0, out float t1) {
    float b = dot(o, d);
    float p = length(o - b * d);
    float disc = (radius - p) * (radius + p);
    if (disc < 0.0) {
        return false;
    }
    float q = -b - (b >= 0.0 ? 1.0 : -1.0) * sqrt(disc);
    if (q == 0.0) {
        t0 = 0.0;
        t1 = 0.0;
        return true;
    }
    float a = q;
    float e = c / q;
    t0 = min(a, e);
    t1 = max(a, e);
    return true;
}

// The table's texels at texel coordinates (fx, fy) (centres on integers),
// filtered between rows 0 and last_row.
vec3 table_texels(float fx, float fy, int last_row) {
    int w = int(STATIC_OZONE_LAYER.z);
    int hh = int(STATIC_OZONE_LAYER.w);
    if (TABLE_FILTER == 1) {
        return texelFetch(od_table, ivec2(round(fx), round(fy)), 0).xyz;
    }
    if (TABLE_FILTER == 2) {
        // Texel centres sit on x = 0 and x = 1 (see the table's mapping);
        // at a row's centre the sampler gives the next row no weight.
        return textureLod(od_table, (vec2(fx, fy) + 0.5) / vec2(w, hh), 0.0).xyz;
    }
    int x0 = min(int(floor(fx)), w - 2);
    int y0 = min(int(floor(fy)), last_row - 1);
    float ax = fx - float(x0);
    float ay = fy - float(y0);
    // Manual bilinear from four texel fetches (32-bit floats).
    vec3 t00 = texelFetch(od_table, ivec2(x0, y0), 0).xyz;
    vec3 t10 = texelFetch(od_table, ivec2(x0 + 1, y0), 0).xyz;
    vec3 t01 = texelFetch(od_table, ivec2(x0, y0 + 1), 0).xyz;
    vec3 t11 = texelFetch(od_table, ivec2(x0 + 1, y0 + 1), 0).xyz;
    return mix(mix(t00, t10, ax), mix(t01, t11, ax), ay);
}

// The table's last row (the horizontal ray) at texel coordinate fx,
// filtered along the row alone: two fetches.
vec3 table_row(float fx) {
    int w = int(STATIC_OZONE_LAYER.z);
    int hh = int(STATIC_OZONE_LAYER.w);
    if (TABLE_FILTER == 1) {
        return texelFetch(od_table, ivec2(round(fx), hh - 1), 0).xyz;
    }
    if (TABLE_FILTER == 2) {
        return textureLod(od_table, vec2(fx + 0.5, float(hh) - 0.5) / vec2(w, hh), 0.0).xyz;
    }
    int x0 = min(int(floor(fx)), w - 2);
    vec3 t0 = texelFetch(od_table, ivec2(x0, hh - 1), 0).xyz;
    vec3 t1 = texelFetch(od_table, ivec2(x0 + 1, hh - 1), 0).xyz;
    return mix(t0, t1, fx - float(x0));
}

// Density integrals from a filtered texel value v stored for altitude h.
vec3 table_decode(vec3 v, float h) {
    float offset = STATIC_GROUND_ALBEDO.w;
    return vec3(
        max(exp(v.x - h * STATIC_RAYLEIGH.w) - offset, 0.0),
        max(exp(v.y - h * STATIC_MIE_SCATTERING.w) - offset, 0.0),
        v.z);
}

// f = s^2 / (s^2 + (1 - s)^2) on [0, 1]: samples evenly spaced in s crowd
// towards both ends of f, where f near 0 grows as s^2 and near 1 as
// 1 - (1 - s)^2. The table's altitude axis and the sky view's rows from
// space use it.
float crowd_ends(float s) {
    return s * s / (s * s + (1.0 - s) * (1.0 - s));
}

// Inverse of crowd_ends: s = sqrt(f) / (sqrt(f) + sqrt(1 - f)).
float crowd_ends_inverse(float f) {
    float a = sqrt(f);
    return a / (a + sqrt(1.0 - f));
}

// The horizon mapping's altitude axis (src/atmosphere/table.rs): the
// texel coordinate of altitude h is crowd_ends_inverse(h / thickness).
float table_altitude_unit(float h, float thickness) {
    return crowd_ends_inverse(clamp(h / thickness, 0.0, 1.0));
}

// The multiple-scattering and sky-irradiance tables share one layout
// (src/render/sun_tables.rs): columns by the cosine mu_s of the sun's
// zenith angle, column coordinate 0.5 + 0.5 sign(mu_s) sqrt(|mu_s|),
// crowded towards the horizon, where both fall steeply as the sun sets (a
// linear mu_s axis made twilight up to 2.5 times too bright at 32
// columns); rows by altitude, row coordinate sqrt(h / thickness), crowded
// towards the ground where the air is dense; texel centres on both ends
// of both axes.
vec2 sun_table_coords(ivec2 size, float h, float mu_s) {
    float thickness = STATIC_RADII.y - STATIC_RADII.x;
    float m = clamp(mu_s, -1.0, 1.0);
    float fx = (0.5 + 0.5 * sign(m) * sqrt(abs(m))) * float(size.x - 1);
    float fy = sqrt(clamp(h / thickness, 0.0, 1.0)) * float(size.y - 1);
    return vec2(fx, fy);
}

// The altitude and sun cosine of texel (x, y) of such a table.
vec2 sun_table_texel(ivec2 size, int x, int y) {
    float thickness = STATIC_RADII.y - STATIC_RADII.x;
    float s = float(y) / float(size.y - 1);
    float u = float(x) / float(size.x - 1) * 2.0 - 1.0;
    return vec2(thickness * s * s, sign(u) * u * u);
}

#if defined(MULTIPLE_SCATTERING) || defined(GROUND_SKY_LIGHT)
// Bilinear between the four texels around f (texel units, centres on
// integers) of a table of at least 2 x 2 texels.
vec3 sun_table_read(sampler2D table, vec2 f) {
    ivec2 size = textureSize(table, 0);
    if (SUN_TABLES_LINEAR_FILTER) {
        return textureLod(table, (f + 0.5) / vec2(size), 0.0).xyz;
    }
    int x0 = min(int(floor(f.x)), size.x - 2);
    int y0 = min(int(floor(f.y)), size.y - 2);
    float ax = f.x - float(x0);
    float ay = f.y - float(y0);
    vec3 t00 = texelFetch(table, ivec2(x0, y0), 0).xyz;
    vec3 t10 = texelFetch(table, ivec2(x0 + 1, y0), 0).xyz;
    vec3 t01 = texelFetch(table, ivec2(x0, y0 + 1), 0).xyz;
    vec3 t11 = texelFetch(table, ivec2(x0 + 1, y0 + 1), 0).xyz;
    return mix(mix(t00, t10, ax), mix(t01, t11, ax), ay);
}
#endif

#ifdef MULTIPLE_SCATTERING
// Psi_ms at altitude h with the sun at cosine mu_s from the zenith.
vec3 multiple_scattering(float h, float mu_s) {
    return sun_table_read(ms_table, sun_table_coords(textureSize(ms_table, 0), h, mu_s));
}
#endif

#ifdef GROUND_SKY_LIGHT
// The sky's irradiance on a horizontal surface at altitude h.
vec3 sky_irradiance(float h, float mu_s) {
    return sun_table_read(irradiance_table, sun_table_coords(textureSize(irradiance_table, 0), h, mu_s));
}
#endif

// A ray towards the sun from altitude h (clamped to the atmosphere) along
// cosine mu, also described from its lowest point (src/atmosphere/mod.rs,
// lowest_point): rho^2 = r^2 - Rb^2 there and its altitude, both negative
// for a ray whose line passes below the ground (-Rb^2 and -Rb for a
// vertical one). Chords computed from them depend on r^2 at the lowest
// point, which float32 holds to a few m^2.
struct SunRay {
    float h;
    float mu;
    float rho;      // sqrt(r^2 - Rb^2) at the start
    float rho2_low;
    float alt_low;
};

SunRay sun_ray(float h, float mu) {
    float rb = STATIC_RADII.x;
    SunRay ray;
    ray.h = clamp(h, 0.0, STATIC_RADII.y - rb);
    ray.mu = mu;
    float r = rb + ray.h;
    ray.rho = sqrt(ray.h * (2.0 * rb + ray.h));
    ray.rho2_low = (ray.rho - r * abs(mu)) * (ray.rho + r * abs(mu));
    ray.alt_low = ray.rho2_low / (sqrt(max(ray.rho2_low + rb * rb, 0.0)) + rb);
    return ray;
}

// Density integrals to the top (Rayleigh, Mie, ozone) along the ray,
// directions into the ground excluded by the caller. Horizon mapping: the
// rows but the last hold upward directions; a downward one is
// 2 F(lowest point) - (the upward ray at -mu), with F the horizontal row
// (src/atmosphere/table.rs says why). Both lookups run for every ray, with
// a select rather than a branch: a CPU driver runs both sides of a branch
// its lanes disagree on anyway.
vec3 table_densities(SunRay ray) {
    float rb = STATIC_RADII.x;
    float rt = STATIC_RADII.y;
    float thickness = rt - rb;
    float h = ray.h;
    int w = int(STATIC_OZONE_LAYER.z);
    int hh = int(STATIC_OZONE_LAYER.w);
    if (TABLE_MAPPING == 1) {
        float fx = clamp((1.0 - ray.mu) * 0.5, 0.0, 1.0) * float(w - 1);
        float fy = clamp(h / thickness, 0.0, 1.0) * float(hh - 1);
        return table_decode(table_texels(fx, fy, hh - 1), h);
    }
    float r = rb + h;
    float m = abs(ray.mu);
    // Distance to the top along m, and at its ends (straight up, horizontal),
    // from q = Rt^2 - r^2 without cancellation.
    float d_min = thickness - h;
    float q = d_min * (rt + r);
    float d = q / max(r * m + sqrt(q + r * r * m * m), 1e-30);
    float d_max = sqrt(q);
    float x_mu = clamp((d - d_min) / max(d_max - d_min, 1e-6), 0.0, 1.0);
    float fy = table_altitude_unit(h, thickness) * float(hh - 2);
    vec3 up = table_decode(table_texels(x_mu * float(w - 1), fy, hh - 2), h);
    // A downward ray that misses the ground has its lowest point above it.
    float alt_low = max(ray.alt_low, 0.0);
    float fx = table_altitude_unit(alt_low, thickness) * float(w - 1);
    vec3 horizontal = table_decode(table_row(fx), alt_low);
    return ray.mu >= 0.0 ? up : max(2.0 * horizontal - up, vec3(0.0));
}

// The ozone integral over [a, b] (distances from the start; empty when
// b <= a) of a density slope * (altitude - zero), by three-point
// Gauss-Legendre.
float ozone_interval(SunRay ray, float start, float a, float b, float zero, float slope) {
    float rb = STATIC_RADII.x;
    float mid = 0.5 * (a + b) + start;
    float half_length = 0.5 * max(b - a, 0.0);
    float sum = 0.0;
    for (int i = -1; i <= 1; i++) {
        float u = mid + float(i) * half_length * 0.7745966692;
        float rho2 = ray.rho2_low + u * u;
        float alt = rho2 / (sqrt(max(rho2 + rb * rb, 0.0)) + rb);
        sum += (i == 0 ? 8.0 / 9.0 : 5.0 / 9.0) * (alt - zero);
    }
    return half_length * slope * sum;
}

// Half the chord of the sphere at altitude k, from the lowest point;
// negative when the ray passes above it.
float ozone_half_chord(float k, float alt_low) {
    float disc = (k - alt_low) * (2.0 * STATIC_RADII.x + k + alt_low);
    return disc < 0.0 ? -1.0 : sqrt(disc);
}

// The ozone density integral along the ray to the top, in closed form
// (src/atmosphere/ozone.rs, the same arithmetic): within each shell of
// the tent the density is linear in the altitude, and the ray meets a
// shell in at most two intervals. Distances are from the lowest point
// (u = s + start).
float ozone_to_top(SunRay ray) {
    float thickness = STATIC_RADII.y - STATIC_RADII.x;
    float start = (STATIC_RADII.x + ray.h) * ray.mu;
    float end = ozone_half_chord(thickness, ray.alt_low) - start;
    float knots[3] = float[3](STATIC_OZONE_ABSORPTION.w, STATIC_OZONE_LAYER.x, STATIC_OZONE_LAYER.y);
    float sum = 0.0;
    for (int shell = 0; shell < 2; shell++) {
        float lower = knots[shell];
        float upper = min(knots[shell + 1], thickness);
        float zero = shell == 0 ? knots[0] : knots[2];
        float slope = shell == 0 ? 1.0 / (knots[1] - knots[0]) : -1.0 / (knots[2] - knots[1]);
        // A ray that passes above the upper sphere, or a shell above the
        // top, leaves both intervals empty.
        float outer = lower < upper ? ozone_half_chord(upper, ray.alt_low) : -1.0;
        float a = outer < 0.0 ? 0.0 : max(-outer - start, 0.0);
        float b = outer < 0.0 ? 0.0 : min(outer - start, end);
        // Split where the ray enters and leaves the lower sphere, or at the
        // lowest point when it passes above it.
        float inner = max(ozone_half_chord(lower, ray.alt_low), 0.0);
        sum += ozone_interval(ray, start, a, min(b, -inner - start), zero, slope);
        sum += ozone_interval(ray, start, max(a, inner - start), b, zero, slope);
    }
    return sum;
}

// Optical depth from a point at altitude h (radius r, position p relative
// to the centre) to the sun; lit is false in the planet's shadow.
vec3 sun_optical_depth(float h, float r, vec3 p, out bool lit) {
    SunRay ray = sun_ray(h, dot(p, SUN_DIRECTION) / r);
    lit = ray.mu >= -ray.rho / r;
    if (!lit) {
        return vec3(0.0);
    }
    vec3 d = table_densities(ray);
    // Uniform branch: an atmosphere without ozone skips the integral.
    if (OZONE_EXACT && any(greaterThan(STATIC_OZONE_ABSORPTION.xyz, vec3(0.0)))) {
        d.z = ozone_to_top(ray);
    }
    return STATIC_RAYLEIGH.xyz * d.x + STATIC_MIE_EXTINCTION.xyz * d.y + STATIC_OZONE_ABSORPTION.xyz * d.z;
}

vec3 densities(float h) {
    float ozone = 0.0;
    float start = STATIC_OZONE_ABSORPTION.w;
    float peak = STATIC_OZONE_LAYER.x;
    float end = STATIC_OZONE_LAYER.y;
    if (h > start && h < end) {
        ozone = h <= peak ? (h - start) / (peak - start) : (end - h) / (end - peak);
    }
    return vec3(exp(-h * STATIC_RAYLEIGH.w), exp(-h * STATIC_MIE_SCATTERING.w), ozone);
}

vec3 extinction(vec3 rho) {
    return STATIC_RAYLEIGH.xyz * rho.x + STATIC_MIE_EXTINCTION.xyz * rho.y
        + STATIC_OZONE_ABSORPTION.xyz * rho.z;
}

// Altitude at distance t along a ray with b = dot(o, d) and
// c = |o|^2 - Rb^2: r^2 - Rb^2 = c + t (2b + t), so the altitude needs no
// planet-scale difference.
float altitude(float c, float b, float t, out float r) {
    float r2_minus = c + t * (2.0 * b + t);
    float rb = STATIC_RADII.x;
    r = sqrt(max(rb * rb + r2_minus, 0.0));
    return r2_minus / (r + rb);
}

// Where a view ray ends.
const int END_SPACE = 0;   // it misses the atmosphere
const int END_SKY = 1;     // it leaves through the top
const int END_GROUND = 2;  // it hits the planet
const int END_SURFACE = 3; // it hits something the surface pass drew

// Single scattering along a view ray, per unit solar irradiance, with the
// phase functions left out: they depend only on the angle to the sun,
// constant along the ray, so the radiance is
// irradiance * (phase_r * rayleigh + phase_m * mie). The sky-view table
// stores exactly these, and every pixel applies its own phase.
struct Path {
    vec3 rayleigh;
    vec3 mie;
    vec3 transmittance; // from the camera to the ray's end
#ifdef MULTIPLE_SCATTERING
    vec3 multiple;      // every higher order, isotropic: no phase applies
#endif
    int end;
    float t_end;        // distance from the camera to the end
};

// Sample i of n along a march of length t_end (i may fall between
// samples): its distance and its step (x, y). Inside the atmosphere samples crowd near the camera
// (t = L u^2), where the density is highest; from space, rays that end on
// the ground crowd them towards it (march_from says why).
vec2 march_sample(float i, int n, float t_end, bool inside, bool crowd_ground) {
    float u = (i + 0.5) / float(n);
    float t_space = crowd_ground ? t_end * (1.0 - (1.0 - u) * (1.0 - u)) : t_end * u;
    float dt_space = crowd_ground ? t_end * 2.0 * (1.0 - u) / float(n) : t_end / float(n);
    float t = inside ? t_end * u * u : t_space;
    float dt = inside ? t_end * 2.0 * u / float(n) : dt_space;
    return vec2(t, dt);
}

#ifdef MULTIPLE_SCATTERING
// Consecutive march samples that share one read of the
// multiple-scattering table (march_from writes the four out).
const int MS_GROUP = 4;

// Psi_ms at distance t along a march with b = dot(o, d), c_bottom =
// |o|^2 - Rb^2, sun_b = dot(o, sun) and sun_d = dot(d, sun).
vec3 multiple_scattering_at(float t, float c_bottom, float b, float sun_b, float sun_d) {
    float r;
    float h = altitude(c_bottom, b, t, r);
    return multiple_scattering(h, (sun_b + t * sun_d) / r);
}
#endif

// The view path's running optical depth (trapezoid between samples) and
// where its last sample was.
struct MarchSums {
    vec3 tau;
    float previous_t;
    vec3 previous_extinction;
};

// One sample of the march at (t, dt) = sample_t along o + t d: the view's
// optical depth so far, and the sample's scattering added to the path
// (with MULTIPLE_SCATTERING, the higher orders' too, psi being Psi_ms
// there).
#ifdef MULTIPLE_SCATTERING
void march_step(inout Path path, inout MarchSums sums, vec3 o, vec3 d, float c_bottom, float b, vec2 sample_t, vec3 psi) {
#else
void march_step(inout Path path, inout MarchSums sums, vec3 o, vec3 d, float c_bottom, float b, vec2 sample_t) {
#endif
    float t = sample_t.x;
    float dt = sample_t.y;
    float r;
    float h = altitude(c_bottom, b, t, r);
    vec3 rho = densities(h);
    vec3 e = extinction(rho);
    sums.tau += 0.5 * (sums.previous_extinction + e) * (t - sums.previous_t);
    sums.previous_t = t;
    sums.previous_extinction = e;
    vec3 tau = sums.tau;
    bool lit;
    vec3 sun_tau = sun_optical_depth(h, r, o + t * d, lit);
#ifdef MULTIPLE_SCATTERING
    // The higher orders reach into the planet's shadow too: no lit test,
    // and the view's transmittance alone.
    vec3 view = exp(-tau) * dt;
    vec3 weight = view * exp(-sun_tau) * (lit ? 1.0 : 0.0);
    vec3 scattering = STATIC_RAYLEIGH.xyz * rho.x + STATIC_MIE_SCATTERING.xyz * rho.y;
    path.multiple += scattering * psi * view;
#else
    // One exponential for both paths; no branch (lanes stay together).
    vec3 weight = exp(-(tau + sun_tau)) * (lit ? dt : 0.0);
#endif
    path.rayleigh += STATIC_RAYLEIGH.xyz * (rho.x * weight);
    path.mie += STATIC_MIE_SCATTERING.xyz * (rho.y * weight);
}

// Marches the ray from the camera along d (unit) up to a surface at
// t_surface (INF: none). ground: 0 decides by the sphere test; 1 ignores
// the ground; 2 ends at the ground, or where the ray grazes it (the rows
// either side of the horizon in the sky-view table).
//
// march_from starts at o (relative to the centre) with c_bottom =
// |o|^2 - Rb^2 and c_top = |o|^2 - Rt^2 given exactly; march starts at
// the camera.
Path march_from(vec3 o, float c_bottom, float c_top, vec3 d, float t_surface, int ground_rule) {
    Path path;
    path.rayleigh = vec3(0.0);
    path.mie = vec3(0.0);
    path.transmittance = vec3(1.0);
#ifdef MULTIPLE_SCATTERING
    path.multiple = vec3(0.0);
#endif
    path.end = END_SPACE;
    path.t_end = INF;

    float rb = STATIC_RADII.x;
    float rt = STATIC_RADII.y;
    float t0, t1;
    if (!sphere(o, d, c_top, rt, t0, t1) || t1 <= 0.0) {
        return path;
    }
    // From outside, start at the entry point, where |o|^2 - Rb^2 is
    // exactly Rt^2 - Rb^2: altitudes along the ray stay precise.
    float shift = 0.0;
    bool inside = t0 <= 0.0;
    if (!inside) {
        o = o + t0 * d;
        c_bottom = STATIC_RADII.z * STATIC_RADII.z;
        shift = t0;
    }
    float b = dot(o, d);
    float t_end = t1 - shift;
    path.end = END_SKY;
    if (ground_rule != 1) {
        float g0, g1;
        // A ray that starts on the ground (c_bottom = 0) and points into
        // it hits it at distance 0: g0 = 0 < g1. One that points away has
        // g1 = 0 and misses.
        if (sphere(o, d, c_bottom, rb, g0, g1) && g0 >= 0.0 && g1 > 0.0) {
            t_end = g0;
            path.end = END_GROUND;
        } else if (ground_rule == 2) {
            // Grazing: the point of closest approach.
            t_end = max(-b, 0.0);
            path.end = END_GROUND;
        }
    }
    if (t_surface - shift < t_end) {
        t_end = max(t_surface - shift, 0.0);
        path.end = END_SURFACE;
    }
    path.t_end = t_end + shift;

    int n = int(STATIC_RADII.w);
    float h_start = c_bottom / (sqrt(rb * rb + c_bottom) + rb);
    vec3 previous_extinction = extinction(densities(h_start));
    // From space, a ray that ends on the ground crowds its samples towards
    // it, where the air is densest (t = L (1 - (1 - u)^2)): uniform samples
    // spread over a tall atmosphere's empty shell left the ground seen
    // from space 1.5 % dark. Other rays from space stay uniform: along a
    // limb ray the density is a smooth bump around its lowest point, which
    // the midpoint rule on uniform samples integrates best (crowding
    // towards that point cost the orbit's grazing row 1.3 % instead of
    // 0.6 %).
    bool crowd_ground = path.end == END_GROUND;
    MarchSums sums;
    sums.tau = vec3(0.0);
    sums.previous_t = 0.0;
    sums.previous_extinction = previous_extinction;
#ifdef MULTIPLE_SCATTERING
    // Psi_ms changes slowly along a ray (with the altitude and the sun's
    // angle; the density, which changes fast, is applied per sample): one
    // table read serves MS_GROUP consecutive samples, read at their middle
    // (it moves the earth scenes by at most 0.4 % of a pixel's radiance
    // against a read per sample). A read per sample was two thirds of what
    // multiple scattering added to the march. The group is written out,
    // not a loop or a branch: with the read behind a branch taken every
    // fourth sample, the march cost more than with a read per sample (a
    // CPU driver runs a branch's code under masks).
    float sun_b = dot(o, SUN_DIRECTION);
    float sun_d = dot(d, SUN_DIRECTION);
    int groups = n / MS_GROUP;
    for (int g = 0; g < groups; ++g) {
        float k = float(g * MS_GROUP);
        vec3 psi = multiple_scattering_at(march_sample(k + 0.5 * float(MS_GROUP - 1), n, t_end, inside, crowd_ground).x, c_bottom, b, sun_b, sun_d);
        march_step(path, sums, o, d, c_bottom, b, march_sample(k, n, t_end, inside, crowd_ground), psi);
        march_step(path, sums, o, d, c_bottom, b, march_sample(k + 1.0, n, t_end, inside, crowd_ground), psi);
        march_step(path, sums, o, d, c_bottom, b, march_sample(k + 2.0, n, t_end, inside, crowd_ground), psi);
        march_step(path, sums, o, d, c_bottom, b, march_sample(k + 3.0, n, t_end, inside, crowd_ground), psi);
    }
    // The last n mod MS_GROUP samples read the table each.
    for (int i = groups * MS_GROUP; i < n; ++i) {
        vec2 at = march_sample(float(i), n, t_end, inside, crowd_ground);
        march_step(path, sums, o, d, c_bottom, b, at, multiple_scattering_at(at.x, c_bottom, b, sun_b, sun_d));
    }
#else
    for (int i = 0; i < n; ++i) {
        march_step(path, sums, o, d, c_bottom, b, march_sample(float(i), n, t_end, inside, crowd_ground));
    }
#endif
    vec3 tau = sums.tau;
    float previous_t = sums.previous_t;
    previous_extinction = sums.previous_extinction;
    {
        float r;
        float h = altitude(c_bottom, b, t_end, r);
        tau += 0.5 * (previous_extinction + extinction(densities(h))) * (t_end - previous_t);
    }
    path.transmittance = exp(-tau);
    return path;
}

Path march(vec3 d, float t_surface, int ground_rule) {
    return march_from(sky.origin.xyz, sky.terms.x, sky.terms.y, d, t_surface, ground_rule);
}

// The Rayleigh phase and the Cornette-Shanks Mie phase at cosine mu
// between the view ray and the sun, both normalised over the sphere.
vec2 phases(float mu) {
    float g = STATIC_MIE_EXTINCTION.w;
    float phase_r = 3.0 / (16.0 * PI) * (1.0 + mu * mu);
    // x^1.5 as x * sqrt(x) (x >= (1 - |g|)^2 > 0): the same value without
    // pow's exp2(1.5 * log2(x)), which costs a CPU driver a polynomial each.
    float x = 1.0 + g * g - 2.0 * g * mu;
    float phase_m = 3.0 / (8.0 * PI) * (1.0 - g * g) * (1.0 + mu * mu)
        / ((2.0 + g * g) * (x * sqrt(x)));
    return vec2(phase_r, phase_m);
}

// The sun's direct light reflected by the ground at p (relative to the
// centre): zero where the sun is below the horizon or the planet hides it.
vec3 ground_direct(vec3 p) {
    vec3 normal = normalize(p);
    float cos_sun = dot(normal, SUN_DIRECTION);
    bool lit;
    vec3 sun_tau = sun_optical_depth(0.0, STATIC_RADII.x, p, lit);
    vec3 radiance = vec3(0.0);
    if (cos_sun > 0.0 && lit) {
        radiance = STATIC_GROUND_ALBEDO.xyz / PI * cos_sun * sky.sun_irradiance.xyz * exp(-sun_tau);
    }
    return radiance;
}

// The ground at p (relative to the centre, on the planet): the Lambertian
// albedo under the transmitted sun, and, with GROUND_SKY_LIGHT, under the
// sky's irradiance.
vec3 ground_radiance(vec3 p) {
    vec3 radiance = ground_direct(p);
#ifdef GROUND_SKY_LIGHT
    float cos_sun = dot(normalize(p), SUN_DIRECTION);
    radiance += STATIC_GROUND_ALBEDO.xyz / PI * sky.sun_irradiance.xyz * sky_irradiance(0.0, cos_sun);
#endif
    return radiance;
}

// The sky-view table: the Path sums for directions around the camera, by
// nadir angle (the angle from straight down) × azimuth from the sun's
// side (0..pi: the sky is symmetric about the plane of the zenith and the
// sun). Rows 0..H/2-1 are directions that miss the ground, from the
// horizon (row 0) to the zenith or, from space, the atmosphere's edge;
// rows H/2..H-1 hit the ground, from the horizon (row H/2) to the nadir.
// Both halves put a texel centre on the horizon and square their row
// coordinate, so texels crowd where the sky changes fastest and no filter
// mixes ground and sky. From space the sky half also crowds its rows
// towards the atmosphere's edge (f = s^2 / (s^2 + (1-s)^2)): there the
// path through the air grows as the square root of the angle from the
// edge, which rows spaced for the horizon missed by half on a pixel
// beside the edge. The table is an RGBA32F image three times as
// wide: the Rayleigh sums in columns 0..W-1, the Mie sums in W..2W-1, the
// transmittance in 2W..3W-1; with MULTIPLE_SCATTERING four times, the
// higher orders' sums in 3W..4W-1.

// Whether the camera is outside the atmosphere (its edge's nadir angle is
// pi inside; from space it is below pi/2 plus the planet's angular size).
bool sky_view_from_space() {
    return sky.azimuth_zero.w < 0.99 * PI;
}

// The sky half's row spacing: the fraction f of the way from the horizon
// to the zenith or the atmosphere's edge at row coordinate s in [0, 1].
float sky_view_row_fraction(float s) {
    if (sky_view_from_space()) {
        return crowd_ends(s);
    }
    return s * s;
}

// Inverse of sky_view_row_fraction.
float sky_view_row_unit(float f) {
    if (sky_view_from_space()) {
        return crowd_ends_inverse(f);
    }
    return sqrt(f);
}

// The direction of the texel at column x, row y.
vec3 sky_view_direction(int x, int y) {
    int w = int(STATIC_SKY_VIEW.x);
    int half_h = int(STATIC_SKY_VIEW.y) / 2;
    float s;
    float nadir;
    float horizon = sky.zenith.w;
    if (y < half_h) {
        s = float(y) / float(half_h - 1);
        nadir = horizon + (sky.azimuth_zero.w - horizon) * sky_view_row_fraction(s);
    } else {
        s = float(y - half_h) / float(half_h - 1);
        nadir = horizon - horizon * s * s;
    }
    float azimuth = PI * float(x) / float(w - 1);
    vec3 z = sky.zenith.xyz;
    vec3 ax = sky.azimuth_zero.xyz;
    vec3 ay = cross(z, ax);
    return -z * cos(nadir) + (ax * cos(azimuth) + ay * sin(azimuth)) * sin(nadir);
}

// Continuous texel coordinates (column, row) of direction d, and whether
// it is in the ground half. Angles from atan of a cross and a dot
// product stay precise near the horizon and the nadir, where acos of a
// dot product would not.
vec2 sky_view_coords(vec3 d, out bool below) {
    vec3 z = sky.zenith.xyz;
    float nadir = atan(length(cross(d, z)), -dot(d, z));
    vec3 ax = sky.azimuth_zero.xyz;
    float cx = dot(d, ax);
    float cy = abs(dot(d, cross(z, ax)));
    float azimuth = (cx == 0.0 && cy == 0.0) ? 0.0 : atan(cy, cx);
    int w = int(STATIC_SKY_VIEW.x);
    int half_h = int(STATIC_SKY_VIEW.y) / 2;
    float horizon = sky.zenith.w;
    below = nadir < horizon;
    float s;
    if (below) {
        s = sqrt(clamp((horizon - nadir) / horizon, 0.0, 1.0));
    } else {
        float span = sky.azimuth_zero.w - horizon;
        s = sky_view_row_unit(clamp((nadir - horizon) / max(span, 1e-30), 0.0, 1.0));
    }
    return vec2(azimuth / PI * float(w - 1), s * float(half_h - 1));
}

// The aerial-perspective volume (aerial_volume.comp writes it; the
// AERIAL_VOLUME variant of atmosphere.frag reads it): for a grid of view
// directions through the screen (columns, centred on the pixels of a
// WIDTH x HEIGHT image) and DEPTH distances along each, the light the air
// scatters towards the camera in front of that distance (every order,
// phases applied for the column's direction, times the sun's irradiance)
// and the transmittance from the camera. A 3D RGBA32F image two panels
// wide: in-scattering in columns 0..W-1, transmittance in W..2W-1.
//
// Slice k (0..DEPTH-1) lies at distance reach * ((k + 1) / DEPTH)^2 along
// its column, reach being the far side of the farthest object in view
// (sky.forward.w; src/render/plan.rs, aerial_volume_reach): slices crowd
// near the camera, where the air in front of a surface changes fastest
// relative to itself, and the camera itself is slice -1 (nothing
// scattered, transmittance 1). docs/atmosphere.md has the measurements
// behind the choice.

// The distance of slice coordinate k (texel centres on integers).
float aerial_slice_distance(float k, float slices) {
    float s = (k + 1.0) / slices;
    return sky.forward.w * s * s;
}

// The slice coordinate of distance t: the inverse of aerial_slice_distance.
float aerial_slice(float t, float slices) {
    return slices * sqrt(max(t, 0.0) / sky.forward.w) - 1.0;
}
