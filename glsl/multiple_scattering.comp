#version 450
// Hillaire's (2020) multiple-scattering table: for an altitude h and a sun
// at cosine mu_s from the zenith, Psi_ms = L2 / (1 - f_ms), where L2 is the
// light scattered once (isotropically) or reflected once by the ground
// that arrives at the point, averaged over all directions, and f_ms the
// share of isotropic light the air around scatters back to it. Each
// further order is taken to scatter like the second, so the orders form
// a geometric series. The march then adds sigma_s(x) Psi_ms at every
// sample. Per unit solar irradiance; one invocation per texel.

// The bake's own sun (include/sun_frame.glsl).
#define SUN_DIRECTION vec3(0.0, 1.0, 0.0)
#include "atmosphere.glsl"
#include "sun_frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform writeonly image2D ms_out;

// Directions: strata of equal solid angle (cosine of the zenith angle ×
// azimuth over [0, pi]; the light is mirror-symmetric about the plane of
// the zenith and the sun). Steps along each, midpoints.
const int ZENITH_STRATA = 16;
const int AZIMUTH_STRATA = 8;
const int STEPS = 40;

void main() {
    ivec2 size = imageSize(ms_out);
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (xy.x >= size.x || xy.y >= size.y) {
        return;
    }
    vec2 at = sun_table_texel(size, xy.x, xy.y);
    SunFrame f = sun_frame(at.x, at.y);
    float rb = STATIC_RADII.x;
    float rt = STATIC_RADII.y;
    vec3 second = vec3(0.0);
    vec3 transfer = vec3(0.0);
    for (int i = 0; i < ZENITH_STRATA; ++i) {
        float cos_zenith = 1.0 - 2.0 * (float(i) + 0.5) / float(ZENITH_STRATA);
        for (int j = 0; j < AZIMUTH_STRATA; ++j) {
            float phi = PI * (float(j) + 0.5) / float(AZIMUTH_STRATA);
            vec3 d = sun_frame_direction(f, cos_zenith, phi);
            float t0, t1;
            sphere(f.o, d, f.c_top, rt, t0, t1);
            float t_end = max(t1, 0.0);
            float g0, g1;
            bool ground = sphere(f.o, d, f.c_bottom, rb, g0, g1) && g0 >= 0.0 && g1 > 0.0;
            if (ground) {
                t_end = g0;
            }
            float b = dot(f.o, d);
            float dt = t_end / float(STEPS);
            vec3 tau = vec3(0.0);
            vec3 lit_sum = vec3(0.0);
            vec3 sum = vec3(0.0);
            for (int k = 0; k < STEPS; ++k) {
                float t = (float(k) + 0.5) * dt;
                float r;
                float h = altitude(f.c_bottom, b, t, r);
                vec3 rho = densities(h);
                vec3 e = extinction(rho);
                vec3 view = exp(-(tau + 0.5 * dt * e));
                vec3 scattering = STATIC_RAYLEIGH.xyz * rho.x + STATIC_MIE_SCATTERING.xyz * rho.y;
                lit_sum += view * scattering * sun_transmittance(h, r, f.o + t * d) * dt;
                sum += view * scattering * dt;
                tau += e * dt;
            }
            // Once scattered with the isotropic phase 1 / (4 pi), plus the
            // ground lit by the sun.
            vec3 once = lit_sum / (4.0 * PI);
            if (ground) {
                once += exp(-tau) * ground_sunlit(f.o + t_end * d);
            }
            second += once;
            transfer += sum;
        }
    }
    // Each direction stands for 4 pi / N of the sphere, times the
    // isotropic phase 1 / (4 pi) of the scattering at the point: a plain
    // mean over the directions.
    float n = float(ZENITH_STRATA * AZIMUTH_STRATA);
    second /= n;
    transfer /= n;
    vec3 psi = second / max(vec3(1.0) - transfer, vec3(1e-3));
    imageStore(ms_out, xy, vec4(psi, 0.0));
}
