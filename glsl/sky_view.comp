#version 450
// feature: MULTIPLE_SCATTERING
// The sky-view table: the atmosphere's single-scattering sums (without the
// phase functions) for a grid of directions around the camera, marched
// exactly as the atmosphere subpass marches a pixel (include/atmosphere.glsl
// has the march and the table's layout). One invocation per direction.
// The MULTIPLE_SCATTERING variant writes a fourth panel: the sum of the
// higher orders.

#include "atmosphere.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 2, rgba32f) uniform writeonly image2D sky_view_table;

void main() {
    int w = int(STATIC_SKY_VIEW.x);
    int h = int(STATIC_SKY_VIEW.y);
    int x = int(gl_GlobalInvocationID.x);
    int y = int(gl_GlobalInvocationID.y);
    if (x >= w || y >= h) {
        return;
    }
    // Rows below the first half hit the ground; the first half's rows
    // never do, even the horizon row, which grazes it.
    vec3 d = sky_view_direction(x, y);
    bool ground = y >= h / 2;
    Path path = march(d, INF, ground ? 2 : 1);
    // Ground rows store the lit ground as seen through the air (its
    // radiance times the view transmittance): what a pixel would multiply
    // them into, smooth in the direction like the sums.
    vec3 third = path.transmittance;
    if (ground && path.end == END_GROUND) {
        third *= ground_radiance(sky.origin.xyz + path.t_end * d);
    }
    imageStore(sky_view_table, ivec2(x, y), vec4(path.rayleigh, 0.0));
    imageStore(sky_view_table, ivec2(x + w, y), vec4(path.mie, 0.0));
    imageStore(sky_view_table, ivec2(x + 2 * w, y), vec4(third, 0.0));
#ifdef MULTIPLE_SCATTERING
    imageStore(sky_view_table, ivec2(x + 3 * w, y), vec4(path.multiple, 0.0));
#endif
}
