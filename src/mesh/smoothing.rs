//! Per-corner shading normals for triangle soups: face normals, or averages
//! over the faces that share a (welded) position within one object or across
//! the whole model, limited by a crease angle.
//!
//! Positions are welded by spatial hashing (cells one tolerance wide, each
//! point compared with the 27 cells around it), so smoothing a model is
//! near-linear in its size. [`naive_normals`] is the direct all-faces loop,
//! kept as a test oracle.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::{DVec3, Vec3};

/// A fast, non-cryptographic hasher for the integer keys of welding and
/// vertex merging (the standard SipHash is DoS-resistant but several times
/// slower, and these keys come from a file the user chose to load).
#[derive(Default, Clone, Copy)]
pub struct FxHasher(u64);

impl Hasher for FxHasher {
    fn write(&mut self, bytes: &[u8]) {
        // Integer arrays hash as their bytes: take them eight at a time.
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }
    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, i: i64) {
        self.write_u64(i as u64);
    }
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

/// A `HashMap` with [`FxHasher`].
pub type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// How shading normals are made (`smoothing` in the scene file).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Smoothing {
    /// Every corner takes its triangle's normal (faceted).
    Face,
    /// Averaged over the triangles of one object/group sharing a position.
    Object,
    /// Averaged over every triangle of the model sharing a position, across
    /// objects: boundaries between objects disappear.
    Model,
    /// The file's normals, unchanged.
    File,
}

impl Smoothing {
    /// The scene-file name.
    pub fn name(self) -> &'static str {
        match self {
            Smoothing::Face => "face",
            Smoothing::Object => "object",
            Smoothing::Model => "model",
            Smoothing::File => "file",
        }
    }
}

/// Smoothing parameters for [`smooth_normals`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothingOptions {
    /// `Face`, `Object` or `Model` (`File` is handled by the caller).
    pub mode: Smoothing,
    /// Faces whose normals differ by more than this (degrees) do not share
    /// a normal.
    pub crease_degrees: f32,
    /// Positions closer than this (absolute, model units) are the same
    /// point. 0 means bit-identical positions only.
    pub weld_distance: f32,
}

/// Unit normal (zero for a degenerate triangle) and, per corner, the weight
/// that corner's face contributes: its interior angle, so that how a
/// surface is cut into triangles does not bias the average.
fn face_data(positions: &[Vec3]) -> Vec<(DVec3, [f64; 3])> {
    positions
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|p| p.as_dvec3());
            let n = (b - a).cross(c - a);
            let Some(n) = n.try_normalize() else {
                return (DVec3::ZERO, [0.0; 3]);
            };
            // In f32: a weight needs no more, and f32 acos is much cheaper.
            let angle = |p: DVec3, q: DVec3, r: DVec3| {
                f64::from((q - p).as_vec3().angle_between((r - p).as_vec3()))
            };
            let w = [angle(a, b, c), angle(b, c, a), angle(c, a, b)];
            if w.iter().any(|x| !x.is_finite()) {
                return (DVec3::ZERO, [0.0; 3]);
            }
            (n, w)
        })
        .collect()
}

/// Groups of point indices within `distance` of one another (transitively),
/// as one group id per point (each id below `points.len()`).
pub fn weld(points: &[Vec3], distance: f32) -> Vec<usize> {
    // Exact duplicates first: corners of neighbouring triangles repeat the
    // same position many times, and the hash below need see each once.
    let mut unique: Vec<Vec3> = Vec::new();
    // Sized for the usual six corners per position, so it rarely rehashes.
    let mut exact: FastMap<[u32; 3], usize> =
        FastMap::with_capacity_and_hasher(points.len() / 4, Default::default());
    let point_to_unique: Vec<usize> = points
        .iter()
        .map(|p| {
            // +0.0 so that -0.0 and 0.0 are one key.
            let key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
            *exact.entry(key).or_insert_with(|| {
                unique.push(*p);
                unique.len() - 1
            })
        })
        .collect();
    let mut parent: Vec<usize> = (0..unique.len()).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let distance = f64::from(distance);
    if distance > 0.0 {
        // Cells four tolerances wide: a point near no cell face (half of
        // each axis) needs only its own cell along that axis, so on average
        // about 3.4 cells are visited instead of 27.
        let size = 4.0 * distance;
        let mut grid: FastMap<[i64; 3], Vec<usize>> = FastMap::default();
        for (i, p) in unique.iter().enumerate() {
            let scaled = p.as_dvec3() / size;
            let cell = scaled.floor();
            let fraction = scaled - cell;
            let cell = cell.as_i64vec3().to_array();
            let range = |f: f64| -> (i64, i64) {
                (if f < 0.25 { -1 } else { 0 }, if f > 0.75 { 1 } else { 0 })
            };
            let (rx, ry, rz) = (range(fraction.x), range(fraction.y), range(fraction.z));
            for dx in rx.0..=rx.1 {
                for dy in ry.0..=ry.1 {
                    for dz in rz.0..=rz.1 {
                        let key = [cell[0] + dx, cell[1] + dy, cell[2] + dz];
                        let Some(others) = grid.get(&key) else {
                            continue;
                        };
                        for &j in others {
                            if unique[j].as_dvec3().distance(p.as_dvec3()) <= distance {
                                let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                                parent[a.max(b)] = a.min(b);
                            }
                        }
                    }
                }
            }
            grid.entry(cell).or_default().push(i);
        }
    }
    point_to_unique
        .into_iter()
        .map(|u| find(&mut parent, u))
        .collect()
}

