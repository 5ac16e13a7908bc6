#version 450
// The atmosphere subpass: for each pixel, single scattering along the view
// ray through the atmosphere (Rayleigh + Mie, ozone absorption) in front
// of whatever the surface pass drew there, or the analytic ground sphere,
// or the sun disc; the surface colour is attenuated by the view path
// (aerial perspective). Positions are camera-relative: the CPU gives the
// camera's offset from the planet centre and the exact c = |o|^2 - R^2 of
// both spheres (from doubles), so no planet-scale coordinate is squared in
// float32. Sun transmittance at each sample comes from the optical-depth
// table (manual bilinear of four texels); the view path's optical depth is
// accumulated on the same samples (trapezoid between samples, while the
// scattering uses each sample as a midpoint: two different rules, as the
// seed asks, so both sums do not share one bias).

layout(std140, set = 0, binding = 0) uniform Sky {
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
} sky;

layout(std430, set = 0, binding = 1) readonly buffer Table {
    vec4 texels[];
} table;

layout(input_attachment_index = 0, set = 1, binding = 0) uniform subpassInput surface;
layout(input_attachment_index = 1, set = 1, binding = 1) uniform subpassInput surface_depth;

layout(location = 0) out vec4 out_color;

// The table's mapping (0: horizon, Bruneton-style; 1: the seed's linear
// altitude × linear cosine) and filter (0: manual bilinear; 1: nearest).
layout(constant_id = 0) const int TABLE_MAPPING = 0;
layout(constant_id = 1) const int TABLE_FILTER = 0;

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

// Density integrals to the top (Rayleigh, Mie, ozone) from altitude h
// along cosine mu, directions into the ground excluded by the caller.
vec3 table_densities(float h, float mu) {
    float rb = sky.radii.x;
    float thickness = sky.radii.y - sky.radii.x;
    float big_h = sky.radii.z;
    h = clamp(h, 0.0, thickness);
    float x_mu;
    float x_r;
    if (TABLE_MAPPING == 1) {
        x_mu = clamp((1.0 - mu) * 0.5, 0.0, 1.0);
        x_r = clamp(h / thickness, 0.0, 1.0);
    } else {
        float r = rb + h;
        float rho = sqrt(h * (2.0 * rb + h));
        float d_min = thickness - h;
        float disc = d_min * (sky.radii.y + r) + r * r * mu * mu;
        float d = max(-r * mu + sqrt(max(disc, 0.0)), 0.0);
        float d_max = rho + big_h;
        x_mu = clamp((d - d_min) / max(d_max - d_min, 1e-6), 0.0, 1.0);
        x_r = clamp(rho / big_h, 0.0, 1.0);
    }
    int w = int(sky.ozone_layer.z);
    int hh = int(sky.ozone_layer.w);
    float fx = x_mu * float(w - 1);
    float fy = x_r * float(hh - 1);
    vec3 v;
    if (TABLE_FILTER == 1) {
        v = table.texels[int(round(fy)) * w + int(round(fx))].xyz;
    } else {
        int x0 = min(int(floor(fx)), w - 2);
        int y0 = min(int(floor(fy)), hh - 2);
        float ax = fx - float(x0);
        float ay = fy - float(y0);
        // Manual bilinear from four texel fetches (32-bit floats).
        vec3 t00 = table.texels[y0 * w + x0].xyz;
        vec3 t10 = table.texels[y0 * w + x0 + 1].xyz;
        vec3 t01 = table.texels[(y0 + 1) * w + x0].xyz;
        vec3 t11 = table.texels[(y0 + 1) * w + x0 + 1].xyz;
        v = mix(mix(t00, t10, ax), mix(t01, t11, ax), ay);
    }
    float offset = sky.ground_albedo.w;
    return vec3(
        max(exp(v.x - h * sky.rayleigh.w) - offset, 0.0),
        max(exp(v.y - h * sky.mie_scattering.w) - offset, 0.0),
        v.z);
}

// Optical depth from a point at altitude h (radius r, position p relative
// to the centre) to the sun; lit is false in the planet's shadow.
vec3 sun_optical_depth(float h, float r, vec3 p, out bool lit) {
    float mu = dot(p, sky.sun_direction.xyz) / r;
    float horizon = -sqrt(max(h, 0.0) * (2.0 * sky.radii.x + max(h, 0.0))) / r;
    lit = mu >= horizon;
    if (!lit) {
        return vec3(0.0);
    }
    vec3 d = table_densities(h, mu);
    return sky.rayleigh.xyz * d.x + sky.mie_extinction.xyz * d.y + sky.ozone_absorption.xyz * d.z;
}

vec3 densities(float h) {
    float ozone = 0.0;
    float start = sky.ozone_absorption.w;
    float peak = sky.ozone_layer.x;
    float end = sky.ozone_layer.y;
    if (h > start && h < end) {
        ozone = h <= peak ? (h - start) / (peak - start) : (end - h) / (end - peak);
    }
    return vec3(exp(-h * sky.rayleigh.w), exp(-h * sky.mie_scattering.w), ozone);
}

vec3 extinction(vec3 rho) {
    return sky.rayleigh.xyz * rho.x + sky.mie_extinction.xyz * rho.y
        + sky.ozone_absorption.xyz * rho.z;
}

