//! The scene's meshes and world-space bounds, built once per render and
//! shared by the plan (light culling, draw order) and the renderer (vertex
//! upload), so no object is tessellated or loaded twice.

use crate::mesh::Mesh;
use crate::scene::Scene;
use glam::Vec3;

/// Every object's mesh (object space) and bounding sphere (world space).
#[derive(Clone, Debug, Default)]
pub struct SceneGeometry {
    /// `meshes[i]` is object i.
    pub meshes: Vec<Mesh>,
    /// `bounds[i]` is object i's world-space bounding sphere `(centre, radius)`.
    pub bounds: Vec<(Vec3, f32)>,
}

impl SceneGeometry {
    pub fn new(scene: &Scene) -> SceneGeometry {
        let meshes: Vec<Mesh> = (0..scene.objects.len())
            .map(|i| scene.object_mesh(i))
            .collect();
        let bounds = meshes
            .iter()
            .enumerate()
            .map(|(i, m)| scene.world_bounds(i, m))
            .collect();
        SceneGeometry { meshes, bounds }
    }
}
