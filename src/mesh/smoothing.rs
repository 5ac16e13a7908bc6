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
    // Faces are independent: whole triangles split over the cores.
    let threads = threads_for(positions.len());
    if threads <= 1 {
        return face_data_serial(positions);
    }
    let chunk = (positions.len() / 3).div_ceil(threads) * 3;
    std::thread::scope(|scope| {
        let handles: Vec<_> = positions
            .chunks(chunk)
            .map(|part| scope.spawn(move || face_data_serial(part)))
            .collect();
        let mut all = Vec::with_capacity(positions.len() / 3);
        for h in handles {
            all.extend(h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)));
        }
        all
    })
}

fn face_data_serial(positions: &[Vec3]) -> Vec<(DVec3, [f64; 3])> {
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

/// For each of `count` keys, the index of the first key equal to it, by an
/// open-addressing hash table of indices (twice as many slots as keys,
/// linear probing): no per-entry allocation, and one flat array to probe.
pub(crate) fn first_equal<const N: usize>(
    count: usize,
    key: impl Fn(usize) -> [u32; N],
) -> Vec<u32> {
    let slots = (count * 2).next_power_of_two().max(16);
    let mask = slots - 1;
    let mut table = vec![u32::MAX; slots];
    let mut first = Vec::with_capacity(count);
    for i in 0..count {
        let k = key(i);
        let mut h = 0x9e37_79b9_7f4a_7c15_u64;
        for word in k {
            h = (h ^ u64::from(word)).wrapping_mul(0xff51_afd7_ed55_8ccd);
            h ^= h >> 32;
        }
        let mut slot = h as usize & mask;
        loop {
            let held = table[slot];
            if held == u32::MAX {
                table[slot] = i as u32;
                first.push(i as u32);
                break;
            }
            if key(held as usize) == k {
                first.push(held);
                break;
            }
            slot = (slot + 1) & mask;
        }
    }
    first
}

/// Groups of point indices within `distance` of one another (transitively),
/// as one group id per point (each id below `points.len()`).
pub fn weld(points: &[Vec3], distance: f32) -> Vec<usize> {
    // Exact duplicates first: corners of neighbouring triangles repeat the
    // same position many times, and the hash below need see each once.
    // +0.0 so that -0.0 and 0.0 are one key.
    let key = |i: usize| (points[i] + Vec3::ZERO).to_array().map(f32::to_bits);
    let first = first_equal(points.len(), key);
    let mut unique: Vec<Vec3> = Vec::new();
    let mut unique_of_first = vec![u32::MAX; points.len()];
    let point_to_unique: Vec<usize> = first
        .iter()
        .enumerate()
        .map(|(i, &f)| {
            if f as usize == i {
                unique_of_first[i] = unique.len() as u32;
                unique.push(points[i]);
            }
            unique_of_first[f as usize] as usize
        })
        .collect();
    drop(unique_of_first);
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
        // Each cell's points as a chain through flat arrays (the cell's
        // last point, then each point's predecessor in its cell): no
        // allocation per cell.
        let mut last: FastMap<[i64; 3], u32> =
            FastMap::with_capacity_and_hasher(unique.len(), Default::default());
        let mut previous = vec![u32::MAX; unique.len()];
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
                        let mut j = last.get(&key).copied().unwrap_or(u32::MAX);
                        while j != u32::MAX {
                            let other = j as usize;
                            if unique[other].as_dvec3().distance(p.as_dvec3()) <= distance {
                                let (a, b) = (find(&mut parent, i), find(&mut parent, other));
                                parent[a.max(b)] = a.min(b);
                            }
                            j = previous[other];
                        }
                    }
                }
            }
            if let Some(before) = last.insert(cell, i as u32) {
                previous[i] = before;
            }
        }
    }
    point_to_unique
        .into_iter()
        .map(|u| find(&mut parent, u))
        .collect()
}

/// Groups of more corners than this are averaged by the shortcuts of
/// [`smooth_group`]; smaller ones by the direct comparison of every pair.
const DIRECT_GROUP: usize = 64;

