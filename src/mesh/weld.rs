//! Welding: which corners of a triangle soup are one point, exactly (equal
//! bits) or within a distance (transitively), as a group number per corner.
//!
//! Corners are joined in one pass through a table of distinct positions
//! sized by their number, not by the number of corners (a closed mesh has
//! about six corners per position), so that it stays small. Only the
//! distinct positions are then welded by distance, on a grid of cells four
//! tolerances wide, sorted by cell so that every access is sequential: a
//! hash table of cells, or even a bit set of the occupied ones, costs a
//! cache miss per lookup once the points outgrow the caches. The groups
//! are the connected components of "within the distance": the same
//! whatever the order of the comparisons. The exact position numbers are
//! kept too: the tangent stage joins vertices from them.

use glam::Vec3;

use super::join::{hash_words, IndexTable};

/// The weld groups of a scope of corners.
pub(crate) struct Welded {
    /// The number of each corner's exact position (the scope's slices back
    /// to back), in order of first appearance: corners with bit-identical
    /// positions (`-0.0` as `0.0`) share a number. Vertex joining reuses
    /// these ([`super::tangents`]).
    pub position_of: Vec<u32>,
    /// The group of each position, when welding by distance joined some
    /// (`None`: every position is its own group). Groups are numbered in
    /// the order of their first corner.
    pub group_of_position: Option<Vec<u32>>,
    /// The number of groups.
    pub groups: usize,
}

impl Welded {
    /// The group of each corner.
    pub fn group_of(&self) -> std::borrow::Cow<'_, [u32]> {
        match &self.group_of_position {
            None => std::borrow::Cow::Borrowed(&self.position_of),
            Some(group) => self
                .position_of
                .iter()
                .map(|&p| group[p as usize])
                .collect(),
        }
    }
}

