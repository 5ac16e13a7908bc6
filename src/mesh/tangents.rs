//! Indexed meshes with tangent frames from triangle soups.
//!
//! Each triangle's tangent `T` and bitangent `B` follow its UV deltas
//! (`T` along increasing u, `B` along increasing v). Corners are merged
//! into one vertex only when position, normal, UV and handedness all agree,
//! so averaging never crosses a UV seam or a mirrored seam (where `+T` and
//! `-T` would cancel). Triangles with zero area or zero UV area add nothing;
//! a vertex left with no valid contribution gets an orthonormal frame built
//! from its normal alone. Triangles collapsed to a line or a point are left
//! out: they cover no pixels and have no normal of their own. `T` is made orthogonal to the normal
//! (Gram-Schmidt) and `tangent.w` holds the handedness, so that
//! `B = w * cross(N, T)`.
//!
//! After smoothing, which has already numbered the distinct positions and
//! measured every corner angle, corners are joined among the vertices of
//! their position ([`build_mesh_numbered`]): neighbouring corners then
//! read neighbouring entries, where a hash table of every attribute is a
//! random read per corner, and no angle is measured twice.

use glam::{DVec3, Vec2, Vec3};

use super::join::{hash_words, IndexTable};
use super::smoothing::{corner_angle, PartNumbers};
use super::{Mesh, Vertex};

/// Statistics of one [`build_mesh`] call, for reports and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TangentStats {
    /// Triangles collapsed to a line or point, left out of the mesh.
    pub collapsed: usize,
    /// Triangles with zero area or zero UV area (no tangent contribution).
    pub degenerate: usize,
    /// Triangles whose UVs are mirrored (handedness -1).
    pub mirrored: usize,
    /// Vertices whose frame came from the normal alone.
    pub from_normal: usize,
}

/// Joins a soup (three corners per triangle; `normals` unit length, never
/// NaN) into an indexed [`Mesh`] with tangent frames. `uvs` are the file's
/// (v up, as the renderer's texture coordinates; the shader flips v to
/// address image rows); without them every frame comes from the normal.
pub fn build_mesh(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: Option<&[Vec2]>,
) -> (Mesh, TangentStats) {
    build_mesh_numbered(positions, normals, uvs, None)
}

/// [`build_mesh`], given the exact position number of each corner of the
/// whole triangles (equal numbers for bit-identical positions, `-0.0` as
/// `0.0`) and each triangle's corner angles, from smoothing's welding
/// ([`super::smoothing::PositionNumbers`]): a corner is then joined among
/// the vertices already made at its position, found through an array
/// indexed by position number, instead of through a hash table of every
/// attribute, and the angles are not measured again. Positions are numbered in
/// order of first appearance, so neighbouring corners read neighbouring
/// entries, where a hash table's slots are random reads that miss the
/// caches on a large model. The same mesh, bit for bit.
pub fn build_mesh_numbered(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: Option<&[Vec2]>,
    numbers: Option<PartNumbers>,
) -> (Mesh, TangentStats) {
    let corners = positions.len();
    let buffers = MeshBuffers::for_corners(corners);
    let mut scratch = MeshScratch::for_corners(corners);
    build_mesh_in(positions, normals, uvs, numbers, buffers, &mut scratch)
}

/// The arrays [`build_mesh_numbered`] fills, reserved ahead: a caller
/// that builds meshes on other threads reserves them on its own, so that
/// they reuse the memory its earlier stages freed (each thread allocates
/// from its own pool, and fresh memory costs a page fault per 4 KB).
pub(crate) struct MeshBuffers {
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
}

impl MeshBuffers {
    /// Room for a soup of `corners` corners with up to one vertex per four
    /// corners (a closed mesh has about one per six; cuts and seams add
    /// some), so that the arrays do not grow: reserved memory costs
    /// nothing until it is written.
    pub(crate) fn for_corners(corners: usize) -> Self {
        MeshBuffers {
            vertices: Vec::with_capacity(corners / 4 + 16),
            indices: Vec::with_capacity(corners),
        }
    }
}

/// The working arrays of [`build_mesh_in`] (each vertex's sums of frames,
/// and the vertices of each position), reused from one mesh to the next.
#[derive(Default)]
pub(crate) struct MeshScratch {
    sums: Vec<(DVec3, DVec3)>,
    earlier: Vec<u32>,
}

