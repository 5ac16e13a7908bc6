//! The scene's meshes and world-space bounds, built once per render and
//! shared by the plan (light culling, draw order) and the renderer (vertex
//! upload), so no object is tessellated or loaded twice.

use super::RenderError;
use crate::mesh::Mesh;
use crate::scene::Scene;

/// Every object's mesh (object space) and bounding sphere (world space).
#[derive(Clone, Debug, Default)]
pub struct SceneGeometry {
    /// `meshes[i]` is object i.
    pub meshes: Vec<Mesh>,
    /// `bounds[i]` is object i's world-space bounding sphere `(centre, radius)`.
    pub bounds: Vec<(glam::DVec3, f32)>,
}

impl SceneGeometry {
    /// Builds every object's mesh, refusing (by object name) one that
    /// tessellates to no triangle or to non-finite vertices, which would
    /// otherwise draw nothing or garbage without a word.
    pub fn new(scene: &Scene) -> Result<SceneGeometry, RenderError> {
        let mut meshes = Vec::with_capacity(scene.objects.len());
        let mut bounds = Vec::with_capacity(scene.objects.len());
        for (i, object) in scene.objects.iter().enumerate() {
            let name = || format!("objects[{i}] \"{}\"", object.name);
            let mesh = scene.object_mesh(i);
            if mesh.indices.is_empty() {
                return Err(RenderError::Object {
                    object: name(),
                    reason: "its surface tessellates to no triangles (every triangle is \
                             degenerate: the shape's sizes are too far apart)"
                        .into(),
                });
            }
            let finite = mesh.vertices.iter().all(|v| {
                v.position.iter().all(|x| x.is_finite()) && v.normal.iter().all(|x| x.is_finite())
            });
            let (centre, radius) = scene.world_bounds(i, &mesh);
            let world_ok = object.transform.matrix_f64().is_finite()
                && centre.is_finite()
                && radius.is_finite();
            if !finite || !world_ok {
                return Err(RenderError::Object {
                    object: name(),
                    reason: "its vertices are not finite numbers (sizes too large)".into(),
                });
            }
            meshes.push(mesh);
            bounds.push((centre, radius));
        }
        Ok(SceneGeometry { meshes, bounds })
    }
}
