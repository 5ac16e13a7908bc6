//! What a scene needs from the GPU, decided on the CPU before any Vulkan
//! object exists: which passes run, which pipeline variants and textures
//! are created, and the order of the draws.
//!
//! Everything the scene does not use is left out here, so the GPU side
//! only builds what the plan lists.

use crate::mesh::Mesh;
use crate::scene::{HdrFormat, Scene, ShadingModel};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// A pipeline variant: shading model and light count (specialization
/// constants), base colour texture (a shader variant with its own
/// descriptor set) and alpha blending (the transparent pass).
///
/// The light count is a constant so the driver compiles the light loop with
/// a fixed trip count (unrolled, with constant offsets into the light
/// block); on lavapipe that is about twice as fast as a loop bounded by a
/// value read from the buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PipelineKey {
    pub shading: ShadingKey,
    pub textured: bool,
    pub blended: bool,
    /// Lights in the object's block.
    pub lights: u32,
}

/// `ShadingModel` as an ordered key (the GLSL specialization value).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ShadingKey {
    Phong = 0,
    Gouraud = 1,
    Toon = 2,
}

impl From<ShadingModel> for ShadingKey {
    fn from(m: ShadingModel) -> Self {
        match m {
            ShadingModel::Phong => ShadingKey::Phong,
            ShadingModel::Gouraud => ShadingKey::Gouraud,
            ShadingModel::Toon => ShadingKey::Toon,
        }
    }
}

/// One object draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Draw {
    pub object: usize,
    pub pipeline: PipelineKey,
    /// Index into `FramePlan::textures`.
    pub texture: Option<usize>,
    /// Indices into `Scene::lights` that reach this object.
    pub lights: Vec<usize>,
}

/// A timed pass of the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Copy a given HDR image into the HDR attachment (tone-mapping an
    /// existing image instead of drawing a scene).
    HdrUpload,
    Opaque,
    Transparent,
    ToneMap,
    Readback,
}

/// Why the split between subpasses is approximate: printed under timing
/// tables.
pub const SUBPASS_TIMING_NOTE: &str =
    "opaque, transparent and tonemap are subpasses of one render pass: \
a binning rasterizer (lavapipe, tile-based GPUs) may do a draw's work after a later timestamp, \
so their split is approximate; the sum over the render pass is exact";

impl Pass {
    pub fn name(self) -> &'static str {
        match self {
            Pass::HdrUpload => "hdr upload",
            Pass::Opaque => "opaque",
            Pass::Transparent => "transparent",
            Pass::ToneMap => "tonemap",
            Pass::Readback => "readback",
        }
    }
}

/// The frame a scene needs.
#[derive(Clone, Debug)]
pub struct FramePlan {
    pub width: u32,
    pub height: u32,
    pub hdr_format: HdrFormat,
    /// Opaque draws, grouped by pipeline and texture to save binds, front
    /// to back within a group.
    pub opaque: Vec<Draw>,
    /// Transparent draws, back to front from the camera.
    pub transparent: Vec<Draw>,
    /// Distinct base-colour textures, each loaded once.
    pub textures: Vec<PathBuf>,
    /// Store the HDR image for readback (`--hdr`).
    pub keep_hdr: bool,
    /// Passes in the order they run; one timestamp interval each.
    pub passes: Vec<Pass>,
}

impl FramePlan {
    /// `meshes[i]` is object i tessellated in object space.
    pub fn new(scene: &Scene, meshes: &[Mesh], keep_hdr: bool) -> FramePlan {
        let mut textures: Vec<PathBuf> = Vec::new();
        let mut texture_index = BTreeMap::new();
        let mut opaque = Vec::new();
        let mut transparent = Vec::new();
        for (i, object) in scene.objects.iter().enumerate() {
            let material = &scene.materials[object.material];
            let texture = material.texture.as_ref().map(|path| {
                *texture_index.entry(path.clone()).or_insert_with(|| {
                    textures.push(path.clone());
                    textures.len() - 1
                })
            });
            let blended = material.opacity < 1.0;
            let lights = scene.lights_reaching(i);
            let draw = Draw {
                object: i,
                pipeline: PipelineKey {
                    shading: material.shading.into(),
                    textured: texture.is_some(),
                    blended,
                    lights: lights.len() as u32,
                },
                texture,
                lights,
            };
            if blended {
                transparent.push(draw);
            } else {
                opaque.push(draw);
            }
        }
        // Distance from the eye to each object's world-space bounding-sphere
        // centre.
        let eye = scene.camera.eye;
        let distance = |d: &Draw| {
            let object = &scene.objects[d.object];
            let (centre, _) = meshes[d.object].bounding_sphere();
            object
                .transform
                .matrix()
                .transform_point3(centre)
                .distance(eye)
        };
        // Opaque: grouped by pipeline and texture (fewer binds), front to
        // back within a group, so the depth test rejects hidden fragments
        // before they are shaded.
        let mut keyed: Vec<(f32, Draw)> = opaque.into_iter().map(|d| (distance(&d), d)).collect();
        keyed.sort_by(|a, b| {
            (a.1.pipeline, a.1.texture)
                .cmp(&(b.1.pipeline, b.1.texture))
                .then(a.0.total_cmp(&b.0))
        });
        let opaque: Vec<Draw> = keyed.into_iter().map(|(_, d)| d).collect();
        // Transparent: back to front; ties keep scene order.
        let mut keyed: Vec<(f32, Draw)> =
            transparent.into_iter().map(|d| (distance(&d), d)).collect();
        keyed.sort_by(|a, b| b.0.total_cmp(&a.0));
        let transparent: Vec<Draw> = keyed.into_iter().map(|(_, d)| d).collect();

        let mut passes = vec![Pass::Opaque];
        if !transparent.is_empty() {
            passes.push(Pass::Transparent);
        }
        passes.extend([Pass::ToneMap, Pass::Readback]);
        FramePlan {
            width: scene.output.width,
            height: scene.output.height,
            hdr_format: scene.output.hdr_format,
            opaque,
            transparent,
            textures,
            keep_hdr,
            passes,
        }
    }

