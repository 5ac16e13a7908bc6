//! Data laid out exactly as the shaders read it (`glsl/include/scene_data.glsl`).

use bytemuck::{Pod, Zeroable};

/// The per-frame uniform block (std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_projection: [[f32; 4]; 4],
    pub camera_position: [f32; 4],
    pub ambient: [f32; 4],
}

/// One light as the shader reads it (std430).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    /// xyz position with w = 1, or unit direction towards the light with w = 0.
    pub position: [f32; 4],
    pub color: [f32; 4],
    pub attenuation: [f32; 4],
}

/// The fixed head of a per-object block (std430); the object's lights
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

#[cfg(test)]
mod tests {
    use super::*;

    // Sizes the GLSL layouts imply; a mismatch would shift every field.
    #[test]
    fn layouts_match_glsl() {
        assert_eq!(std::mem::size_of::<FrameUniforms>(), 96);
        assert_eq!(std::mem::size_of::<GpuLight>(), 48);
        assert_eq!(std::mem::size_of::<ObjectHeader>(), 192);
    }
}