/// Groups of the corners of `slices` (taken back to back) within
/// `distance` of one another, transitively; 0 joins bit-identical
/// positions only (`-0.0` and `0.0` are one).
///
/// `indices`, when given for a slice (one per corner, as many as its
/// corners), are the file's vertex indices: corners with equal indices
/// have bit-identical positions (the caller guarantees it). Only the first
/// corner of each index is then looked up in the table of distinct
/// positions, the others take its number from an array indexed by the
/// vertex index: a closed mesh has about six corners per vertex. The
/// numbers are the same either way (positions numbered in order of their
/// first corner), and different indices with equal positions (an
/// object's copy of another's boundary) are still joined by the table.
pub(crate) fn weld_corners(
    slices: &[&[Vec3]],
    indices: &[Option<&[u32]>],
    distance: f32,
) -> Welded {
    let count: usize = slices.iter().map(|s| s.len()).sum();
    assert!(
        count < u32::MAX as usize,
        "{count} corners: more than 32-bit indices can address"
    );
    // Distinct positions, in order of first appearance; the group of each
    // corner starts as its position's number.
    let mut table = IndexTable::with_capacity(count / 6 + 16);
    let mut unique: Vec<Vec3> = Vec::with_capacity(count / 5 + 16);
    let mut position_of: Vec<u32> = Vec::with_capacity(count);
    // In batches: their first slots are read together first (see
    // `IndexTable::touch`).
    let mut keys = [[0u32; 3]; BATCH];
    let mut hashes = [0u64; BATCH];
    // The number of each vertex index of the slice at hand (`u32::MAX`
    // before its first corner), reused from slice to slice.
    let mut numbered: Vec<u32> = Vec::new();
    for (s, slice) in slices.iter().enumerate() {
        let given = indices.get(s).copied().flatten();
        let given = given.filter(|g| g.len() == slice.len());
        // Indices spread far beyond the slice's corners (a part numbered
        // within a larger model) would cost an array larger than the
        // table: those corners are hashed instead.
        let vertices = given.map_or(0, |g| g.iter().max().map_or(0, |&m| m as usize + 1));
        let Some(given) = given.filter(|_| vertices <= 2 * slice.len() + 1024) else {
            for batch in slice.chunks(BATCH) {
                for ((key, hash), p) in keys.iter_mut().zip(&mut hashes).zip(batch) {
                    // + 0.0 so that -0.0 and 0.0 are one key.
                    *key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
                    *hash = hash_words(*key);
                }
                table.touch(&hashes[..batch.len()]);
                for (&key, &hash) in keys.iter().zip(&hashes).take(batch.len()) {
                    let next = unique.len() as u32;
                    let id = table.get_or_insert(hash, next, |u| {
                        unique[u as usize].to_array().map(f32::to_bits) == key
                    });
                    if id == next {
                        unique.push(Vec3::from_array(key.map(f32::from_bits)));
                    }
                    position_of.push(id);
                }
            }
            continue;
        };
        numbered.clear();
        numbered.resize(vertices, u32::MAX);
        // Batches of corners large enough to hold about BATCH first
        // corners of an index (one in six on a closed mesh), cut short
        // when BATCH are found. Each batch's table slots are read while
        // the batch before it is joined, so that their cache misses are
        // waited for behind that work rather than in front of it.
        let mut current = Batch::default();
        let mut ahead = Batch::default();
        current.collect(0, slice, given, &mut numbered);
        table.touch(current.hashes());
        while !current.span.is_empty() {
            ahead.collect(current.span.end, slice, given, &mut numbered);
            table.touch(ahead.hashes());
            for ((&key, &hash), &corner) in current
                .keys
                .iter()
                .zip(&current.hashes)
                .zip(&current.firsts)
                .take(current.found)
            {
                let next = unique.len() as u32;
                let id = table.get_or_insert(hash, next, |u| {
                    unique[u as usize].to_array().map(f32::to_bits) == key
                });
                if id == next {
                    unique.push(Vec3::from_array(key.map(f32::from_bits)));
                }
                numbered[given[corner as usize] as usize] = id;
            }
            let span = current.span.clone();
            position_of.extend(given[span].iter().map(|&i| numbered[i as usize]));
            std::mem::swap(&mut current, &mut ahead);
        }
        debug_assert!(
            slice
                .iter()
                .zip(&position_of[position_of.len() - slice.len()..])
                .all(|(p, &n)| (*p + Vec3::ZERO).to_array().map(f32::to_bits)
                    == unique[n as usize].to_array().map(f32::to_bits)),
            "corners with equal vertex indices at different positions"
        );
    }
    drop(table);
    if distance > 0.0 {
        let group_of_position = weld_by_distance(&unique, f64::from(distance));
        let groups = group_of_position.iter().map(|&g| g as usize + 1).max();
        let groups = groups.unwrap_or(0);
        // Groups are numbered in order of their first position, so when
        // every position is its own group (the distance joined none: the
        // common case) the numbering is the identity, and the corners'
        // position numbers serve as their groups without a copy.
        return Welded {
            position_of,
            group_of_position: (groups < unique.len()).then_some(group_of_position),
            groups,
        };
    }
    Welded {
        position_of,
        group_of_position: None,
        groups: unique.len(),
    }
}

/// Corners per batch of table lookups in [`weld_corners`].
const BATCH: usize = 16;

/// Pending marker in [`weld_corners`]'s numbers of vertex indices: the
/// index's first corner is in a batch not yet joined.
const PENDING: u32 = u32::MAX - 1;

/// A batch of indexed corners in [`weld_corners`]: the corners it spans,
/// and those that are their vertex index's first (whose positions are
/// looked up), with their position keys and hashes, in corner order.
#[derive(Default)]
struct Batch {
    span: std::ops::Range<usize>,
    found: usize,
    keys: [[u32; 3]; BATCH],
    hashes: [u64; BATCH],
    firsts: [u32; BATCH],
}

impl Batch {
    /// The batch starting at corner `start` of `slice` (vertex indices
    /// `given`), marking each index it is the first to use as pending in
    /// `numbered` (`u32::MAX` for an index not seen yet).
    fn collect(&mut self, start: usize, slice: &[Vec3], given: &[u32], numbered: &mut [u32]) {
        self.found = 0;
        let mut end = start;
        while end < slice.len() && self.found < BATCH {
            let slot = &mut numbered[given[end] as usize];
            if *slot == u32::MAX {
                // Pending: its later corners wait for this batch's join.
                *slot = PENDING;
                let key = (slice[end] + Vec3::ZERO).to_array().map(f32::to_bits);
                self.keys[self.found] = key;
                self.hashes[self.found] = hash_words(key);
                self.firsts[self.found] = end as u32;
                self.found += 1;
            }
            end += 1;
        }
        self.span = start..end;
    }