/// Shading normal per corner of `parts` (each a soup of three corners per
/// triangle). Never NaN: a corner with nothing to average (a degenerate
/// triangle) takes the average of every face at its position, else `+Y`.
pub fn smooth_normals(parts: &[&[Vec3]], options: &SmoothingOptions) -> Vec<Vec<Vec3>> {
    let faces: Vec<Vec<(DVec3, [f64; 3])>> = parts.iter().map(|p| face_data(p)).collect();
    let cos_crease = f64::from(options.crease_degrees.clamp(0.0, 180.0))
        .to_radians()
        .cos();
    let mut normals: Vec<Vec<Vec3>> = parts.iter().map(|p| vec![Vec3::Y; p.len()]).collect();
    // Corner lists (part, corner) in each weld scope: each part alone, or
    // all parts together.
    let scopes: Vec<Vec<(usize, usize)>> = match options.mode {
        Smoothing::Model => vec![parts
            .iter()
            .enumerate()
            .flat_map(|(p, part)| (0..part.len()).map(move |c| (p, c)))
            .collect()],
        _ => parts
            .iter()
            .enumerate()
            .map(|(p, part)| (0..part.len()).map(|c| (p, c)).collect())
            .collect(),
    };
    for scope in scopes {
        if options.mode == Smoothing::Face || options.mode == Smoothing::File {
            for (p, c) in scope {
                let n = faces[p][c / 3].0;
                normals[p][c] = unit_or(n, DVec3::Y);
            }
            continue;
        }
        let points: Vec<Vec3> = scope.iter().map(|&(p, c)| parts[p][c]).collect();
        let ids = weld(&points, options.weld_distance);
        // Members of each weld group as contiguous runs, by a counting sort
        // on the group id (ids are below the number of points): linear, and
        // cheaper than a map of small vectors.
        // u32 offsets halve the memory traffic of these corner-sized arrays
        // (mesh indices are u32 as well).
        let count = points.len();
        let mut starts = vec![0u32; count + 1];
        for &id in &ids {
            starts[id + 1] += 1;
        }
        for i in 0..count {
            starts[i + 1] += starts[i];
        }
        let mut order = vec![0u32; count];
        let mut next = starts.clone();
        for (k, &id) in ids.iter().enumerate() {
            order[next[id] as usize] = k as u32;
            next[id] += 1;
        }
        drop(next);
        let mut contributions: Vec<(DVec3, DVec3)> = Vec::new();
        for group in 0..count {
            let run = &order[starts[group] as usize..starts[group + 1] as usize];
            if run.is_empty() {
                continue;
            }
            contributions.clear();
            contributions.extend(run.iter().map(|&k| {
                let (p, c) = scope[k as usize];
                let (n, w) = faces[p][c / 3];
                (n, n * w[c % 3])
            }));
            let total: DVec3 = contributions.iter().map(|c| c.1).sum();
            for (&k, &(own, _)) in run.iter().zip(&contributions) {
                let sum: DVec3 = contributions
                    .iter()
                    .filter(|(n, _)| own.dot(*n) >= cos_crease - 1e-12)
                    .map(|(_, weighted)| weighted)
                    .sum();
                let (p, c) = scope[k as usize];
                normals[p][c] = unit_or(sum, unit_or(total, DVec3::Y).as_dvec3());
            }
        }
    }
    normals
}

/// The same normals as [`smooth_normals`] by the direct method: for every
/// corner, every corner of the scope within the weld distance. Quadratic;
/// a test oracle for small models.
pub fn naive_normals(parts: &[&[Vec3]], options: &SmoothingOptions) -> Vec<Vec<Vec3>> {
    let faces: Vec<Vec<(DVec3, [f64; 3])>> = parts.iter().map(|p| face_data(p)).collect();
    let cos_crease = f64::from(options.crease_degrees.clamp(0.0, 180.0))
        .to_radians()
        .cos();
    let distance = f64::from(options.weld_distance);
    let mut out = Vec::new();
    for (p, part) in parts.iter().enumerate() {
        let mut normals = Vec::with_capacity(part.len());
        for (c, position) in part.iter().enumerate() {
            let own = faces[p][c / 3].0;
            if options.mode == Smoothing::Face || options.mode == Smoothing::File {
                normals.push(unit_or(own, DVec3::Y));
                continue;
            }
            let mut sum = DVec3::ZERO;
            let mut total = DVec3::ZERO;
            for (q, other) in parts.iter().enumerate() {
                if options.mode == Smoothing::Object && q != p {
                    continue;
                }
                for (d, x) in other.iter().enumerate() {
                    if x.as_dvec3().distance(position.as_dvec3()) <= distance {
                        let (n, w) = faces[q][d / 3];
                        total += n * w[d % 3];
                        if own.dot(n) >= cos_crease - 1e-12 {
                            sum += n * w[d % 3];
                        }
                    }
                }
            }
            normals.push(unit_or(sum, unit_or(total, DVec3::Y).as_dvec3()));
        }
        out.push(normals);
    }
    out
}

fn unit_or(v: DVec3, fallback: DVec3) -> Vec3 {
    v.try_normalize().unwrap_or(fallback).as_vec3()
}