impl MeshScratch {
    /// Room for the meshes of soups of up to `corners` corners (see
    /// [`MeshBuffers::for_corners`]).
    pub(crate) fn for_corners(corners: usize) -> Self {
        MeshScratch {
            sums: Vec::with_capacity(corners / 4 + 16),
            earlier: Vec::with_capacity(corners / 4 + 16),
        }
    }
}

/// [`build_mesh_numbered`] into `buffers`, working in `scratch`.
pub(crate) fn build_mesh_in(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: Option<&[Vec2]>,
    numbers: Option<PartNumbers>,
    buffers: MeshBuffers,
    scratch: &mut MeshScratch,
) -> (Mesh, TangentStats) {
    let MeshBuffers {
        mut vertices,
        mut indices,
    } = buffers;
    let sums = &mut scratch.sums;
    sums.clear();
    let mut stats = TangentStats::default();
    let corners = positions.len() / 3 * 3;
    let uv = |c: usize| uvs.map_or(Vec2::ZERO, |u| u[c]);
    let mut by_position =
        numbers.and_then(|n| ByPosition::new(n.positions, corners, &mut scratch.earlier));
    // Smoothing's corner angles, when they cover every triangle.
    let face_angles = numbers.map(|n| n.faces).filter(|f| f.len() == corners / 3);

    // One pass over the triangles, in batches: each triangle's frame and
    // corner weights, then its corners joined into vertices (in order of
    // first appearance) and their weighted frames added to the vertex's
    // sums, in corner order. A batch's first table slots are read together
    // before its corners are joined (see `IndexTable::touch`). A closed
    // mesh has about one vertex per six corners; the table grows when
    // there are more.
    let expected = corners / 6 + 16;
    let mut table = IndexTable::with_capacity(if by_position.is_some() { 1 } else { expected });
    const BATCH: usize = 8;
    let mut frames = [(DVec3::ZERO, DVec3::ZERO); BATCH];
    let mut keys = [[0u32; 9]; 3 * BATCH];
    let mut hashes = [0u64; 3 * BATCH];
    let mut weights = [(0.0f64, 0usize); 3 * BATCH];
    for first in (0..corners / 3).step_by(BATCH) {
        let mut kept = 0;
        for (slot, t) in (first..(first + BATCH).min(corners / 3)).enumerate() {
            let corner_positions = [0, 1, 2].map(|k| positions[3 * t + k]);
            let corners = corner_positions.map(|p| p.as_dvec3());
            let corner_uvs = [0, 1, 2].map(|k| uv(3 * t + k).as_dvec2());
            let Some((tangent, bitangent, sign)) = triangle_frame(corners, corner_uvs, &mut stats)
            else {
                continue;
            };
            frames[slot] = (tangent, bitangent);
            // Smoothing measured the same angles of every face with a
            // normal (all finite); the others are measured here.
            let corner_weights = match face_angles.and_then(|f| f[t].angles()) {
                Some(angles) => angles.map(f64::from),
                None => corner_weights(corners),
            };
            for (k, weight) in corner_weights.into_iter().enumerate() {
                let c = 3 * t + k;
                // Vertex key: exact bits of position, normal, UV (+ 0:
                // -0.0 is stored, and keyed, as 0.0), and the handedness.
                let key = &mut keys[kept];
                key[..8].copy_from_slice(&corner_bits(positions[c], normals[c], uv(c)));
                key[8] = u32::from(sign < 0.0);
                if by_position.is_none() {
                    hashes[kept] = hash_words(*key);
                }
                weights[kept] = (weight, c);
                kept += 1;
            }
        }
        if by_position.is_none() {
            table.touch(&hashes[..kept]);
        }
        for ((key, &hash), &(weight, c)) in keys.iter().zip(&hashes).zip(&weights).take(kept) {
            let next = vertices.len() as u32;
            let same = |v: u32| same_key(&vertex_key(&vertices[v as usize]), key);
            let index = match &mut by_position {
                Some(by_position) => by_position.get_or_insert(c, key, next, same),
                None => table.get_or_insert(hash, next, same),
            };
            if index == next {
                let word = |i: usize| f32::from_bits(key[i]);
                vertices.push(Vertex {
                    position: [word(0), word(1), word(2)],
                    normal: [word(3), word(4), word(5)],
                    tangent: [0.0, 0.0, 0.0, if key[8] == 1 { -1.0 } else { 1.0 }],
                    uv: [word(6), word(7)],
                });
                sums.push((DVec3::ZERO, DVec3::ZERO));
            }
            let (tangent, bitangent) = frames[c / 3 - first];
            let s = &mut sums[index as usize];
            s.0 += tangent * weight;
            s.1 += bitangent * weight;
            indices.push(index);
        }
    }
    drop(table);
    finish_tangents(&mut vertices, sums, &mut stats);
    (Mesh { vertices, indices }, stats)
}