    /// The hashes of the batch's first corners.
    fn hashes(&self) -> &[u64] {
        &self.hashes[..self.found]
    }
}

/// The forward neighbours of a grid cell: the 13 of its 26 neighbours
/// whose keys come after its own (offsets along x, y, z), so that each
/// pair of cells is searched once, from the cell that comes first.
const FORWARD: [[i64; 3]; 13] = [
    [0, 0, 1],
    [0, 1, -1],
    [0, 1, 0],
    [0, 1, 1],
    [1, -1, -1],
    [1, -1, 0],
    [1, -1, 1],
    [1, 0, -1],
    [1, 0, 0],
    [1, 0, 1],
    [1, 1, -1],
    [1, 1, 0],
    [1, 1, 1],
];

/// A cell key's weight per axis: 21 bits each.
const AXIS: [u64; 3] = [1 << 42, 1 << 21, 1];

/// A distinct point on the grid of [`weld_by_distance`]: its cell's key,
/// its number, and which of the [`FORWARD`] neighbouring cells it is
/// within reach of (bit `k` for `FORWARD[k]`), so that the search over
/// the sorted points reads nothing but this array.
#[derive(Clone, Copy)]
struct OnGrid {
    key: u64,
    index: u32,
    near: u32,
}

/// The box of the finite coordinates of `points`, axis by axis (an axis
/// with none has low +inf and high -inf). Four points at a time, as
/// twelve floats side by side compared without branches, so that the
/// comparisons run in vector registers: a point at a time, with the NaN
/// handling of `f32::min` and `max`, took 9.4 ms for the 3 million
/// corners of a 10⁶-triangle model (this takes 4.0, about what reading
/// them from memory takes), and 3.5 to 4 ms for its half a million
/// distinct positions (this takes 1).
pub(crate) fn finite_bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    const WIDTH: usize = 12;
    let mut low = [f32::INFINITY; WIDTH];
    let mut high = [f32::NEG_INFINITY; WIDTH];
    // A non-finite coordinate is replaced by values that change neither
    // bound (`|x| < INFINITY` is false for infinities and NaN alike).
    let widen = |low: &mut [f32; WIDTH], high: &mut [f32; WIDTH], floats: &[f32]| {
        for k in 0..floats.len().min(WIDTH) {
            let x = floats[k];
            let finite = x.abs() < f32::INFINITY;
            let (down, up) = if finite {
                (x, x)
            } else {
                (f32::INFINITY, f32::NEG_INFINITY)
            };
            low[k] = if down < low[k] { down } else { low[k] };
            high[k] = if up > high[k] { up } else { high[k] };
        }
    };
    let floats: &[f32] = bytemuck::cast_slice(points);
    let mut chunks = floats.chunks_exact(WIDTH);
    for chunk in &mut chunks {
        widen(&mut low, &mut high, chunk);
    }
    // The remainder is whole points, so its floats keep their lanes' axes.
    widen(&mut low, &mut high, chunks.remainder());
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for (k, (&l, &h)) in low.iter().zip(&high).enumerate() {
        lo[k % 3] = lo[k % 3].min(l);
        hi[k % 3] = hi[k % 3].max(h);
    }
    (lo, hi)
}

/// The largest magnitude of any finite coordinate of `points` (0 when
/// none is): a bound on every coordinate of every finite point. An axis
/// without finite coordinates has infinite bounds, which the comparison
/// with 0 leaves out.
fn finite_extent(points: &[Vec3]) -> f32 {
    let (lo, hi) = finite_bounds(points);
    (-lo).max(hi).to_array().into_iter().fold(0.0, |m, x| {
        if x.abs() < f32::INFINITY && x > m {
            x
        } else {
            m
        }
    })
}