/// At most this many crease comparisons per corner of a large group (plus
/// one pass over its corners), so that smoothing is linear in the model's
/// size whatever its shape.
pub const WORK_PER_CORNER: u64 = 64;

/// Shading normal per corner of `parts` (each a soup of three corners per
/// triangle). Never NaN: a corner with nothing to average (a degenerate
/// triangle) takes the average of every face at its position, else `+Y`.
/// Corners after the last whole triangle of a part take `+Y`.
pub fn smooth_normals(parts: &[&[Vec3]], options: &SmoothingOptions) -> Vec<Vec<Vec3>> {
    smooth_normals_counted(parts, options).0
}

/// [`smooth_normals`], and the number of crease comparisons (one face
/// normal against another) it made: at most [`WORK_PER_CORNER`] + 1 per
/// corner for any input, which tests check.
pub fn smooth_normals_counted(
    parts: &[&[Vec3]],
    options: &SmoothingOptions,
) -> (Vec<Vec<Vec3>>, u64) {
    let cos_crease = f64::from(options.crease_degrees.clamp(0.0, 180.0))
        .to_radians()
        .cos();
    let whole = |p: &[Vec3]| p.len() / 3 * 3;
    let mut comparisons = 0;
    let scoped: Vec<Vec<Vec3>> = match options.mode {
        Smoothing::Face | Smoothing::File => parts
            .iter()
            .map(|p| {
                face_data(&p[..whole(p)])
                    .iter()
                    .flat_map(|(n, _)| [unit_or(*n, DVec3::Y); 3])
                    .collect()
            })
            .collect(),
        Smoothing::Object => parts
            .iter()
            .map(|p| {
                let (normals, work) = smooth_scope(&p[..whole(p)], options, cos_crease);
                comparisons += work;
                normals
            })
            .collect(),
        Smoothing::Model => {
            // One scope of every part's whole triangles, back to back.
            let mut points = Vec::with_capacity(parts.iter().map(|p| whole(p)).sum());
            for p in parts {
                points.extend_from_slice(&p[..whole(p)]);
            }
            let (all, work) = smooth_scope(&points, options, cos_crease);
            comparisons += work;
            let mut rest = all.as_slice();
            parts
                .iter()
                .map(|p| {
                    let (mine, next) = rest.split_at(whole(p));
                    rest = next;
                    mine.to_vec()
                })
                .collect()
        }
    };
    let normals = scoped
        .into_iter()
        .zip(parts)
        .map(|(mut n, p)| {
            n.resize(p.len(), Vec3::Y);
            n
        })
        .collect();
    (normals, comparisons)
}

/// Threads worth starting for `items` units of work.
pub(crate) fn threads_for(items: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    // Below ~64k items, starting threads costs more than it saves.
    cores.min(items / 65_536).max(1)
}

/// Smooth normals of one weld scope: `points` holds whole triangles.
fn smooth_scope(points: &[Vec3], options: &SmoothingOptions, cos_crease: f64) -> (Vec<Vec3>, u64) {
    let faces = face_data(points);
    let ids = weld(points, options.weld_distance);
    // Members of each weld group as contiguous runs, by a counting sort
    // on the group id (ids are below the number of points): linear, and
    // cheaper than a map of small vectors. u32 offsets halve the memory
    // traffic of these corner-sized arrays (mesh indices are u32 as well).
    let count = points.len();
    let mut starts = vec![0u32; count + 1];
    for &id in &ids {
        starts[id + 1] += 1;
    }
    for i in 0..count {
        starts[i + 1] += starts[i];
    }
    let mut order = vec![0u32; count];
    {
        let mut next = starts.clone();
        for (k, &id) in ids.iter().enumerate() {
            order[next[id] as usize] = k as u32;
            next[id] += 1;
        }
    }
    drop(ids);
    // The normal of each corner in `order`'s order, group by group; the
    // groups are split between threads at group boundaries.
    let mut sorted = vec![Vec3::Y; count];
    let threads = threads_for(count);
    let mut bounds = vec![0usize];
    for t in 1..threads {
        // The first group starting at or after an even share of corners.
        let target = (count * t / threads) as u32;
        let group = starts.partition_point(|&s| s < target).min(count);
        if group > *bounds.last().unwrap_or(&0) {
            bounds.push(group);
        }
    }
    bounds.push(count);
    let work = std::thread::scope(|scope| {
        let mut rest = sorted.as_mut_slice();
        let mut handles = Vec::new();
        for pair in bounds.windows(2) {
            let (first, last) = (pair[0], pair[1]);
            let corners = (starts[last] - starts[first]) as usize;
            let (mine, next) = rest.split_at_mut(corners);
            rest = next;
            let (starts, order, faces) = (&starts, &order, &faces);
            handles.push(scope.spawn(move || {
                let mut work = 0;
                let base = starts[first] as usize;
                let mut scratch = Scratch::default();
                for group in first..last {
                    let (a, b) = (starts[group] as usize, starts[group + 1] as usize);
                    if a == b {
                        continue;
                    }
                    work += smooth_group(
                        &order[a..b],
                        faces,
                        cos_crease,
                        &mut mine[a - base..b - base],
                        &mut scratch,
                    );
                }
                work
            }));
        }
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .sum::<u64>()
    });
    let mut normals = vec![Vec3::Y; count];
    for (&k, n) in order.iter().zip(&sorted) {
        normals[k as usize] = *n;
    }
    (normals, work)
}