/// A triangle's unit tangent and bitangent (zero when degenerate) and its
/// handedness, from its `corners` and their `uvs`; `None` for a triangle
/// collapsed to a line or point. Counts mirrored, degenerate and
/// collapsed triangles in `stats`.
#[inline]
fn triangle_frame(
    corners: [DVec3; 3],
    uvs: [glam::DVec2; 3],
    stats: &mut TangentStats,
) -> Option<(DVec3, DVec3, f64)> {
    let [a, b, c] = corners;
    let [ta, tb, tc] = uvs;
    let (e1, e2) = (b - a, c - a);
    let (d1, d2) = (tb - ta, tc - ta);
    let det = d1.x * d2.y - d2.x * d1.y;
    let area = e1.cross(e2).length();
    let uv_scale = d1.length_squared().max(d2.length_squared());
    let valid = area > 0.0 && det.abs() > 1e-12 * uv_scale && det.is_finite();
    // Unit T and B (zero when degenerate), handedness.
    let (tangent, bitangent, sign) = if valid {
        let tangent = (e1 * d2.y - e2 * d1.y) / det;
        let bitangent = (e2 * d1.x - e1 * d2.x) / det;
        let sign = if det < 0.0 { -1.0 } else { 1.0 };
        if sign < 0.0 {
            stats.mirrored += 1;
        }
        (
            tangent.try_normalize().unwrap_or(DVec3::ZERO),
            bitangent.try_normalize().unwrap_or(DVec3::ZERO),
            sign,
        )
    } else {
        stats.degenerate += 1;
        (DVec3::ZERO, DVec3::ZERO, 1.0)
    };
    // `is_collapsed`, from the edges and area already at hand.
    if collapsed_edges(e1, e2, c - b, area) {
        stats.collapsed += 1;
        return None;
    }
    Some((tangent, bitangent, sign))
}

/// The weights of a triangle's corners in the vertices' frames: the
/// corner angles, like the normals', so that how the surface is cut into
/// triangles does not bias the frame (0 where an angle is not finite).
#[inline]
fn corner_weights([a, b, c]: [DVec3; 3]) -> [f64; 3] {
    let angle = |here: DVec3, next: DVec3, prev: DVec3| {
        let angle = f64::from(corner_angle(
            (next - here).as_vec3(),
            (prev - here).as_vec3(),
        ));
        if angle.is_finite() {
            angle
        } else {
            0.0
        }
    };
    [angle(a, b, c), angle(b, c, a), angle(c, a, b)]
}

/// Each vertex's tangent from its frame sums: orthogonalised against the
/// normal, with the handedness the vertex holds.
fn finish_tangents(vertices: &mut [Vertex], sums: &[(DVec3, DVec3)], stats: &mut TangentStats) {
    for (vertex, &(t, b)) in vertices.iter_mut().zip(sums.iter()) {
        let n = Vec3::from(vertex.normal).as_dvec3();
        let sign = f64::from(vertex.tangent[3]);
        // Gram-Schmidt against the normal; if T vanished (or is parallel to
        // the normal), fall back to B turned into a tangent, then to any
        // direction orthogonal to the normal.
        // The fallback is only computed when needed: nearly every vertex
        // has a tangent of its own.
        let from_t = (t - n * n.dot(t)).try_normalize();
        let from_b = || {
            (b - n * n.dot(b))
                .try_normalize()
                .map(|b| b.cross(n) * sign)
        };
        let tangent = match from_t.or_else(from_b) {
            Some(tangent) => tangent,
            None => {
                stats.from_normal += 1;
                n.any_orthonormal_vector()
            }
        };
        vertex.tangent = [
            tangent.x as f32,
            tangent.y as f32,
            tangent.z as f32,
            sign as f32,
        ];
    }
}

/// The vertices of each position, for [`build_mesh_numbered`]: the last
/// vertex made at each position number (offset by the smallest number in
/// use), and for each vertex the one made before it at its position. A
/// position keeps at most [`CROWDED`] vertices in its list; beyond, they
/// go into a hash table of every attribute, so that a position shared by
/// many vertices (the apex of a fan of creased or differently mapped
/// faces) costs a bounded number of comparisons per corner, not one per
/// vertex there.
struct ByPosition<'a> {
    numbers: &'a [u32],
    base: u32,
    last: Vec<u32>,
    earlier: &'a mut Vec<u32>,
    crowded: IndexTable,
}

