#version 450
// The sky-irradiance table: for an altitude h and a sun at cosine mu_s
// from the zenith, the irradiance on a horizontal surface from the whole
// sky (every order of scattering, through the multiple-scattering table,
// and the sunlit ground seen below the horizon from above it), the
// direct sun excluded. Per unit solar irradiance; one invocation per
// texel. It lights the ground (include/atmosphere.glsl, GROUND_SKY_LIGHT).

#define MULTIPLE_SCATTERING
#define BAKING_SKY_IRRADIANCE
// The bake's own sun (include/sun_frame.glsl).
#define SUN_DIRECTION vec3(0.0, 1.0, 0.0)
#include "atmosphere.glsl"
#include "sun_frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform writeonly image2D irradiance_out;

// Directions over the upper hemisphere, cosine-weighted strata (sin^2 of
// the zenith angle evenly spaced) × azimuth over [0, pi] (the sky is
// mirror-symmetric about the plane of the zenith and the sun). 32 zenith
// strata, not 8: the sky brightens steeply towards the horizon, and one
// stratum over its last 20 degrees left the irradiance about 1 % (blue)
// low.
const int ZENITH_STRATA = 32;
const int AZIMUTH_STRATA = 16;

void main() {
    ivec2 size = imageSize(irradiance_out);
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (xy.x >= size.x || xy.y >= size.y) {
        return;
    }
    vec2 at = sun_table_texel(size, xy.x, xy.y);
    SunFrame f = sun_frame(at.x, at.y);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < ZENITH_STRATA; ++i) {
        float sin2 = (float(i) + 0.5) / float(ZENITH_STRATA);
        float cos_zenith = sqrt(1.0 - sin2);
        for (int j = 0; j < AZIMUTH_STRATA; ++j) {
            float phi = PI * (float(j) + 0.5) / float(AZIMUTH_STRATA);
            vec3 d = sun_frame_direction(f, cos_zenith, phi);
            Path path = march_from(f.o, f.c_bottom, f.c_top, d, INF, 0);
            vec2 phase = phases(dot(d, SUN_DIRECTION));
            vec3 radiance = phase.x * path.rayleigh + phase.y * path.mie + path.multiple;
            if (path.end == END_GROUND) {
                radiance += path.transmittance * ground_sunlit(f.o + path.t_end * d);
            }
            sum += radiance;
        }
    }
    // Cosine-weighted directions: the irradiance is pi times the mean
    // radiance.
    vec3 irradiance = PI * sum / float(ZENITH_STRATA * AZIMUTH_STRATA);
    imageStore(irradiance_out, xy, vec4(irradiance, 0.0));
}