/// The group of each of the distinct `points` (numbered in order of their
/// first point), joining points within `distance` transitively.
fn weld_by_distance(points: &[Vec3], distance: f64) -> Vec<u32> {
    // Union-find whose root is always the smallest index of its set, so
    // that groups can be numbered in order of first appearance below.
    let mut parent: Vec<u32> = (0..points.len() as u32).collect();
    let grid = Grid::new(points, distance);
    let sorted = grid.sorted(points);
    join_within(points, &sorted, distance, &mut parent);
    // Number the groups in order of their smallest point (the root).
    let mut group = vec![0u32; points.len()];
    let mut groups = 0;
    for i in 0..points.len() as u32 {
        let root = find_root(&mut parent, i);
        group[i as usize] = if root == i {
            groups += 1;
            groups - 1
        } else {
            group[root as usize]
        };
    }
    group
}

/// The root of `i`'s set in the union-find `parent`, halving the path on
/// the way.
fn find_root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let grand = parent[parent[i as usize] as usize];
        parent[i as usize] = grand;
        i = grand;
    }
    i
}

/// The grid [`weld_by_distance`] sorts the points into.
struct Grid {
    /// One over the cells' size.
    inv: f64,
    /// A point whose scaled coordinate is within `reach` of a cell face
    /// may have partners in the neighbouring cell on that side; otherwise
    /// only in its own.
    reach: f64,
    /// Per axis, the neighbours whose offset along it is -1, 0 or +1.
    masks: [[u32; 3]; 3],
}

impl Grid {
    fn new(points: &[Vec3], distance: f64) -> Grid {
        let extent = finite_extent(points);
        // Cells four tolerances wide, or wider when the tolerance is below the
        // coordinates' own precision, so that scaled coordinates stay within
        // 2^19: a cell's coordinates then pack into one 64-bit key (21 bits
        // each), and their rounding error (below 2^-32 of a cell) stays far
        // below the margin that decides which neighbouring cells to search.
        let size = (4.0 * distance).max(f64::from(extent) * 2f64.powi(-19));
        let inv = 1.0 / size;
        let reach = distance * inv + 1e-3;
        let along = |axis: usize, step: i64| -> u32 {
            (0..FORWARD.len())
                .filter(|&k| FORWARD[k][axis] == step)
                .fold(0, |m, k| m | 1 << k)
        };
        let masks: [[u32; 3]; 3] = [0, 1, 2].map(|a| [along(a, -1), along(a, 0), along(a, 1)]);
        Grid { inv, reach, masks }
    }

    /// The finite points sorted by cell: the grid's cells become runs of one
    /// array, and a neighbouring cell's run is found by a cursor moving
    /// forward through it, so every access is sequential (a table of cells
    /// costs a cache miss per lookup once the points outgrow the caches).
    /// Non-finite points are never within any distance of another point
    /// (the difference is infinite or NaN): only finite ones go on the grid.
    fn sorted(&self, points: &[Vec3]) -> Vec<OnGrid> {
        // Coordinates offset to be positive (and never at the ends of their 21
        // bits), so that truncation is the floor and a neighbour's key is the
        // key plus a constant.
        const OFFSET: f64 = ((1 << 19) + 2) as f64;
        let reach = self.reach;
        let mut sorted: Vec<OnGrid> = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            if !p.is_finite() {
                continue;
            }
            let scaled = p.as_dvec3() * self.inv + OFFSET;
            let (mut key, mut near) = (0, u32::MAX);
            for (axis, &s) in scaled.to_array().iter().enumerate() {
                // Positive: the truncation (to i64, one instruction) is the floor.
                let cell = s as i64;
                let fraction = s - cell as f64;
                // Masks, not branches: which faces of its cell a point lies
                // near is as good as random, and branches on it cost twice the
                // rest of this loop (14 to 16 ms against 5 ms for half a million).
                // `below_zero(x - y)` is `x < y`: a difference has the sign of
                // the exact difference, and only equal values give (+)0.
                let below_zero = |x: f64| 0u32.wrapping_sub((x.to_bits() >> 63) as u32);
                let [below, level, above] = self.masks[axis];
                near &= level
                    | below & below_zero(fraction - reach)
                    | above & below_zero((1.0 - reach) - fraction);
                key += cell as u64 * AXIS[axis];
            }
            sorted.push(OnGrid {
                key,
                index: i as u32,
                near,
            });
        }
        sorted.sort_unstable_by_key(|g| g.key);
        sorted
    }
}

