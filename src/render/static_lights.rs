//! Static lights: the lights a pipeline evaluates, carried as
//! specialization constants (`glsl/include/static_lights.glsl`) instead of
//! read from a uniform block.
//!
//! On lavapipe a fragment shader reads uniform-block data once per pixel,
//! at about 2.6 instructions per float per pixel (measured with
//! `aerial bench --metric instructions`): six lights of twelve floats cost
//! more than their Blinn-Phong arithmetic. As constants they cost nothing.
//! The frame never changes a light, but the camera moves, so positions are
//! made relative to a fixed origin, the camera when the resources were made
//! (`SceneResources::light_anchor`), and the frame block holds that origin
//! relative to the current camera: at the original view the light is
//! exactly the uniform block's.
//!
//! Each distinct light list needs its own pipeline, so a pass that would
//! need more than [`MAX_STATIC_PIPELINES`] of them, or a draw with more
//! than `MAX_STATIC_LIGHTS` lights, reads its lights from the uniform
//! block as before. An atmosphere's sun is not among a draw's lights: the
//! object shaders compute it per point from the atmosphere's uniforms.

use super::gpu_types::GpuLight;
#[cfg(test)]
use super::scene_resources::gpu_light;
use super::scene_resources::scene_light;
use crate::scene::Scene;
use crate::shader_ids::{
    float_constants, MAX_STATIC_LIGHTS, SPEC_STATIC_LIGHTS, SPEC_STATIC_LIGHT_DATA,
};

/// The most pipelines a pass specializes by their lights: each costs a
/// shader compile when the renderer is made.
pub const MAX_STATIC_PIPELINES: usize = 32;

/// Whether a light list can be carried as constants.
pub fn fits(lights: &[usize]) -> bool {
    lights.len() <= MAX_STATIC_LIGHTS as usize
}

/// Whether a pass of `scene` whose light lists that fit need `pipelines`
/// pipelines carries them as constants: the scene allows it
/// (`static_lights`) and the count is within [`MAX_STATIC_PIPELINES`].
pub fn enabled(scene: &Scene, pipelines: usize) -> bool {
    scene.output.static_lights && pipelines <= MAX_STATIC_PIPELINES
}

/// The specialization constants of a pipeline whose lights are `lights`
/// (indices into the scene's lights) placed from `anchor`, or, with
/// `None`, the one constant that makes it read them from its block.
pub fn constants(scene: &Scene, anchor: glam::DVec3, lights: Option<&[usize]>) -> Vec<(u32, u32)> {
    let Some(lights) = lights.filter(|l| fits(l)) else {
        return vec![(SPEC_STATIC_LIGHTS, 0)];
    };
    let mut constants = vec![(SPEC_STATIC_LIGHTS, 1)];
    for (k, &light) in lights.iter().enumerate() {
        let GpuLight {
            position,
            color,
            attenuation,
        } = scene_light(scene, light, anchor);
        let values = position.into_iter().chain(color).chain(attenuation);
        constants.extend(float_constants(
            SPEC_STATIC_LIGHT_DATA + 12 * k as u32,
            values,
        ));
    }
    constants
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constants hold each light's block layout, float for float, and
    /// a list too long for them turns static lights off.
    #[test]
    fn constants_carry_the_block_layout() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench/many_lights.toml");
        let scene = Scene::load(&path).unwrap();
        let anchor = scene.camera.eye;
        let lights: Vec<usize> = (0..scene.lights.len()).collect();
        let c = constants(&scene, anchor, Some(&lights));
        assert_eq!(c[0], (SPEC_STATIC_LIGHTS, 1));
        assert_eq!(c.len(), 1 + 12 * lights.len());
        for (k, &l) in lights.iter().enumerate() {
            let block = gpu_light(&scene.lights[l], anchor, scene.light_cutoff);
            let floats: Vec<f32> = bytemuck::cast_slice(bytemuck::bytes_of(&block)).to_vec();
            for (i, f) in floats.iter().enumerate() {
                let id = SPEC_STATIC_LIGHT_DATA + 12 * k as u32 + i as u32;
                assert!(c.contains(&(id, f.to_bits())), "light {k} float {i}");
            }
        }
        let many = vec![0; MAX_STATIC_LIGHTS as usize + 1];
        assert_eq!(
            constants(&scene, anchor, Some(&many)),
            vec![(SPEC_STATIC_LIGHTS, 0)]
        );
        assert_eq!(
            constants(&scene, anchor, None),
            vec![(SPEC_STATIC_LIGHTS, 0)]
        );
    }
}
