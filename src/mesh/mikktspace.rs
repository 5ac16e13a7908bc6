//! Tangent frames by Mikkelsen's algorithm (`tangents = "mikktspace"`),
//! through `bevy_mikktspace`, which reproduces the C reference: normal maps
//! baked by common tools expect exactly these tangents. The vertices are
//! joined as in [`super::tangents::build_mesh`], additionally keyed by the
//! tangent, so corners that MikkTSpace gives different frames stay apart.

use super::smoothing::FastMap;
use super::tangents::{corner_bits, is_collapsed, TangentStats};
use super::{Mesh, Vertex};
use bevy_mikktspace::{generate_tangents, Geometry, TangentSpace};
use glam::{Vec2, Vec3};

/// The triangle soup as MikkTSpace reads it, and the tangent it returns
/// per corner.
struct Soup<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    uvs: Option<&'a [Vec2]>,
    tangents: Vec<Option<[f32; 4]>>,
}

impl Geometry for Soup<'_> {
    fn num_faces(&self) -> usize {
        self.positions.len() / 3
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[face * 3 + vert].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[face * 3 + vert].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.uvs.map_or([0.0; 2], |u| u[face * 3 + vert].to_array())
    }

    fn set_tangent(&mut self, tangent_space: Option<TangentSpace>, face: usize, vert: usize) {
        self.tangents[face * 3 + vert] = tangent_space.map(|t| t.tangent_encoded());
    }
}

/// [`super::tangents::build_mesh`] with MikkTSpace tangents: same inputs
/// (three corners per triangle, unit normals, optional UVs with v up), an
/// indexed mesh out. A corner MikkTSpace leaves without a frame, or gives a
/// non-finite one, gets a frame built from its normal.
pub fn build_mesh_mikktspace(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: Option<&[Vec2]>,
) -> (Mesh, TangentStats) {
    let corners = positions.len() / 3 * 3;
    let mut soup = Soup {
        positions: &positions[..corners],
        normals: &normals[..corners],
        uvs: uvs.map(|u| &u[..corners]),
        tangents: vec![None; corners],
    };
    // Only fails on a mesh with no faces at all, which has nothing to set.
    let _ = generate_tangents(&mut soup);

    let mut stats = TangentStats::default();
    let mut index_of: FastMap<[u32; 12], u32> =
        FastMap::with_capacity_and_hasher(corners / 4, Default::default());
    let mut vertices: Vec<Vertex> = Vec::new();
    let mut indices = Vec::with_capacity(corners);
    for t in 0..corners / 3 {
        let [a, b, c] = [0, 1, 2].map(|k| positions[3 * t + k]);
        if is_collapsed(a, b, c) {
            stats.collapsed += 1;
            continue;
        }
        for c in 3 * t..3 * t + 3 {
            let n = normals[c] + Vec3::ZERO;
            let p = positions[c] + Vec3::ZERO;
            let u = uvs.map_or(Vec2::ZERO, |u| u[c]) + Vec2::ZERO;
            let tangent = soup.tangents[c]
                .filter(|t| t.iter().all(|x| x.is_finite()))
                .and_then(|t| {
                    let v = Vec3::new(t[0], t[1], t[2]);
                    // MikkTSpace's tangent is orthogonal to the normal up to
                    // rounding; make it exact as the shader expects.
                    (v - n * n.dot(v))
                        .try_normalize()
                        .map(|v| [v.x, v.y, v.z, if t[3] < 0.0 { -1.0 } else { 1.0 }])
                })
                .unwrap_or_else(|| {
                    stats.from_normal += 1;
                    let v = n.any_orthonormal_vector();
                    [v.x, v.y, v.z, 1.0]
                });
            let mut key = [0; 12];
            key[..8].copy_from_slice(&corner_bits(p, n, u));
            key[8..].copy_from_slice(&tangent.map(|x| (x + 0.0).to_bits()));
            let index = *index_of.entry(key).or_insert_with(|| {
                vertices.push(Vertex {
                    position: p.to_array(),
                    normal: n.to_array(),
                    tangent,
                    uv: [u.x, u.y],
                });
                vertices.len() as u32 - 1
            });
            indices.push(index);
        }
        if uvs.is_some() {
            let [ta, tb, tc] = [0, 1, 2].map(|k| uvs.map_or(Vec2::ZERO, |u| u[3 * t + k]));
            let det = (tb - ta).perp_dot(tc - ta);
            if det == 0.0 || !det.is_finite() {
                stats.degenerate += 1;
            } else if det < 0.0 {
                stats.mirrored += 1;
            }
        }
    }
    (Mesh { vertices, indices }, stats)
}
