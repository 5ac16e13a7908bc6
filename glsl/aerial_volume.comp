#version 450
// feature: MULTIPLE_SCATTERING
// The aerial-perspective volume (Hillaire 2020): for each column of a grid
// of view directions through the screen, the air in front of every slice
// along it: the light scattered towards the camera (every order the frame
// draws, the column's phases applied, times the sun's irradiance) and the
// transmittance from the camera. One invocation marches one column once,
// from the camera through all the slices, writing each as it passes it:
// a column costs about as much as one pixel's march, and the atmosphere
// subpass then reads the volume at each surface instead of marching
// (include/atmosphere.glsl has the layout and the slice spacing).
//
// The march is the pixel march's (include/atmosphere.glsl, march_from):
// midpoint sums for the scattering, the trapezoid rule for the view's
// optical depth, the same sun lookups; its samples are spread over the
// slices, ceil(samples / slices) in each, so a column has at least the
// samples a pixel's ray has.

#include "atmosphere.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = AERIAL_VOLUME_WRITE_BINDING, rgba32f) uniform writeonly image3D aerial_volume_out;

void main() {
    ivec3 size = imageSize(aerial_volume_out);
    int w = size.x / 2;
    int slices = size.z;
    int x = int(gl_GlobalInvocationID.x);
    int y = int(gl_GlobalInvocationID.y);
    if (x >= w || y >= size.y) {
        return;
    }
    // The column through the centre of texel (x, y) of a w x h image
    // covering the screen, as atmosphere.frag forms a pixel's ray.
    vec2 ndc = (vec2(x, y) + 0.5) / vec2(w, size.y) * 2.0 - 1.0;
    vec3 d = normalize(sky.forward.xyz + sky.right.xyz * ndc.x - sky.up.xyz * ndc.y);
    vec2 phase = phases(dot(d, sky.sun_direction.xyz));

    // The stretch of the column in the air, [0, end] from o: from space it
    // starts at the entry point (distances shifted by `shift`), where
    // |o|^2 - Rb^2 is exact, as in march_from; it ends where the column
    // leaves the air. A surface behind the planet's ground marches its own
    // ray (atmosphere.frag), but a column that meets the ground still
    // serves pixels beside it whose rays pass just above the ground, as
    // the filter blends neighbouring columns: so it goes on through the
    // ground as if along it, its altitude held at 0 (stopped at the
    // ground instead, it darkened the bottom rows of objects beyond the
    // horizon by up to 1.6 %).
    vec3 o = sky.origin.xyz;
    float c_bottom = sky.terms.x;
    float t0, t1;
    bool meets = sphere(o, d, sky.terms.y, STATIC_RADII.y, t0, t1) && t1 > 0.0;
    float shift = 0.0;
    if (meets && t0 > 0.0) {
        o = o + t0 * d;
        c_bottom = STATIC_RADII.z * STATIC_RADII.z;
        shift = t0;
    }
    float end = meets ? t1 - shift : 0.0;
    float b = dot(o, d);

    int per_slice = max(1, (int(STATIC_RADII.w) + slices - 1) / slices);
    vec3 inscatter = vec3(0.0);
    vec3 tau = vec3(0.0);
    float r;
    float previous_t = 0.0;
    vec3 previous_extinction = extinction(densities(altitude(c_bottom, b, 0.0, r)));
    float slice_start = 0.0;
    for (int k = 0; k < slices; ++k) {
        float slice_end = aerial_slice_distance(float(k), float(slices)) - shift;
        float a = clamp(slice_start, 0.0, end);
        float z = clamp(slice_end, 0.0, end);
        float dt = (z - a) / float(per_slice);
        for (int i = 0; i < per_slice; ++i) {
            float t = a + (float(i) + 0.5) * dt;
            float h = altitude(c_bottom, b, t, r);
            h = max(h, 0.0);
            r = max(r, STATIC_RADII.x);
            vec3 rho = densities(h);
            vec3 e = extinction(rho);
            tau += 0.5 * (previous_extinction + e) * (t - previous_t);
            previous_t = t;
            previous_extinction = e;
            bool lit;
            vec3 sun_tau = sun_optical_depth(h, r, o + t * d, lit);
            vec3 single = (STATIC_RAYLEIGH.xyz * (rho.x * phase.x)
                + STATIC_MIE_SCATTERING.xyz * (rho.y * phase.y))
                * exp(-sun_tau) * (lit ? 1.0 : 0.0);
#ifdef MULTIPLE_SCATTERING
            // The higher orders reach into the planet's shadow too, with no
            // phase (as in march_from).
            float mu_s = dot(o + t * d, SUN_DIRECTION) / r;
            single += (STATIC_RAYLEIGH.xyz * rho.x + STATIC_MIE_SCATTERING.xyz * rho.y)
                * multiple_scattering(h, mu_s);
#endif
            inscatter += single * exp(-tau) * dt;
        }
        // The view's optical depth to the slice itself.
        float h = max(altitude(c_bottom, b, z, r), 0.0);
        vec3 e = extinction(densities(h));
        tau += 0.5 * (previous_extinction + e) * (z - previous_t);
        previous_t = z;
        previous_extinction = e;
        imageStore(aerial_volume_out, ivec3(x, y, k), vec4(sky.sun_irradiance.xyz * inscatter, 0.0));
        imageStore(aerial_volume_out, ivec3(x + w, y, k), vec4(exp(-tau), 0.0));
        slice_start = slice_end;
    }
}
