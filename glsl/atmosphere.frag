#version 450
// feature: SKY_VIEW
// feature: MULTIPLE_SCATTERING
// feature: AERIAL_VOLUME
// feature: SHADOWS
// The atmosphere subpass: for each pixel, single scattering along the view
// ray through the atmosphere (Rayleigh + Mie, ozone absorption) in front
// of whatever the surface pass drew there, or the analytic ground sphere,
// or the sun disc; the surface colour is attenuated by the view path
// (aerial perspective). The march itself is in include/atmosphere.glsl.
//
// The SKY_VIEW variant is drawn only on pixels where the surface pass drew
// nothing, and reads the march's sums from the sky-view table
// (glsl/sky_view.comp, computed before the render pass for a few
// thousand directions) instead of marching: there the radiance depends on
// the direction only. The phase functions, the ground's lighting and the
// sun disc are still evaluated per pixel. The other variant marches.
//
// The MULTIPLE_SCATTERING variant adds every order of scattering above the
// first (isotropic, so no phase applies) and lights the ground by the sky
// too (include/atmosphere.glsl).
//
// The AERIAL_VOLUME variant (aerial_perspective = "volume") is drawn only
// on pixels with a surface (depth test LESS) and reads the air in front of
// it from the aerial-perspective volume (glsl/aerial_volume.comp) at the
// pixel and the surface's distance instead of marching (where the
// planet's ground hides the surface, at the ground's distance, with the
// ground's light behind it).

#include "atmosphere.glsl"
#include "shadow_map.glsl"

#ifdef SKY_VIEW
// Bilinear through the sampler where the device filters the table's
// RGBA32F linearly (one filtered lookup per sum instead of four fetches:
// on lavapipe the fetches were about 40 % of the pass), by hand otherwise.
layout(set = 0, binding = 3) uniform sampler2D sky_view_table;
layout(constant_id = SPEC_SKY_VIEW_HARDWARE_FILTER) const bool SKY_VIEW_HARDWARE_FILTER = false;
// Whether the frame draws transparent objects, the only surfaces that leave
// colour where depth still holds the far plane. Without them a sky pixel's
// surface colour is the clear colour, black, and is not read: on lavapipe
// an input-attachment read is about two empty passes' worth per full screen.
layout(constant_id = SPEC_TRANSPARENT_OVER_SKY) const bool TRANSPARENT_OVER_SKY = true;
#endif

#ifdef AERIAL_VOLUME
// Trilinear through the sampler where the device filters RGBA32F (the
// same check as the multiple-scattering tables'), by eight fetches a
// panel otherwise.
layout(set = 0, binding = AERIAL_VOLUME_BINDING) uniform sampler3D aerial_volume;
#endif

layout(input_attachment_index = 0, set = 1, binding = 0) uniform subpassInput surface;
layout(input_attachment_index = 1, set = 1, binding = 1) uniform subpassInput surface_depth;

layout(location = 0) out vec4 out_color;

// Both variants are drawn over the whole screen and split by the depth
// test: test before shading, so each pixel runs only one of them.
layout(early_fragment_tests) in;

#ifdef SKY_VIEW
// Manual bilinear between texel p and its right, lower and diagonal
// neighbours.
vec3 sky_view_bilinear(ivec2 p, float ax, float ay) {
    vec3 t00 = texelFetch(sky_view_table, p, 0).xyz;
    vec3 t10 = texelFetch(sky_view_table, p + ivec2(1, 0), 0).xyz;
    vec3 t01 = texelFetch(sky_view_table, p + ivec2(0, 1), 0).xyz;
    vec3 t11 = texelFetch(sky_view_table, p + ivec2(1, 1), 0).xyz;
    return mix(mix(t00, t10, ax), mix(t01, t11, ax), ay);
}

// The Path sums of direction d from the sky-view table (manual bilinear
// within the half of the table d falls in).
Path sky_view_path(vec3 d) {
    bool below;
    vec2 f = sky_view_coords(d, below);
    int w = int(STATIC_SKY_VIEW.x);
    int half_h = int(STATIC_SKY_VIEW.y) / 2;
    int x0 = min(int(floor(f.x)), w - 2);
    int y0 = min(int(floor(f.y)), half_h - 2);
    float ax = f.x - float(x0);
    float ay = f.y - float(y0);
    ivec2 p = ivec2(x0, (below ? half_h : 0) + y0);
    Path path;
    if (SKY_VIEW_HARDWARE_FILTER) {
        // The same position in texel units; f stays within its half and
        // its third of the table (0 <= f <= size - 1), so the filter never
        // blends across into a neighbouring sum or half.
        vec2 at = vec2(p) + vec2(ax, ay) + 0.5;
        vec2 texel = 1.0 / vec2(textureSize(sky_view_table, 0));
        path.rayleigh = texture(sky_view_table, at * texel).xyz;
        path.mie = texture(sky_view_table, (at + vec2(w, 0)) * texel).xyz;
        path.transmittance = texture(sky_view_table, (at + vec2(2 * w, 0)) * texel).xyz;
#ifdef MULTIPLE_SCATTERING
        path.multiple = texture(sky_view_table, (at + vec2(3 * w, 0)) * texel).xyz;
#endif
    } else {
        path.rayleigh = sky_view_bilinear(p, ax, ay);
        path.mie = sky_view_bilinear(p + ivec2(w, 0), ax, ay);
        path.transmittance = sky_view_bilinear(p + ivec2(2 * w, 0), ax, ay);
#ifdef MULTIPLE_SCATTERING
        path.multiple = sky_view_bilinear(p + ivec2(3 * w, 0), ax, ay);
#endif
    }
    path.end = below ? END_GROUND : END_SKY;
    path.t_end = INF;
    return path;
}
#endif