    /// The frame that only tone-maps a given `width`×`height` HDR image:
    /// no draws, the image copied into a 32-bit float HDR attachment.
    pub fn for_hdr_image(width: u32, height: u32, keep_hdr: bool) -> FramePlan {
        FramePlan {
            width,
            height,
            hdr_format: HdrFormat::Rgba32F,
            opaque: Vec::new(),
            transparent: Vec::new(),
            textures: Vec::new(),
            keep_hdr,
            passes: vec![Pass::HdrUpload, Pass::ToneMap, Pass::Readback],
        }
    }

    /// Whether the HDR attachment starts from an uploaded image.
    pub fn loads_hdr(&self) -> bool {
        self.passes.contains(&Pass::HdrUpload)
    }

    /// Every distinct pipeline variant the draws use.
    pub fn pipelines(&self) -> Vec<PipelineKey> {
        let mut keys: Vec<PipelineKey> = self
            .opaque
            .iter()
            .chain(&self.transparent)
            .map(|d| d.pipeline)
            .collect();
        keys.sort();
        keys.dedup();
        keys
    }

    pub fn draws(&self) -> impl Iterator<Item = &Draw> {
        self.opaque.iter().chain(&self.transparent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn load(file: &str) -> (Scene, FramePlan) {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes")
            .join(file);
        let scene = Scene::load(&path).unwrap();
        let meshes: Vec<Mesh> = (0..scene.objects.len())
            .map(|i| scene.object_mesh(i))
            .collect();
        let plan = FramePlan::new(&scene, &meshes, false);
        (scene, plan)
    }

    #[test]
    fn a_scene_without_transparency_or_textures_gets_neither() {
        let (_, plan) = load("default.toml");
        assert_eq!(
            plan.passes,
            vec![Pass::Opaque, Pass::ToneMap, Pass::Readback]
        );
        assert!(plan.textures.is_empty());
        assert!(plan.pipelines().iter().all(|k| !k.textured && !k.blended));
    }

    #[test]
    fn transparent_draws_are_sorted_back_to_front() {
        let (scene, plan) = load("transparency.toml");
        assert!(plan.passes.contains(&Pass::Transparent));
        assert!(plan.transparent.len() >= 2);
        let distance = |d: &Draw| {
            let (c, _) = scene.object_bounds(d.object).unwrap();
            c.distance(scene.camera.eye)
        };
        for pair in plan.transparent.windows(2) {
            assert!(distance(&pair[0]) >= distance(&pair[1]));
        }
        assert!(plan.opaque.iter().all(|d| !d.pipeline.blended));
    }

    #[test]
    fn textures_are_loaded_once_and_only_when_used() {
        let (_, plan) = load("flag.toml");
        assert_eq!(plan.textures.len(), 1);
        let textured = plan.draws().filter(|d| d.texture.is_some()).count();
        assert!(textured >= 1);
        assert!(plan.pipelines().iter().any(|k| k.textured));
    }

    #[test]
    fn each_draw_carries_only_the_lights_that_reach_it() {
        let (scene, plan) = load("many_lights.toml");
        for d in plan.draws() {
            assert_eq!(d.lights, scene.lights_reaching(d.object));
        }
        assert!(
            plan.draws().any(|d| d.lights.len() < scene.lights.len()),
            "no light was culled"
        );
    }
}
