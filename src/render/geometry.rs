//! The scene's meshes and world-space bounds, built once per render and
//! shared by the plan (light culling, draw order) and the renderer (vertex
//! upload), so no object is tessellated or loaded twice, and objects of the
//! same shape share one mesh (`Scene::mesh_sources`).

use std::sync::Arc;

use super::RenderError;
use crate::mesh::Mesh;
use crate::scene::Scene;

/// Every object's mesh (object space) and bounding sphere (world space).
#[derive(Clone, Debug, Default)]
pub struct SceneGeometry {
    /// `meshes[i]` is object i's: one allocation per distinct mesh, shared
    /// by every object with the same shape (`Arc::ptr_eq` tells them).
    pub meshes: Vec<Arc<Mesh>>,
    /// `bounds[i]` is object i's world-space bounding sphere `(centre, radius)`.
    pub bounds: Vec<(glam::DVec3, f32)>,
    /// `boxes[i]` is object i's object-space box `(min, max)` around its
    /// vertices, so that plans need not walk the vertices again.
    pub boxes: Vec<(glam::Vec3, glam::Vec3)>,
}

impl SceneGeometry {
    /// Object `i`'s world-space axis-aligned box: its object-space box's
    /// corners moved by the object's transform (in `scene`).
    pub fn world_box(&self, scene: &Scene, i: usize) -> (glam::DVec3, glam::DVec3) {
        let (min, max) = self.boxes[i];
        let model = scene.objects[i].transform.matrix_f64();
        (0..8)
            .map(|k| {
                let pick = |bit: usize, lo: f32, hi: f32| if k & bit == 0 { lo } else { hi };
                let corner = glam::Vec3::new(
                    pick(1, min.x, max.x),
                    pick(2, min.y, max.y),
                    pick(4, min.z, max.z),
                );
                model.transform_point3(corner.as_dvec3())
            })
            .fold(
                (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY),
                |(lo, hi), p| (lo.min(p), hi.max(p)),
            )
    }
}

impl SceneGeometry {
    /// Builds every object's mesh, refusing (by object name) one that
    /// tessellates to no triangle or to non-finite vertices, which would
    /// otherwise draw nothing or garbage without a word.
    pub fn new(scene: &Scene) -> Result<SceneGeometry, RenderError> {
        let mut meshes: Vec<Arc<Mesh>> = Vec::with_capacity(scene.objects.len());
        let mut bounds = Vec::with_capacity(scene.objects.len());
        let mut boxes = Vec::with_capacity(scene.objects.len());
        for (i, (object, source)) in scene.objects.iter().zip(scene.mesh_sources()).enumerate() {
            let name = || format!("objects[{i}] \"{}\"", object.name);
            let mesh = if source < i {
                Arc::clone(&meshes[source])
            } else {
                Arc::new(scene.object_mesh(i))
            };
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
            // Shared meshes share their box too.
            boxes.push(match source < i {
                true => boxes[source],
                false => mesh.bounding_box().unwrap_or_default(),
            });
            meshes.push(mesh);
            bounds.push((centre, radius));
        }
        Ok(SceneGeometry {
            meshes,
            bounds,
            boxes,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Objects of the same shape and tessellation share one mesh (one
    /// allocation, so one upload); a different size or tessellation gets
    /// its own; each keeps its own world-space bounds.
    #[test]
    fn objects_of_the_same_shape_share_one_mesh() {
        let mut text = String::from(
            "[camera]\neye = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             [[materials]]\nname = \"m\"\nkd = [0.8, 0.8, 0.8]\n",
        );
        // (radius, tessellation, x): objects 0, 1 and 3 are one shape.
        for (radius, tessellation, x) in [
            (1.0, [16, 8], -3.0),
            (1.0, [16, 8], 0.0),
            (2.0, [16, 8], 3.0),
            (1.0, [16, 8], 6.0),
            (1.0, [32, 16], 9.0),
        ] {
            text += &format!(
                "[[objects]]\nname = \"s{x}\"\nmaterial = \"m\"\n\
                 shape = {{ type = \"sphere\", radius = {radius:?} }}\n\
                 tessellation = {tessellation:?}\ntranslate = [{x:?}, 0.0, 0.0]\n"
            );
        }
        let scene = Scene::from_toml(&text, "spheres.toml", Path::new(".")).unwrap();
        assert_eq!(scene.mesh_sources(), [0, 0, 2, 0, 4]);
        let geometry = SceneGeometry::new(&scene).unwrap();
        let shared = |a: usize, b: usize| Arc::ptr_eq(&geometry.meshes[a], &geometry.meshes[b]);
        assert!(shared(0, 1) && shared(0, 3));
        assert!(!shared(0, 2) && !shared(0, 4) && !shared(2, 4));
        // Each is the mesh the object would have on its own.
        for i in 0..5 {
            assert_eq!(*geometry.meshes[i], scene.object_mesh(i), "object {i}");
        }
        // Bounds follow each object's own transform.
        let x = |i: usize| geometry.bounds[i].0.x;
        assert!((x(0) + 3.0).abs() < 1e-6 && x(1).abs() < 1e-6 && (x(3) - 6.0).abs() < 1e-6);
    }
}