#ifdef AERIAL_VOLUME
// Manual trilinear of the panel starting at column `panel` around texel
// position f (texel units, centres on integers, within the panel).
vec3 aerial_volume_trilinear(vec3 f, int panel) {
    ivec3 p = ivec3(floor(f));
    ivec3 size = textureSize(aerial_volume, 0);
    p = min(p, ivec3(size.x / 2, size.y, size.z) - 2);
    vec3 a = f - vec3(p);
    p.x += panel;
    vec3 c000 = texelFetch(aerial_volume, p, 0).xyz;
    vec3 c100 = texelFetch(aerial_volume, p + ivec3(1, 0, 0), 0).xyz;
    vec3 c010 = texelFetch(aerial_volume, p + ivec3(0, 1, 0), 0).xyz;
    vec3 c110 = texelFetch(aerial_volume, p + ivec3(1, 1, 0), 0).xyz;
    vec3 c001 = texelFetch(aerial_volume, p + ivec3(0, 0, 1), 0).xyz;
    vec3 c101 = texelFetch(aerial_volume, p + ivec3(1, 0, 1), 0).xyz;
    vec3 c011 = texelFetch(aerial_volume, p + ivec3(0, 1, 1), 0).xyz;
    vec3 c111 = texelFetch(aerial_volume, p + ivec3(1, 1, 1), 0).xyz;
    vec3 near = mix(mix(c000, c100, a.x), mix(c010, c110, a.x), a.y);
    vec3 far = mix(mix(c001, c101, a.x), mix(c011, c111, a.x), a.y);
    return mix(near, far, a.z);
}

// The light scattered towards the camera in front of a surface at
// distance t along the pixel's ray, and the transmittance to it, from the
// volume: bilinear across the columns around the pixel, and linear in the
// distance between the two slices around t (the slices are not evenly
// spaced, so the slice coordinate is placed by distance, not by its
// square root); in front of the first slice, linear from the camera,
// where nothing is scattered yet and the transmittance is 1.
void aerial_volume_read(float t, out vec3 inscatter, out vec3 transmittance) {
    ivec3 size = textureSize(aerial_volume, 0);
    int w = size.x / 2;
    float slices = float(size.z);
    // Column coordinates of the pixel, clamped to the panel's texel
    // centres so no filter reaches into the other panel.
    vec2 column = clamp(gl_FragCoord.xy * STATIC_VIEWPORT.zw * vec2(w, size.y) - 0.5,
        vec2(0.0), vec2(w - 1, size.y - 1));
    float u = aerial_slice(t, slices);
    float k = clamp(floor(u), 0.0, slices - 2.0);
    float t0 = aerial_slice_distance(k, slices);
    float t1 = aerial_slice_distance(k + 1.0, slices);
    float slice = u < 0.0 ? 0.0 : k + clamp((t - t0) / (t1 - t0), 0.0, 1.0);
    // The share of the first slice's values in front of it.
    float share = u < 0.0 ? clamp(t / t0, 0.0, 1.0) : 1.0;
    vec3 f = vec3(column, slice);
    vec3 scattered;
    vec3 through;
    if (SUN_TABLES_LINEAR_FILTER) {
        vec3 texel = 1.0 / vec3(size);
        scattered = textureLod(aerial_volume, (f + 0.5) * texel, 0.0).xyz;
        through = textureLod(aerial_volume, (f + vec3(w, 0.0, 0.0) + 0.5) * texel, 0.0).xyz;
    } else {
        scattered = aerial_volume_trilinear(f, 0);
        through = aerial_volume_trilinear(f, w);
    }
    inscatter = scattered * share;
    transmittance = 1.0 - (1.0 - through) * share;
}
#endif

// With SHADOWS (the sun casts shadows), the fraction of the ground's
// light at p (relative to the centre; q the same point relative to the
// camera) that remains where objects shadow it: the sun's direct part is
// scaled by the shadow map's visibility, the sky's light is not.
vec3 ground_shadowing(vec3 p, vec3 q) {
#ifdef SHADOWS
    float hidden = 1.0 - shadow_visibility(q, normalize(p));
    if (hidden > 0.0) {
        vec3 full = ground_radiance(p);
        vec3 kept = full - hidden * ground_direct(p);
        return mix(vec3(1.0), kept / max(full, vec3(1e-30)), greaterThan(full, vec3(0.0)));
    }
#endif
    return vec3(1.0);
}

