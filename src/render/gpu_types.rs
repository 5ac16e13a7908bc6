//! Data laid out exactly as the shaders read it (`glsl/include/scene_data.glsl`);
//! the build checks every field's offset against the compiled shaders
//! (`glsl/interface.toml`).

use bytemuck::{Pod, Zeroable};

// A field moved, renamed or resized on either side fails here, at compile
// time, naming the block, the member and the shader.
include!(concat!(env!("OUT_DIR"), "/layout_checks.rs"));

// The blocks' fields that pipelines carry as specialization constants, in
// the order the shaders declare them (`sky_static_fields`).
include!(concat!(env!("OUT_DIR"), "/block_constants.rs"));

/// The per-frame uniform block (std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ViewUniforms {
    pub view_projection: [[f32; 4]; 4],
    /// The camera's position in the shaders' space: always the origin, since
    /// every position the GPU sees is relative to the camera (`Camera::view`).
    pub camera_position: [f32; 4],
    pub ambient: [f32; 4],
    /// Clip to world, for positions reconstructed from depth.
    pub inverse_view_projection: [[f32; 4]; 4],
    /// Width, height, 1/width, 1/height in pixels.
    pub viewport: [f32; 4],
    /// Where static lights are placed from (`render::static_lights`),
    /// relative to the camera.
    pub light_origin: [f32; 4],
}

impl ViewUniforms {
    /// The block for `scene`'s camera; static lights are placed from
    /// `light_anchor` (a world position).
    pub fn new(
        scene: &crate::scene::Scene,
        width: u32,
        height: u32,
        light_anchor: glam::DVec3,
    ) -> ViewUniforms {
        let aspect = width as f32 / height as f32;
        // Camera-relative, composed and inverted in double precision: with a
        // far/near ratio of 1e6 and more, a float inverse loses most of the
        // depth resolution.
        let view_projection = scene.camera.view_projection_f64(aspect);
        let inverse = view_projection.inverse().as_mat4();
        let view_projection = view_projection.as_mat4();
        let (w, h) = (width as f32, height as f32);
        ViewUniforms {
            view_projection: view_projection.to_cols_array_2d(),
            camera_position: [0.0, 0.0, 0.0, 1.0],
            ambient: scene.ambient.extend(0.0).to_array(),
            inverse_view_projection: inverse.to_cols_array_2d(),
            viewport: [w, h, 1.0 / w, 1.0 / h],
            light_origin: scene
                .camera
                .relative(light_anchor)
                .as_vec3()
                .extend(0.0)
                .to_array(),
        }
    }
}

/// The exposure buffer's contents (`Exposure` in `exposure.comp` and the
/// tone map's AUTO_EXPOSURE variant): written by the exposure pass, read
/// by the tone map; the CPU only sizes the buffer from it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ExposureBlock {
    /// The linear scale the tone map applies: 0.18 / Lavg.
    pub exposure: f32,
    /// Blocks are checked at their std140 size, a multiple of 16 bytes.
    pub _pad: [f32; 3],
}

/// The shadow block (std140, `glsl/include/shadow_map.glsl`): where each
/// cascade of the shadow map looks from and how finely.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadowUniforms {
    /// Per cascade or cube face, camera-relative position to the light's
    /// clip space over its tile (`Cascade::view_projection`).
    pub view_projection: [[[f32; 4]; 4]; 6],
    /// Per cascade, the distance from the camera where it ends (`f32::MAX`
    /// for the last and the unused ones).
    pub reach: [f32; 4],
    /// Per cascade, a texel's world-space width; x for a point light: per
    /// unit of distance from it.
    pub texel: [f32; 4],
    /// A point light's camera-relative position (xyz) with w = 1; w = 0
    /// for other lights.
    pub light: [f32; 4],
    /// A point light's face projection (`ShadowView::face_projection`):
    /// x = 1 / tan(half-angle), y = far / (near - far), z = y * near.
    pub face: [f32; 4],
}

/// One light as the shader reads it (std140: three vec4s).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    /// xyz position with w = 1, or unit direction towards the light with w = 0.
    pub position: [f32; 4],
    pub color: [f32; 4],
    /// x, y, z: constant, linear, quadratic attenuation; w: the window
    /// subtracted from the attenuation (`Light::window`).
    pub attenuation: [f32; 4],
}

/// The fixed head of a per-object block (std140); the object's lights
/// follow it directly.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ObjectHeader {
    pub model: [[f32; 4]; 4],
    pub normal_matrix: [[f32; 4]; 4],
    pub ka: [f32; 4],
    /// rgb diffuse, a opacity.
    pub kd: [f32; 4],
    /// rgb specular, a shininess.
    pub ks: [f32; 4],
    /// x: number of lights that follow.
    pub counts: [u32; 4],
}

/// One instance of an instanced draw as the vertex shader reads it
/// (per-instance vertex attributes from `INSTANCE_MODEL_LOCATION` and
/// `INSTANCE_NORMAL_LOCATION`): the camera-relative model matrix and the
/// normal matrix, by columns, tightly packed.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct InstanceTransform {
    pub model: [[f32; 4]; 4],
    pub normal_matrix: [[f32; 3]; 3],
}
