//! Welding: which corners of a triangle soup are one point, exactly (equal
//! bits) or within a distance (transitively), as a group number per corner.
//!
//! Corners are joined in one pass through a table of distinct positions
//! sized by their number, not by the number of corners (a closed mesh has
//! about six corners per position), so that it stays in the caches. Only
//! the distinct positions are then welded by distance, on a grid of cells
//! four tolerances wide, through a second such table; a bit set of the
//! occupied cells answers the common question, whether a neighbouring cell
//! holds anything, without probing the table. The groups are the
//! connected components of "within the distance": the same whatever the
//! order of the comparisons.

use glam::Vec3;

use super::join::{hash_words, IndexTable};

/// The weld groups of a scope of corners.
pub(crate) struct Welded {
    /// The group of each corner (the scope's slices back to back), below
    /// `groups`. Groups are numbered in the order of their first corner.
    pub group_of: Vec<u32>,
    /// The number of groups.
    pub groups: usize,
}

/// Groups of the corners of `slices` (taken back to back) within
/// `distance` of one another, transitively; 0 joins bit-identical
/// positions only (`-0.0` and `0.0` are one).
pub(crate) fn weld_corners(slices: &[&[Vec3]], distance: f32) -> Welded {
    let count: usize = slices.iter().map(|s| s.len()).sum();
    assert!(
        count < u32::MAX as usize,
        "{count} corners: more than 32-bit indices can address"
    );
    // Distinct positions, in order of first appearance; the group of each
    // corner starts as its position's number.
    let mut table = IndexTable::with_capacity(count / 6 + 16);
    let mut unique: Vec<Vec3> = Vec::with_capacity(count / 5 + 16);
    let mut group_of: Vec<u32> = Vec::with_capacity(count);
    // In batches: their first slots are read together first (see
    // `IndexTable::touch`).
    const BATCH: usize = 16;
    let mut keys = [[0u32; 3]; BATCH];
    let mut hashes = [0u64; BATCH];
    for batch in slices.iter().flat_map(|s| s.chunks(BATCH)) {
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
            group_of.push(id);
        }
    }
    drop(table);
    if distance > 0.0 {
        let group_of_unique = weld_by_distance(&unique, f64::from(distance));
        let groups = group_of_unique.iter().map(|&g| g as usize + 1).max();
        for g in &mut group_of {
            *g = group_of_unique[*g as usize];
        }
        return Welded {
            group_of,
            groups: groups.unwrap_or(0),
        };
    }
    Welded {
        group_of,
        groups: unique.len(),
    }
}

