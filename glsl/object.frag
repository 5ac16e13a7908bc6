#version 450
// Shades object fragments. Forward: the lit colour into the colour target.
// With GBUFFER (deferred lighting), Phong surfaces write their ambient term
// (plus the atmosphere's sun and sky, below) to the colour target and their
// material and normal to the G-buffer, and the lighting pass adds the
// scene's lights; the other shading models are still
// shaded here and write a zero material, so the lighting pass adds nothing
// to them.
// With NORMAL_MAP, the shading normal comes from a tangent-space normal
// map: T along increasing u, B = sign * cross(N, T) along increasing v,
// a texel holding 0.5 + 0.5 * (x, y, z).
// With SUN_LIGHT (a scene with an atmosphere), every model is also lit by
// the sun through the air at this pixel's own point, and with SKY_LIGHT
// (multiple scattering) by the sky (object_air.glsl); in the G-buffer
// form too, with the ambient term: per pixel, the sun's colour has no
// place in the G-buffer, and the lighting pass's tiles would only repeat
// it for every pixel.
// With SHADOWS (a light casts shadows), the shadow-casting light's term is
// scaled by the fraction of the shadow map's comparisons that find the
// point lit (shadow_map.glsl); not with GOURAUD (lit per vertex) or in the
// G-buffer form (shadows need forward lighting).
// With DEBUG_VIEW, the fragment writes one attribute instead of a colour
// (DEBUG_ATTRIBUTE: world-space normal after normal mapping, tangent,
// bitangent, UV, or albedo), for finding seams and broken frames.
// feature: BASE_COLOR_TEXTURE
// feature: GBUFFER
// feature: NORMAL_MAP
// feature: DEBUG_VIEW
// feature: GOURAUD
// feature: SUN_LIGHT
// feature: SKY_LIGHT
// feature: SHADOWS
// requires: SKY_LIGHT SUN_LIGHT
// excludes: SUN_LIGHT DEBUG_VIEW
// excludes: SHADOWS DEBUG_VIEW
// excludes: SHADOWS GOURAUD
// excludes: SHADOWS GBUFFER
#include "variant_rules.glsl"
#include "scene_data.glsl"
#include "lighting.glsl"
#ifdef SUN_LIGHT
#include "object_air.glsl"
#endif
#include "object_lighting.glsl"
#include "octahedral.glsl"
#include "srgb.glsl"

// Each input exists only in the variants that read it, so the vertex
// stage never writes an output nobody consumes.
#if !defined(GOURAUD) && !defined(DEBUG_VIEW)
layout(location = 0) in vec3 in_world_position;
#endif
#ifndef GOURAUD
layout(location = 1) in vec3 in_normal;
#endif
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP) || defined(DEBUG_VIEW)
layout(location = 2) in vec2 in_uv;
#endif
#ifdef GOURAUD
layout(location = 3) in vec3 in_gouraud;
#endif
#if defined(NORMAL_MAP) || defined(DEBUG_VIEW)
layout(location = 4) in vec4 in_tangent;
#endif

layout(location = 0) out vec4 out_color;
#ifdef GBUFFER
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out vec2 out_normal;
layout(location = 3) out vec4 out_material;
#endif

// One material set with fixed bindings (see constants.glsl).
#ifdef BASE_COLOR_TEXTURE
layout(set = MATERIAL_SET, binding = BASE_COLOR_BINDING) uniform sampler2D base_color;
#endif
#ifdef NORMAL_MAP
layout(set = MATERIAL_SET, binding = NORMAL_MAP_BINDING) uniform sampler2D normal_map;
#endif
// Maps selected by a bit of MATERIAL_MAPS rather than a variant, read in
// the variants with the material set and UVs: the driver folds a clear
// bit's branch away when it creates the pipeline.
layout(constant_id = SPEC_MATERIAL_MAPS) const uint MATERIAL_MAPS = 0u;
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP)
// The specular map multiplies ks (sRGB, like the base colour).
layout(set = MATERIAL_SET, binding = SPECULAR_MAP_BINDING) uniform sampler2D specular_map;
#endif

#ifndef GOURAUD
layout(constant_id = SPEC_TWO_SIDED) const bool TWO_SIDED = false;
#endif

#ifdef DEBUG_VIEW
const uint DEBUG_NORMALS = 1u;
const uint DEBUG_TANGENTS = 2u;
const uint DEBUG_BITANGENTS = 3u;
const uint DEBUG_UV = 4u;
const uint DEBUG_ALBEDO = 5u;
layout(constant_id = SPEC_DEBUG_ATTRIBUTE) const uint DEBUG_ATTRIBUTE = DEBUG_NORMALS;
#endif

// Drawn straight into the 8-bit output (`FrameGraph::new`'s direct path),
// the colour is sRGB-encoded here, as the tone map would encode it.
layout(constant_id = SPEC_ENCODE_SRGB) const bool ENCODE_SRGB = false;

void shade();