/// At most this many vertices per position are found by walking its list.
const CROWDED: usize = 16;

impl<'a> ByPosition<'a> {
    /// `None` when `numbers` does not cover `corners` corners, or spans
    /// far more numbers than it has corners (a small part of a large
    /// model whose positions are scattered over the model's numbering:
    /// an array of them all would cost more than the hash table).
    fn new(numbers: &'a [u32], corners: usize, earlier: &'a mut Vec<u32>) -> Option<Self> {
        if numbers.len() != corners {
            return None;
        }
        let (low, high) = numbers
            .iter()
            .fold((u32::MAX, 0), |(l, h), &n| (l.min(n), h.max(n)));
        if low > high {
            return None;
        }
        let span = (high - low) as usize + 1;
        if span > 2 * corners + 1024 {
            return None;
        }
        Some(ByPosition {
            numbers,
            base: low,
            last: vec![u32::MAX; span],
            earlier: {
                earlier.clear();
                earlier
            },
            crowded: IndexTable::with_capacity(1),
        })
    }

    /// The vertex with key `key` at corner `corner`'s position (`same`
    /// says whether a vertex has it), or `new` after recording it there
    /// (the caller makes vertex `new`).
    #[inline]
    fn get_or_insert(
        &mut self,
        corner: usize,
        key: &[u32; 9],
        new: u32,
        same: impl Fn(u32) -> bool,
    ) -> u32 {
        let last = &mut self.last[(self.numbers[corner] - self.base) as usize];
        let (mut v, mut listed) = (*last, 0);
        while v != u32::MAX {
            if same(v) {
                return v;
            }
            v = self.earlier[v as usize];
            listed += 1;
        }
        debug_assert_eq!(self.earlier.len(), new as usize);
        if listed >= CROWDED {
            // A full list never shrinks: every later vertex at this
            // position, and only those, is in the table.
            let index = self.crowded.get_or_insert(hash_words(*key), new, same);
            if index == new {
                self.earlier.push(u32::MAX);
            }
            return index;
        }
        self.earlier.push(*last);
        *last = new;
        new
    }
}

/// The key [`build_mesh`] joins a vertex's corners by, from the vertex.
fn vertex_key(v: &Vertex) -> [u32; 9] {
    let mut key = [0; 9];
    let [p, n, u] = [&v.position[..], &v.normal[..], &v.uv[..]];
    for (slot, x) in key.iter_mut().zip(p.iter().chain(n).chain(u)) {
        *slot = x.to_bits();
    }
    key[8] = u32::from(v.tangent[3] < 0.0);
    key
}

/// Whether two vertex keys are equal, every word compared without a
/// branch: `==` on the arrays calls the C library's `memcmp`, a call per
/// corner that took a fifth of the tangent stage at 10⁶ triangles.
#[inline]
fn same_key(a: &[u32; 9], b: &[u32; 9]) -> bool {
    a.iter().zip(b).fold(0, |differ, (x, y)| differ | (x ^ y)) == 0
}

/// The exact bits of a corner's position, normal and UV, the part of the
/// key that decides which corners become one vertex (-0.0 counts as 0.0).
pub(crate) fn corner_bits(p: Vec3, n: Vec3, u: Vec2) -> [u32; 8] {
    [p.x, p.y, p.z, n.x, n.y, n.z, u.x, u.y].map(|x| (x + 0.0).to_bits())
}