void main() {
#ifdef SKY_VIEW
    vec3 colour = TRANSPARENT_OVER_SKY ? subpassLoad(surface).rgb : vec3(0.0);
#else
    vec3 colour = subpassLoad(surface).rgb;
#endif
    vec2 ndc = gl_FragCoord.xy * STATIC_VIEWPORT.zw * 2.0 - 1.0;
    vec3 ray = sky.forward.xyz + sky.right.xyz * ndc.x - sky.up.xyz * ndc.y;
    float ray_length = length(ray);
    vec3 d = ray / ray_length;
#ifdef SKY_VIEW
    // The depth test passed this pixel only where depth holds the far
    // plane: no surface, and no depth read (an input attachment read is
    // about a tenth of this variant's cost on lavapipe).
    float t_surface = INF;
#else
    float depth = subpassLoad(surface_depth).r;
    // Reversed Z: depth 0 is the far plane (nothing drawn).
    float t_surface = depth > 0.0 ? sky.terms.w / (depth - sky.terms.z) * ray_length : INF;
#endif

    vec3 sun = sky.sun_direction.xyz;
    bool disc_visible = sky.sun_irradiance.w > 0.0 && dot(d, sun) >= sky.sun_direction.w;
    vec3 disc = disc_visible ? sky.sun_irradiance.xyz * sky.sun_irradiance.w : vec3(0.0);

    vec3 o = sky.origin.xyz;
    float t0, t1;
    if (!sphere(o, d, sky.terms.y, STATIC_RADII.y, t0, t1) || t1 <= 0.0) {
        // The ray misses the atmosphere: the pixel is unchanged, plus the
        // sun seen from space.
        out_color = vec4(colour + (t_surface == INF ? disc : vec3(0.0)), 1.0);
        return;
    }

#ifdef AERIAL_VOLUME
    // Drawn only where a surface is (depth test LESS). The volume holds the
    // air in front of it; where the planet's ground comes first the pixel
    // shows the lit ground, through the air the volume holds in front of
    // the ground (its columns run on through the ground at altitude 0, so
    // they hold the air up to it). The reach holds every object in view;
    // a surface beyond it (capped by the far plane) reads the last slice.
    // No march remains in this variant: with one kept for those pixels
    // the pass cost three times as much where no pixel took it (92.4 M
    // against 30.2 M instructions, assets/bench/aerial_terrain.toml at
    // 320x180; a CPU driver runs a branch's code under masks).
    float g0, g1;
    bool behind_ground = sphere(o, d, sky.terms.x, STATIC_RADII.x, g0, g1)
        && g0 >= 0.0 && g1 > 0.0 && g0 < t_surface;
    vec3 in_front = behind_ground
        ? ground_radiance(o + g0 * d) * ground_shadowing(o + g0 * d, g0 * d)
        : colour;
    vec3 air_light;
    vec3 air_transmittance;
    aerial_volume_read(min(behind_ground ? g0 : t_surface, sky.forward.w), air_light, air_transmittance);
    out_color = vec4(max(in_front * air_transmittance + air_light, vec3(0.0)), 1.0);
    return;
#endif
#ifdef SKY_VIEW
    // Drawn only where nothing is in front (depth test EQUAL far plane).
    Path path = sky_view_path(d);
#else
    Path path = march(d, t_surface, 0);
#endif

    vec2 phase = phases(dot(d, sun));
#ifdef MULTIPLE_SCATTERING
    vec3 inscatter = sky.sun_irradiance.xyz * (phase.x * path.rayleigh + phase.y * path.mie + path.multiple);
#else
    vec3 inscatter = sky.sun_irradiance.xyz * (phase.x * path.rayleigh + phase.y * path.mie);
#endif
    // What lies behind the air, times the view transmittance.
    vec3 seen;
    if (path.end == END_SURFACE) {
        seen = colour * path.transmittance;
    } else if (path.end == END_GROUND) {
#ifdef SKY_VIEW
        // The table's ground rows hold the lit ground already seen
        // through the air.
        seen = path.transmittance;
#else
        seen = ground_radiance(o + path.t_end * d) * path.transmittance;
#endif
#ifdef SHADOWS
        float t_ground = path.t_end;
#ifdef SKY_VIEW
        // The table gives no distance: the ground's, along the ray.
        float g0, g1;
        t_ground = sphere(o, d, sky.terms.x, STATIC_RADII.x, g0, g1) ? max(g0, 0.0) : INF;
#endif
        if (t_ground < INF) {
            seen *= ground_shadowing(o + t_ground * d, t_ground * d);
        }
#endif
    } else {
        seen = (colour + disc) * path.transmittance;
    }
    out_color = vec4(max(seen + inscatter, vec3(0.0)), 1.0);
}