/// The group of each of the distinct `points` (numbered in order of their
/// first point), joining points within `distance` transitively.
fn weld_by_distance(points: &[Vec3], distance: f64) -> Vec<u32> {
    // Union-find whose root is always the smallest index of its set, so
    // that groups can be numbered in order of first appearance below.
    let mut parent: Vec<u32> = (0..points.len() as u32).collect();
    fn find(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            let grand = parent[parent[i as usize] as usize];
            parent[i as usize] = grand;
            i = grand;
        }
        i
    }
    // Non-finite points are never within any distance of another point
    // (the difference is infinite or NaN): only finite ones go on the grid.
    let finite = |p: &Vec3| p.is_finite();
    let extent = points
        .iter()
        .filter(|p| finite(p))
        .map(|p| p.abs().max_element())
        .fold(0.0_f32, f32::max);
    // Cells four tolerances wide, or wider when the tolerance is below the
    // coordinates' own precision, so that scaled coordinates stay below
    // 2^40: their rounding error then stays far below the margin that
    // decides which neighbouring cells to search.
    let size = (4.0 * distance).max(f64::from(extent) * 2f64.powi(-40));
    let inv = 1.0 / size;
    // A point whose scaled coordinate is within `reach` of a cell face
    // (plus a margin for the rounding of the scaling) may have partners in
    // the neighbouring cell on that side; otherwise only in its own.
    let reach = distance * inv + 0.05;
    let cell_of = |p: Vec3| -> [i64; 3] { (p.as_dvec3() * inv).floor().as_i64vec3().to_array() };
    let cell_hash = |c: [i64; 3]| {
        let [x, y, z] = c.map(|v| v as u64);
        let words = [x, x >> 32, y, y >> 32, z, z >> 32];
        hash_words(words.map(|w| w as u32))
    };

    // The cell of a point, and along each axis whether its neighbouring
    // cells below and above are within reach.
    let neighbourhood = |p: Vec3| {
        let scaled = p.as_dvec3() * inv;
        let base = scaled.floor();
        let fraction = scaled - base;
        let span = |f: f64| -> (i64, i64) {
            (
                if f < reach { -1 } else { 0 },
                if f > 1.0 - reach { 1 } else { 0 },
            )
        };
        (
            base.as_i64vec3().to_array(),
            [span(fraction.x), span(fraction.y), span(fraction.z)],
        )
    };
    // Most points have no other point within reach. Two bit sets of
    // hashed cells (32 bits per point: a false "occupied" in about one of
    // 32 empty cells) find the candidates that may: those whose own cell
    // holds another point or whose neighbouring cells within reach hold
    // any. Both points of a pair within the distance are candidates (each
    // lies within reach of the other's cell), so only candidates need the
    // table of cells below. The bit sets are small enough for the caches
    // and are read without a branch per cell; the table is not.
    let bits = (points.len() * 32).next_power_of_two().max(1024);
    let bit_shift = 64 - bits.trailing_zeros();
    // The low bits of the hash choose the bit; the table uses the top ones.
    let bit_of = |c: [i64; 3]| ((cell_hash(c).rotate_left(32)) >> bit_shift) as usize;
    let mut once = vec![0u64; bits / 64];
    let mut twice = vec![0u64; bits / 64];
    for p in points.iter().filter(|p| finite(p)) {
        let bit = bit_of(cell_of(*p));
        let (word, mask) = (bit / 64, 1u64 << (bit % 64));
        twice[word] |= once[word] & mask;
        once[word] |= mask;
    }
    let mut candidates = Vec::new();
    for (i, p) in points.iter().enumerate() {
        if !finite(p) {
            continue;
        }
        let (base, spans) = neighbourhood(*p);
        let own = bit_of(base);
        let mut hit = (twice[own / 64] >> (own % 64)) & 1;
        each_cell(base, spans, |cell| {
            if cell != base {
                let bit = bit_of(cell);
                hit |= (once[bit / 64] >> (bit % 64)) & 1;
            }
        });
        if hit != 0 {
            candidates.push(i as u32);
        }
    }
    drop((once, twice));

    // The candidates on the grid: each cell's points as a chain (the table
    // maps a cell to one of its points, `next` links the rest), each point
    // compared with the points already in the cells within its reach.
    let mut cells = IndexTable::with_capacity(candidates.len());
    let mut next = vec![
        u32::MAX;
        if candidates.is_empty() {
            0
        } else {
            points.len()
        }
    ];
    for &i in &candidates {
        let here = points[i as usize].as_dvec3();
        let (base, spans) = neighbourhood(points[i as usize]);
        each_cell(base, spans, |cell| {
            let h = cell_hash(cell);
            let Some(mut j) = cells.get(h, |j| cell_of(points[j as usize]) == cell) else {
                return;
            };
            while j != u32::MAX {
                if points[j as usize].as_dvec3().distance(here) <= distance {
                    let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                    parent[a.max(b) as usize] = a.min(b);
                }
                j = next[j as usize];
            }
        });
        // Into its own cell's chain, after the cell's first point.
        let first =
            cells.get_or_insert(cell_hash(base), i, |j| cell_of(points[j as usize]) == base);
        if first != i {
            next[i as usize] = next[first as usize];
            next[first as usize] = i;
        }
    }
    // Number the groups in order of their smallest point (the root).
    let mut group = vec![0u32; points.len()];
    let mut groups = 0;
    for i in 0..points.len() as u32 {
        let root = find(&mut parent, i);
        group[i as usize] = if root == i {
            groups += 1;
            groups - 1
        } else {
            group[root as usize]
        };
    }
    group
}

/// Calls `f` with each cell from `base` offset by `spans` (per axis, the
/// lowest and highest offset).
fn each_cell(base: [i64; 3], spans: [(i64, i64); 3], mut f: impl FnMut([i64; 3])) {
    for dx in spans[0].0..=spans[0].1 {
        for dy in spans[1].0..=spans[1].1 {
            for dz in spans[2].0..=spans[2].1 {
                f([base[0] + dx, base[1] + dy, base[2] + dz]);
            }
        }
    }
}