/// Joins in `parent` every two points of `sorted` within `distance`. Each
/// pair of points is compared once, from the point whose cell comes first:
/// within its own cell, the points after it; and the forward neighbouring
/// cells within its reach, each through a cursor that moves forward as the
/// keys do.
fn join_within(points: &[Vec3], sorted: &[OnGrid], distance: f64, parent: &mut [u32]) {
    let delta = FORWARD.map(|offset| {
        offset.iter().zip(AXIS).fold(0u64, |k, (&o, axis)| {
            k.wrapping_add((o as u64).wrapping_mul(axis))
        })
    });
    let join = |i: u32, j: u32, parent: &mut [u32]| {
        if points[j as usize]
            .as_dvec3()
            .distance(points[i as usize].as_dvec3())
            <= distance
        {
            let (a, b) = (find_root(parent, i), find_root(parent, j));
            parent[a.max(b) as usize] = a.min(b);
        }
    };
    let mut cursors = [0usize; FORWARD.len()];
    for (s, here) in sorted.iter().enumerate() {
        for other in &sorted[s + 1..] {
            if other.key != here.key {
                break;
            }
            join(here.index, other.index, parent);
        }
        let mut near = here.near;
        while near != 0 {
            let k = near.trailing_zeros() as usize;
            near &= near - 1;
            let target = here.key.wrapping_add(delta[k]);
            let cursor = &mut cursors[k];
            while *cursor < sorted.len() && sorted[*cursor].key < target {
                *cursor += 1;
            }
            for other in &sorted[*cursor..] {
                if other.key != target {
                    break;
                }
                join(here.index, other.index, parent);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Welding by distance against every pair compared directly: points in
    /// tight clusters (chains of points just within and just beyond the
    /// distance, across cell faces and corners, at negative and positive
    /// coordinates), the same groups, numbered the same way.
    #[test]
    fn distance_welding_matches_every_pair() {
        let mut next = crate::mesh::tests::uniform_stream(0x853c_49e6_748f_ea9b_u64);
        for round in 0..40 {
            let distance = [1e-3f32, 0.01, 0.1, 0.37][round % 4];
            let centres: Vec<Vec3> = (0..8)
                .map(|_| (Vec3::new(next(), next(), next()) * 2.0 - 1.0) * 0.2)
                .collect();
            let points: Vec<Vec3> = (0..300)
                .map(|_| {
                    let c = centres[(next() * 8.0) as usize % 8];
                    let offset = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
                    c + offset * distance * (0.5 + [3.0, 30.0][round % 2] * next())
                })
                .collect();
            // In every third round, a few points with a non-finite
            // coordinate (each its own group, and no bound on the grid);
            // the largest coordinate then belongs to one of them.
            let mut points = points;
            if round % 3 == 0 {
                for (k, bad) in [f32::NAN, f32::INFINITY, -f32::INFINITY]
                    .into_iter()
                    .enumerate()
                {
                    points[37 * k + 5][k] = bad;
                    points[37 * k + 6] = Vec3::new(bad, 9.0, -9.0);
                }
            }
            let d = f64::from(distance);
            // Every pair: union-find whose root is the smallest index.
            let mut parent: Vec<usize> = (0..points.len()).collect();
            fn root(parent: &[usize], mut i: usize) -> usize {
                while parent[i] != i {
                    i = parent[i];
                }
                i
            }
            for i in 0..points.len() {
                for j in i + 1..points.len() {
                    if points[i].as_dvec3().distance(points[j].as_dvec3()) <= d {
                        let (a, b) = (root(&parent, i), root(&parent, j));
                        parent[a.max(b)] = a.min(b);
                    }
                }
            }
            let mut expected = vec![0u32; points.len()];
            let mut groups = 0;
            for i in 0..points.len() {
                let r = root(&parent, i);
                expected[i] = if r == i {
                    groups += 1;
                    groups - 1
                } else {
                    expected[r]
                };
            }
            assert_eq!(weld_by_distance(&points, d), expected, "round {round}");
        }
    }
}
