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
    let mut position_of: Vec<u32> = Vec::with_capacity(count);
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
            position_of.push(id);
        }
    }
    drop(table);
    if distance > 0.0 {
        let group_of_position = weld_by_distance(&unique, f64::from(distance));
        let groups = group_of_position.iter().map(|&g| g as usize + 1).max();
        return Welded {
            position_of,
            group_of_position: Some(group_of_position),
            groups: groups.unwrap_or(0),
        };
    }
    Welded {
        position_of,
        group_of_position: None,
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
    // coordinates' own precision, so that scaled coordinates stay within
    // 2^19: a cell's coordinates then pack into one 64-bit key (21 bits
    // each), and their rounding error stays far below the margin that
    // decides which neighbouring cells to search.
    let size = (4.0 * distance).max(f64::from(extent) * 2f64.powi(-19));
    let inv = 1.0 / size;
    // A point whose scaled coordinate is within `reach` of a cell face
    // (plus a margin for the rounding of the scaling) may have partners in
    // the neighbouring cell on that side; otherwise only in its own.
    let reach = distance * inv + 0.05;
    // Coordinates offset to be positive (and never at the ends of their 21
    // bits), so that a neighbour's key is the key plus a constant.
    const OFFSET: i64 = (1 << 19) + 2;
    const AXIS: [u64; 3] = [1 << 42, 1 << 21, 1];
    let key_of = |c: glam::DVec3| -> u64 {
        let [x, y, z] = c.as_i64vec3().to_array().map(|v| (v + OFFSET) as u64);
        x * AXIS[0] + y * AXIS[1] + z
    };

    // The finite points sorted by cell: the grid's cells become runs of one
    // array, and a neighbouring cell's run is found by a cursor moving
    // forward through it, so every access is sequential (a table of cells
    // costs a cache miss per lookup once the points outgrow the caches).
    let mut sorted: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .filter(|(_, p)| finite(p))
        .map(|(i, p)| (key_of((p.as_dvec3() * inv).floor()), i as u32))
        .collect();
    sorted.sort_unstable();
    // Each pair of points is compared once, from the point whose cell
    // comes first: within its own cell, the points after it; and the cells
    // after its own in key order among its neighbours within reach (13 of
    // the 26). Each of those has a cursor, moving forward as the keys do.
    let forward: Vec<[i64; 3]> = (-1..=1)
        .flat_map(|dx| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| [dx, dy, dz])))
        .filter(|&o| o > [0, 0, 0])
        .collect();
    let mut cursors = vec![0usize; forward.len()];
    let join = |i: u32, j: u32, parent: &mut Vec<u32>| {
        if points[j as usize]
            .as_dvec3()
            .distance(points[i as usize].as_dvec3())
            <= distance
        {
            let (a, b) = (find(parent, i), find(parent, j));
            parent[a.max(b) as usize] = a.min(b);
        }
    };
    for (s, &(key, i)) in sorted.iter().enumerate() {
        for &(other, j) in &sorted[s + 1..] {
            if other != key {
                break;
            }
            join(i, j, &mut parent);
        }
        let scaled = points[i as usize].as_dvec3() * inv;
        let fraction = scaled - scaled.floor();
        let below = fraction.to_array().map(|f| f < reach);
        let above = fraction.to_array().map(|f| f > 1.0 - reach);
        for (offset, cursor) in forward.iter().zip(&mut cursors) {
            let within = (0..3).all(|a| match offset[a] {
                -1 => below[a],
                1 => above[a],
                _ => true,
            });
            if !within {
                continue;
            }
            let target = offset.iter().zip(AXIS).fold(key, |k, (&o, axis)| {
                k.wrapping_add((o as u64).wrapping_mul(axis))
            });
            while *cursor < sorted.len() && sorted[*cursor].0 < target {
                *cursor += 1;
            }
            for &(other, j) in &sorted[*cursor..] {
                if other != target {
                    break;
                }
                join(i, j, &mut parent);
            }
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