/// Reused buffers of [`smooth_group`].
#[derive(Default)]
struct Scratch {
    contributions: Vec<(DVec3, DVec3)>,
    classes: FastMap<[u64; 3], usize>,
    class_of: Vec<usize>,
    class_sums: Vec<(DVec3, DVec3)>,
    class_normals: Vec<Vec3>,
}

/// The normals of one weld group (corner indices `run`, ascending) into
/// `out`; returns the crease comparisons made.
///
/// Each corner averages the weighted face normals of the group's corners
/// whose face is within the crease angle of its own. Up to
/// [`DIRECT_GROUP`] corners, every pair is compared. A larger group (a fan
/// around one centre, a face repeated many times) is summed once when
/// every pair of its faces is within the crease angle (the same sum,
/// bit for bit); otherwise the corners are taken in classes of equal face
/// normal, compared class against class; and when even that would exceed
/// [`WORK_PER_CORNER`], the classes are cells of a grid of directions
/// sized so that it does not, each standing for its members' mean
/// direction (an approximation, only at such vertices, within the cell
/// size: under 10 degrees from 180 faces at one point, about 2 at 40,000).
fn smooth_group(
    run: &[u32],
    faces: &[(DVec3, [f64; 3])],
    cos_crease: f64,
    out: &mut [Vec3],
    scratch: &mut Scratch,
) -> u64 {
    let contributions = &mut scratch.contributions;
    contributions.clear();
    contributions.extend(run.iter().map(|&k| {
        let (n, w) = faces[k as usize / 3];
        (n, n * w[k as usize % 3])
    }));
    let total: DVec3 = contributions.iter().map(|c| c.1).sum();
    let fallback = unit_or(total, DVec3::Y).as_dvec3();
    let k = run.len();
    if k <= DIRECT_GROUP {
        for (slot, &(own, _)) in out.iter_mut().zip(contributions.iter()) {
            let sum: DVec3 = contributions
                .iter()
                .filter(|(n, _)| own.dot(*n) >= cos_crease - 1e-12)
                .map(|(_, weighted)| weighted)
                .sum();
            *slot = unit_or(sum, fallback);
        }
        return (k * k) as u64;
    }
    if every_pair_within(contributions, total, cos_crease) {
        // Every corner's sum is the total, added in the same order.
        out.fill(unit_or(total, fallback));
        return k as u64;
    }
    // Classes of equal face normal.
    let classes = &mut scratch.classes;
    let class_of = &mut scratch.class_of;
    classes.clear();
    class_of.clear();
    for (n, _) in contributions.iter() {
        let key = n.to_array().map(f64::to_bits);
        let next = classes.len();
        class_of.push(*classes.entry(key).or_insert(next));
    }
    let limit = WORK_PER_CORNER * k as u64;
    let sums = &mut scratch.class_sums;
    sums.clear();
    if (classes.len() as u64).pow(2) <= limit {
        sums.resize(classes.len(), (DVec3::ZERO, DVec3::ZERO));
        for (&c, &(n, weighted)) in class_of.iter().zip(contributions.iter()) {
            sums[c] = (n, sums[c].1 + weighted);
        }
    } else {
        // Cells of an octahedral map of directions, side chosen so that
        // the cells number at most sqrt(limit).
        let side = ((limit as f64).sqrt().sqrt().floor() as usize).max(1);
        classes.clear();
        class_of.clear();
        for (n, _) in contributions.iter() {
            let key = match octahedral_cell(*n, side) {
                Some(cell) => [cell as u64, 0, 0],
                None => [u64::MAX; 3],
            };
            let next = classes.len();
            class_of.push(*classes.entry(key).or_insert(next));
        }
        sums.resize(classes.len(), (DVec3::ZERO, DVec3::ZERO));
        for (&c, &(n, weighted)) in class_of.iter().zip(contributions.iter()) {
            sums[c] = (sums[c].0 + n, sums[c].1 + weighted);
        }
        for s in sums.iter_mut() {
            s.0 = s.0.try_normalize().unwrap_or(DVec3::ZERO);
        }
    }
    let d = sums.len();
    let normals = &mut scratch.class_normals;
    normals.clear();
    normals.extend(sums.iter().map(|&(own, _)| {
        let sum: DVec3 = sums
            .iter()
            .filter(|(n, _)| own.dot(*n) >= cos_crease - 1e-12)
            .map(|(_, weighted)| weighted)
            .sum();
        unit_or(sum, fallback)
    }));
    for (slot, &c) in out.iter_mut().zip(class_of.iter()) {
        *slot = normals[c];
    }
    (d * d + k) as u64
}