/// Whether triangle (a, b, c) is collapsed to a line or a point. Same test
/// as the tessellator: only truly collapsed triangles, which have no normal
/// of their own to shade with, are left out of meshes.
pub fn is_collapsed(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let [a, b, c] = [a, b, c].map(|p| p.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    collapsed_edges(e1, e2, c - b, e1.cross(e2).length())
}

/// [`is_collapsed`] of a triangle with edges `e1 = b - a`, `e2 = c - a`,
/// `e3 = c - b` and area `|e1 x e2|` (twice the area).
#[inline]
fn collapsed_edges(e1: DVec3, e2: DVec3, e3: DVec3, area: f64) -> bool {
    let longest = e1
        .length_squared()
        .max(e2.length_squared())
        .max(e3.length_squared());
    area.is_nan() || area <= 1e-10 * longest
}

/// Largest deviation from an orthonormal frame over the mesh: `| |N| - 1 |`,
/// `| |T| - 1 |` and `|N . T|`, and 1 for any non-finite attribute.
pub fn max_orthonormality_error(mesh: &Mesh) -> f32 {
    mesh.vertices
        .iter()
        .map(|v| {
            let all = v
                .position
                .iter()
                .chain(&v.normal)
                .chain(&v.tangent)
                .chain(&v.uv);
            if !all.into_iter().all(|x| x.is_finite()) {
                return 1.0;
            }
            let n = Vec3::from(v.normal);
            let t = Vec3::from_slice(&v.tangent[..3]);
            let w_error = (v.tangent[3].abs() - 1.0).abs();
            ((n.length() - 1.0).abs())
                .max((t.length() - 1.0).abs())
                .max(n.dot(t).abs())
                .max(w_error)
        })
        .fold(0.0, f32::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::smoothing::{smooth_normals_numbered, Smoothing, SmoothingOptions};

    /// The bits of a mesh and its statistics.
    fn bits(mesh: &Mesh, stats: TangentStats) -> (Vec<u32>, Vec<u32>, TangentStats) {
        let words = mesh
            .vertices
            .iter()
            .flat_map(|v| {
                let all = v.position.iter().chain(&v.normal).chain(&v.tangent);
                all.chain(&v.uv).map(|x| x.to_bits()).collect::<Vec<_>>()
            })
            .collect();
        (words, mesh.indices.clone(), stats)
    }

    /// Joining from smoothing's position numbers and angles makes the same
    /// meshes, bit for bit, as hashing every corner: on soups drawn from
    /// small pools of points (shared positions, `-0.0` and `0.0`, collapsed
    /// and degenerate triangles, mirrored UVs, trailing corners), in every
    /// mode and at several weld distances.
    #[test]
    fn numbered_joining_matches_hashing_bit_for_bit() {
        let mut next = crate::mesh::tests::uniform_stream(0x9e37_79b9_u64);
        for round in 0..4 {
            let mut pool: Vec<Vec3> = (0..(6 << round))
                .map(|_| Vec3::new(next(), next(), next()) * 2.0 - 1.0)
                .collect();
            pool.push(Vec3::new(-0.0, 0.0, 0.0));
            pool.push(Vec3::ZERO);
            let uv_pool: Vec<Vec2> = (0..5).map(|_| Vec2::new(next(), next())).collect();
            let parts: Vec<(Vec<Vec3>, Vec<Vec2>)> = (0..3)
                .map(|p| {
                    (0..(60 << round) + p)
                        .map(|_| {
                            let point = pool[(next() * pool.len() as f32) as usize % pool.len()];
                            let uv = uv_pool[(next() * 5.0) as usize % 5];
                            (point, if next() < 0.3 { -uv } else { uv })
                        })
                        .unzip()
                })
                .collect();
            // A fan whose apex has a vertex per triangle (distinct UVs),
            // more than a position's list holds.
            let mut parts = parts;
            parts.push(
                (0..40 << round)
                    .flat_map(|i| {
                        let a = i as f32 * 0.1;
                        let rim = |a: f32| Vec3::new(a.cos(), a.sin(), 0.3 * (3.0 * a).sin());
                        [Vec3::Z, rim(a), rim(a + 0.1)].into_iter().zip([
                            Vec2::new(a, 0.0),
                            Vec2::new(a, 1.0),
                            Vec2::new(a + 0.1, 1.0),
                        ])
                    })
                    .unzip(),
            );
            let positions: Vec<&[Vec3]> = parts.iter().map(|p| p.0.as_slice()).collect();
            for mode in [Smoothing::Face, Smoothing::Object, Smoothing::Model] {
                for weld_distance in [0.0, 1e-3, 0.2] {
                    let options = SmoothingOptions {
                        mode,
                        crease_degrees: 60.0,
                        weld_distance,
                    };
                    let (normals, numbers) = smooth_normals_numbered(&positions, &options);
                    assert_eq!(numbers.is_some(), mode != Smoothing::Face);
                    for (i, ((p, uv), n)) in parts.iter().zip(&normals).enumerate() {
                        let part = numbers.as_ref().and_then(|x| x.part(i));
                        for uvs in [Some(uv.as_slice()), None] {
                            let (hashed, hs) = build_mesh(p, n, uvs);
                            let (numbered, ns) = build_mesh_numbered(p, n, uvs, part);
                            assert!(
                                bits(&hashed, hs) == bits(&numbered, ns),
                                "round {round}, {mode:?}, weld {weld_distance}, part {i}"
                            );
                        }
                    }
                }
            }
        }
    }
}