void main() {
    vec3 colour = subpassLoad(surface).rgb;
    float depth = subpassLoad(surface_depth).r;
    vec2 ndc = gl_FragCoord.xy * sky.viewport.zw * 2.0 - 1.0;
    vec3 ray = sky.forward.xyz + sky.right.xyz * ndc.x - sky.up.xyz * ndc.y;
    float ray_length = length(ray);
    vec3 d = ray / ray_length;
    // Reversed Z: depth 0 is the far plane (nothing drawn).
    float t_surface = depth > 0.0 ? sky.terms.w / (depth - sky.terms.z) * ray_length : INF;

    vec3 o = sky.origin.xyz;
    float rb = sky.radii.x;
    float rt = sky.radii.y;
    vec3 sun = sky.sun_direction.xyz;
    bool disc_visible = sky.sun_irradiance.w > 0.0 && dot(d, sun) >= sky.sun_direction.w;
    vec3 disc = disc_visible ? sky.sun_irradiance.xyz * sky.sun_irradiance.w : vec3(0.0);

    float t0, t1;
    if (!sphere(o, d, sky.terms.y, rt, t0, t1) || t1 <= 0.0) {
        // The ray misses the atmosphere: the pixel is unchanged, plus the
        // sun seen from space.
        out_color = vec4(colour + (t_surface == INF ? disc : vec3(0.0)), 1.0);
        return;
    }
    // From outside, start at the entry point, where |o|^2 - Rb^2 is
    // exactly Rt^2 - Rb^2: altitudes along the ray stay precise.
    float c_bottom = sky.terms.x;
    float shift = 0.0;
    bool inside = t0 <= 0.0;
    if (!inside) {
        o = o + t0 * d;
        c_bottom = sky.radii.z * sky.radii.z;
        shift = t0;
    }
    float t_end = t1 - shift;
    bool ground = false;
    float g0, g1;
    if (sphere(o, d, c_bottom, rb, g0, g1) && g0 > 0.0) {
        t_end = g0;
        ground = true;
    }
    bool object = false;
    if (t_surface - shift < t_end) {
        t_end = max(t_surface - shift, 0.0);
        ground = false;
        object = true;
    }

    float b = dot(o, d);
    float mu = dot(d, sun);
    float g = sky.mie_extinction.w;
    float phase_r = 3.0 / (16.0 * PI) * (1.0 + mu * mu);
    float phase_m = 3.0 / (8.0 * PI) * (1.0 - g * g) * (1.0 + mu * mu)
        / ((2.0 + g * g) * pow(1.0 + g * g - 2.0 * g * mu, 1.5));

    int n = int(sky.radii.w);
    vec3 inscatter = vec3(0.0);
    vec3 tau = vec3(0.0);
    float previous_t = 0.0;
    float h_start = c_bottom / (sqrt(rb * rb + c_bottom) + rb);
    vec3 previous_extinction = extinction(densities(h_start));
    for (int i = 0; i < n; ++i) {
        float u = (float(i) + 0.5) / float(n);
        // Inside the atmosphere samples crowd near the camera (t = L u^2),
        // where the density is highest; from space they are uniform.
        float t = inside ? t_end * u * u : t_end * u;
        float dt = inside ? t_end * 2.0 * u / float(n) : t_end / float(n);
        // r^2 - Rb^2 = c + t (2b + t), so the altitude needs no
        // planet-scale difference.
        float r2_minus = c_bottom + t * (2.0 * b + t);
        float r = sqrt(max(rb * rb + r2_minus, 0.0));
        float h = r2_minus / (r + rb);
        vec3 rho = densities(h);
        vec3 e = extinction(rho);
        tau += 0.5 * (previous_extinction + e) * (t - previous_t);
        previous_t = t;
        previous_extinction = e;
        bool lit;
        vec3 sun_tau = sun_optical_depth(h, r, o + t * d, lit);
        vec3 scattering = sky.rayleigh.xyz * (rho.x * phase_r)
            + sky.mie_scattering.xyz * (rho.y * phase_m);
        // One exponential for both paths; no branch (lanes stay together).
        inscatter += scattering * exp(-(tau + sun_tau)) * (lit ? dt : 0.0);
    }
    {
        float r2_minus = c_bottom + t_end * (2.0 * b + t_end);
        float r = sqrt(max(rb * rb + r2_minus, 0.0));
        float h = r2_minus / (r + rb);
        tau += 0.5 * (previous_extinction + extinction(densities(h))) * (t_end - previous_t);
    }
    vec3 transmittance = exp(-tau);
    inscatter *= sky.sun_irradiance.xyz;

    vec3 background = vec3(0.0);
    if (object) {
        background = colour;
    } else if (ground) {
        vec3 p = o + t_end * d;
        vec3 normal = normalize(p);
        float cos_sun = dot(normal, sun);
        bool lit;
        vec3 sun_tau = sun_optical_depth(0.0, rb, p, lit);
        if (cos_sun > 0.0 && lit) {
            background = sky.ground_albedo.xyz / PI * cos_sun * sky.sun_irradiance.xyz
                * exp(-sun_tau);
        }
    } else {
        background = colour + disc;
    }
    out_color = vec4(max(background * transmittance + inscatter, vec3(0.0)), 1.0);
}