/// True when every two of the (unit or zero) face normals are within the
/// crease angle, shown with a margin: each lies within half of it of their
/// mean direction.
fn every_pair_within(contributions: &[(DVec3, DVec3)], total: DVec3, cos_crease: f64) -> bool {
    if cos_crease <= -1.0 {
        return true;
    }
    let Some(mean) = total.try_normalize() else {
        return false;
    };
    let closest = contributions
        .iter()
        .filter(|(n, _)| *n != DVec3::ZERO)
        .map(|(n, _)| n.dot(mean))
        .fold(1.0_f64, f64::min);
    let widest = closest.clamp(-1.0, 1.0).acos();
    2.0 * widest + 1e-9 <= cos_crease.clamp(-1.0, 1.0).acos()
}

/// The cell of unit direction `n` in a `side` x `side` grid over the
/// octahedral map of the sphere, `None` for a zero vector.
fn octahedral_cell(n: DVec3, side: usize) -> Option<usize> {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if l1 == 0.0 || !l1.is_finite() {
        return None;
    }
    let p = n / l1;
    let (mut u, mut v) = (p.x, p.y);
    if p.z < 0.0 {
        (u, v) = (
            (1.0 - p.y.abs()) * p.x.signum(),
            (1.0 - p.x.abs()) * p.y.signum(),
        );
    }
    let cell = |x: f64| (((x + 1.0) * 0.5 * side as f64) as usize).min(side - 1);
    Some(cell(u) * side + cell(v))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn options(mode: Smoothing, crease_degrees: f32) -> SmoothingOptions {
        SmoothingOptions {
            mode,
            crease_degrees,
            weld_distance: 0.0,
        }
    }

    /// The same triangle `count` times (`f 1 2 3` repeated).
    fn repeated(count: usize) -> Vec<Vec3> {
        [Vec3::ZERO, Vec3::X, Vec3::Y].repeat(count)
    }

    /// A fan of `segments` triangles around one centre vertex at height
    /// `height` over a unit circle: a flat disk for 0, a cone otherwise.
    /// With `pleat`, every other rim point is lifted by it (a star whose
    /// faces take two families of directions).
    fn fan(segments: usize, height: f32, pleat: f32) -> Vec<Vec3> {
        let rim = |i: usize| {
            let a = (i % segments) as f32 / segments as f32 * std::f32::consts::TAU;
            let lift = if i % 2 == 1 { pleat } else { 0.0 };
            Vec3::new(a.cos(), a.sin(), lift)
        };
        (0..segments)
            .flat_map(|i| [Vec3::new(0.0, 0.0, height), rim(i), rim(i + 1)])
            .collect()
    }

    fn assert_work_bounded(name: &str, points: &[Vec3], crease: f32) -> Vec<Vec3> {
        let (normals, work) = smooth_normals_counted(&[points], &options(Smoothing::Model, crease));
        let bound = (WORK_PER_CORNER + 1) * points.len() as u64;
        assert!(
            work <= bound,
            "{name}: {work} comparisons for {} corners (bound {bound})",
            points.len()
        );
        let normals = normals.into_iter().next().unwrap();
        assert!(normals
            .iter()
            .all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-5));
        normals
    }

    /// Corners sharing one position (a face repeated, a fan around one
    /// centre, flat, as a cone, and pleated so that its faces differ by
    /// more than the crease angle) cost a bounded number of comparisons
    /// per corner at every size: smoothing is linear in the model's size.
    #[test]
    fn smoothing_work_per_corner_is_bounded_where_corners_share_a_position() {
        for count in [1_000, 8_000, 40_000] {
            let normals = assert_work_bounded("repeated face", &repeated(count), 60.0);
            assert!(normals.iter().all(|n| *n == Vec3::Z));
            let normals = assert_work_bounded("disk", &fan(count, 0.0, 0.0), 60.0);
            assert!(normals.iter().all(|n| n.distance(Vec3::Z) < 1e-6));
            // A cone whose opposite faces are 90 degrees apart: the centre's
            // faces span more than the crease angle, and all differ.
            assert_work_bounded("cone", &fan(count, 1.0, 0.0), 60.0);
            assert_work_bounded("pleated", &fan(count, 0.3, 0.8), 60.0);
            assert_work_bounded("pleated, crease 0", &fan(count, 0.3, 0.8), 0.0);
        }
    }

    /// The wall clock agrees: 40,000 repeated faces and a 40,000-segment
    /// cone (seconds each before, quadratic) take well under a second, even
    /// unoptimised on a busy machine.
    #[test]
    fn shared_positions_smooth_in_linear_time() {
        for points in [repeated(40_000), fan(40_000, 1.0, 0.0)] {
            let start = std::time::Instant::now();
            smooth_normals(&[&points], &options(Smoothing::Model, 60.0));
            let seconds = start.elapsed().as_secs_f64();
            assert!(seconds < 5.0, "{seconds} s");
        }
    }

    /// Large groups against the direct oracle: all faces within the crease
    /// angle (the one sum, bit for bit), a few distinct normals repeated
    /// (classes of equal normal, to rounding), and thousands of distinct
    /// normals in two families 90 degrees apart, far from the crease
    /// threshold, and a steep cone (direction cells: within 10 degrees).
    #[test]
    fn large_groups_match_the_direct_oracle() {
        let check = |name: &str, points: &[Vec3], crease: f32, tolerance: f32| {
            let o = options(Smoothing::Model, crease);
            let fast = smooth_normals(&[points], &o);
            let slow = naive_normals(&[points], &o);
            for (i, (a, b)) in fast[0].iter().zip(&slow[0]).enumerate() {
                if tolerance == 0.0 {
                    assert_eq!(a, b, "{name} {i}");
                } else {
                    assert!(a.angle_between(*b) <= tolerance, "{name}: {a} vs {b}");
                }
            }
        };
        check("cone within the crease", &fan(500, 0.2, 0.0), 60.0, 0.0);
        check("steep cone", &fan(500, 5.0, 0.0), 60.0, 10f32.to_radians());
        // A square pyramid's four faces, each 100 times.
        let pyramid: Vec<Vec3> = fan(4, 1.0, 0.0).repeat(100);
        check("repeated pyramid", &pyramid, 60.0, 1e-6);
        // 2000 faces, pleated so that neighbours differ by about 90 degrees.
        let pleated = fan(2000, 0.0, 40.0);
        check("pleated star", &pleated, 45.0, 10f32.to_radians());
    }
}