// The object's specular reflectance times `scale` (rgb) and shininess (a).
vec4 scaled_ks(vec3 scale) {
    return vec4(object.ks.rgb * scale, object.ks.a);
}

void main() {
    shade();
    if (ENCODE_SRGB) {
        out_color.rgb = srgb_encode(out_color.rgb);
    }
}

void shade() {
    vec4 base = vec4(1.0);
#ifdef BASE_COLOR_TEXTURE
    // Surface v grows upwards; image rows grow downwards.
    base = texture(base_color, vec2(in_uv.x, 1.0 - in_uv.y));
#endif
    float alpha = object.kd.a * base.a;
#ifdef GOURAUD
    // Lit per vertex; the texture multiplies the interpolated colour.
    out_color = vec4(in_gouraud * base.rgb, alpha);
#ifdef GBUFFER
    out_albedo = vec4(0.0);
    out_normal = vec2(0.0);
    out_material = vec4(0.0);
#endif
#else
    // Interpolated normals are shorter than 1: re-normalize per pixel.
    vec3 n = normalize(in_normal);
    // Two-sided: a face seen from behind is shaded as the other side.
    if (TWO_SIDED && !gl_FrontFacing) {
        n = -n;
    }
#ifdef SHADOWS
    // Offset along the interpolated normal, before any normal map.
    shadow_light_visibility = shadow_visibility(in_world_position, n);
#endif
#ifdef NORMAL_MAP
    vec3 m = texture(normal_map, vec2(in_uv.x, 1.0 - in_uv.y)).xyz * 2.0 - 1.0;
    if (object.counts.y != 0u) {
        m.y = -m.y;
    }
    // Re-orthogonalize the interpolated tangent against this normal.
    vec3 t = in_tangent.xyz - n * dot(n, in_tangent.xyz);
    float t_length = length(t);
    if (t_length > 1e-6) {
        t /= t_length;
        vec3 b = (in_tangent.w < 0.0 ? -1.0 : 1.0) * cross(n, t);
        vec3 mapped = t * m.x + b * m.y + n * m.z;
        // A texel of (0.5, 0.5, 0.5) is no direction: keep the normal.
        if (dot(mapped, mapped) > 1e-12) {
            n = normalize(mapped);
        }
    }
#endif
    vec3 kd = object.kd.rgb * base.rgb;
    vec3 ka = object.ka.rgb * base.rgb;
    // The specular map's factor on ks (1 without one). ks itself is read
    // where it is used (scaled_ks): read here, ahead of the branches, it
    // cost lavapipe 0.4 % more instructions in a textured scene.
    vec3 ks_scale = vec3(1.0);
#if defined(BASE_COLOR_TEXTURE) || defined(NORMAL_MAP)
    if ((MATERIAL_MAPS & SPECULAR_MAP_BIT) != 0u) {
        ks_scale = texture(specular_map, vec2(in_uv.x, 1.0 - in_uv.y)).rgb;
    }
#endif
#ifdef DEBUG_VIEW
    // The frame as the normal map uses it: T re-orthogonalized against the
    // (mapped) normal, B = sign * cross(N, T).
    vec3 debug_t = in_tangent.xyz - n * dot(n, in_tangent.xyz);
    debug_t = dot(debug_t, debug_t) > 1e-12 ? normalize(debug_t) : vec3(0.0);
    vec3 debug_b = (in_tangent.w < 0.0 ? -1.0 : 1.0) * cross(n, debug_t);
    vec3 value = DEBUG_ATTRIBUTE == DEBUG_NORMALS ? n
               : DEBUG_ATTRIBUTE == DEBUG_TANGENTS ? debug_t
               : DEBUG_ATTRIBUTE == DEBUG_BITANGENTS ? debug_b
               : DEBUG_ATTRIBUTE == DEBUG_UV ? vec3(in_uv, 0.0)
               : kd;
    out_color = vec4(value, 1.0);
#else
    vec3 v = normalize(frame.camera_position.xyz - in_world_position);
#ifdef GBUFFER
    if (SHADING_MODEL == SHADING_PHONG) {
        // Ambient (and the atmosphere's sun and sky, if the scene has
        // one; the object's block holds no lights here); the lighting
        // pass adds the scene's lights.
        out_color = vec4(blinn_phong(in_world_position, n, v, kd, ka, scaled_ks(ks_scale)), alpha);
        out_albedo = vec4(kd, 1.0);
        out_normal = octahedral_encode(n);
        out_material = scaled_ks(ks_scale);
        return;
    }
    out_albedo = vec4(0.0);
    out_normal = vec2(0.0);
    out_material = vec4(0.0);
#endif
    if (SHADING_MODEL == SHADING_TOON) {
        vec3 c = abs(dot(n, v)) < TOON_SILHOUETTE ? vec3(0.0) : toon(in_world_position, n, v, kd, ka, scaled_ks(ks_scale));
        out_color = vec4(c, alpha);
    } else {
        out_color = vec4(blinn_phong(in_world_position, n, v, kd, ka, scaled_ks(ks_scale)), alpha);
    }
#endif
#endif
}
