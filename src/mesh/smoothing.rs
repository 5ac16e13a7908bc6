//! Per-corner shading normals for triangle soups: face normals, or averages
//! over the faces that share a (welded) position within one object or across
//! the whole model, limited by a crease angle.
//!
//! Positions are welded through tables sized by the number of distinct
//! positions ([`super::weld`]), so smoothing a model is linear in its size.
//! Each weld group's weighted sum of face normals is then accumulated in
//! one pass over the corners, in corner order, into a flat array of groups:
//! where every face of a group is within the crease angle of every other
//! (the common case: a smooth surface) that sum, normalised, is every
//! corner's normal, bit for bit the sum the direct per-corner comparison
//! makes. Only the other groups (creases, degenerate faces, more than
//! [`DIRECT_GROUP`] corners) are gathered into runs and compared corner by
//! corner. [`naive_normals`] is the direct all-faces loop, kept as a test
//! oracle.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::mem::MaybeUninit;
use std::ops::Range;

use glam::{DVec3, Vec3};

use super::weld::weld_corners;

/// A fast, non-cryptographic hasher for integer keys (the standard SipHash
/// is DoS-resistant but several times slower, and these keys come from a
/// file the user chose to load).
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

/// A triangle's unit normal (zero for a degenerate triangle) and, per
/// corner, the weight that corner contributes: its interior angle, so that
/// how a surface is cut into triangles does not bias the average. The
/// angles are f32 (a weight needs no more, and f32 acos is much cheaper)
/// and enter the f64 sums exactly.
#[derive(Clone, Copy, Default)]
pub(crate) struct Face {
    normal: DVec3,
    weights: [f32; 3],
}

impl Face {
    fn of(t: &[Vec3]) -> Face {
        let [a, b, c] = [t[0], t[1], t[2]].map(|p| p.as_dvec3());
        let n = (b - a).cross(c - a);
        let Some(normal) = n.try_normalize() else {
            return Face::default();
        };
        let angle =
            |p: DVec3, q: DVec3, r: DVec3| corner_angle((q - p).as_vec3(), (r - p).as_vec3());
        let weights = [angle(a, b, c), angle(b, c, a), angle(c, a, b)];
        if weights.iter().any(|x| !x.is_finite()) {
            return Face::default();
        }
        Face { normal, weights }
    }

    /// The weighted normal corner `corner` (0 to 2) contributes.
    fn contribution(&self, corner: usize) -> DVec3 {
        self.normal * f64::from(self.weights[corner])
    }
}

/// A face's corner angles as the tangent stage weighs its frames by them
/// (computed the same way), kept after the rest of the face data is
/// freed: 12 bytes of the 40 of a [`Face`].
#[derive(Clone, Copy)]
pub(crate) struct FaceAngles([f32; 3]);

impl FaceAngles {
    /// The angles of `face`; NaN, which no measured angle of a face with a
    /// normal is, when it has none.
    fn of(face: &Face) -> Self {
        FaceAngles(if face.normal == DVec3::ZERO {
            [f32::NAN; 3]
        } else {
            face.weights
        })
    }

    /// The corner angles, when the face has a normal (`None` for a
    /// degenerate face).
    pub(crate) fn angles(&self) -> Option<[f32; 3]> {
        (!self.0[0].is_nan()).then_some(self.0)
    }
}

/// The angle between `u` and `v`, bit for bit glam's `Vec3::angle_between`
/// (its approximate arc cosine: the same operations in the same order),
/// but taking the obtuse side by a mask instead of a branch: whether a
/// corner is obtuse is as good as random on most meshes (a right angle's
/// cosine is rounding noise around zero), and a sampling profile put a
/// sixth of the face data's time on that branch.
pub(crate) fn corner_angle(u: Vec3, v: Vec3) -> f32 {
    let cosine = u.dot(v) / (u.length_squared() * v.length_squared()).sqrt();
    let x = cosine.abs();
    let one_minus = 1.0 - x;
    let root = if one_minus < 0.0 { 0.0 } else { one_minus }.sqrt();
    #[allow(clippy::approx_constant)]
    let acute =
        ((((((-0.001_262_491_1 * x + 0.006_670_09) * x - 0.017_088_126) * x + 0.030_891_88) * x
            - 0.050_174_303)
            * x
            + 0.088_978_99)
            * x
            - 0.214_598_8)
            * x
            + 1.570_796_3;
    let acute = acute * root;
    let obtuse = std::f32::consts::PI - acute;
    // All ones when the cosine is negative (or NaN, as glam's `>= 0` test).
    let mask = 0u32.wrapping_sub(u32::from((cosine < 0.0) | cosine.is_nan()));
    f32::from_bits(acute.to_bits() & !mask | obtuse.to_bits() & mask)
}

/// Every whole triangle of `slices` (back to back), on every core: faces
/// are independent.
fn face_data(slices: &[&[Vec3]]) -> Vec<Face> {
    let first_face = first_faces(slices);
    let total = first_face[slices.len()];
    let mut faces = fill_back_to_back(&[total], threads_for(3 * total), |range| {
        faces_in(slices, &first_face, range).map(Face::of)
    });
    faces.pop().unwrap_or_default()
}

/// The number of the first whole triangle of each slice, back to back, and
/// the total at the end.
fn first_faces(slices: &[&[Vec3]]) -> Vec<usize> {
    let mut first = Vec::with_capacity(slices.len() + 1);
    let mut sum = 0;
    first.push(0);
    for s in slices {
        sum += s.len() / 3;
        first.push(sum);
    }
    first
}

/// The corners of each face in `range` (faces numbered back to back over
/// `slices`, `first_face` from [`first_faces`]).
fn faces_in<'a>(
    slices: &'a [&'a [Vec3]],
    first_face: &'a [usize],
    range: Range<usize>,
) -> impl Iterator<Item = &'a [Vec3]> + 'a {
    slices.iter().zip(first_face).flat_map(move |(s, &base)| {
        let end = base + s.len() / 3;
        let (from, to) = (range.start.clamp(base, end), range.end.clamp(base, end));
        s[3 * (from - base)..3 * (to - base)].chunks_exact(3)
    })
}

/// Vectors of `lengths` values, filled in place on `threads` threads: taken
/// back to back, the values in `range` are those `values(range)` yields,
/// and each thread fills a contiguous share. No element is written twice,
/// where a vector made with a placeholder first costs another pass over
/// its memory (a few milliseconds per million corners).
pub(crate) fn fill_back_to_back<T: Send, I: Iterator<Item = T>>(
    lengths: &[usize],
    threads: usize,
    values: impl Fn(Range<usize>) -> I + Sync,
) -> Vec<Vec<T>> {
    let mut outputs: Vec<Vec<T>> = lengths.iter().map(|&n| Vec::with_capacity(n)).collect();
    let total: usize = lengths.iter().sum();
    let threads = threads.max(1);
    let share = total.div_ceil(threads).max(1);
    type Share<'a, T> = Vec<(usize, &'a mut [MaybeUninit<T>])>;
    let mut shares: Vec<Share<T>> = (0..threads).map(|_| Vec::new()).collect();
    let mut start = 0;
    for (out, &length) in outputs.iter_mut().zip(lengths) {
        let mut rest = &mut out.spare_capacity_mut()[..length];
        while !rest.is_empty() {
            let thread = (start / share).min(threads - 1);
            let room = ((thread + 1) * share).saturating_sub(start).max(1);
            let (mine, tail) = rest.split_at_mut(room.min(rest.len()));
            start += mine.len();
            shares[thread].push((start - mine.len(), mine));
            rest = tail;
        }
    }
    let fill = |share: Share<T>| {
        for (start, slots) in share {
            let (mut written, end) = (0, start + slots.len());
            for (slot, value) in slots.iter_mut().zip(values(start..end)) {
                slot.write(value);
                written += 1;
            }
            assert_eq!(written, slots.len(), "fewer values than elements");
        }
    };
    if threads == 1 {
        shares.into_iter().for_each(fill);
    } else {
        std::thread::scope(|scope| {
            for share in shares {
                let fill = &fill;
                scope.spawn(move || fill(share));
            }
        });
    }
    for (out, &length) in outputs.iter_mut().zip(lengths) {
        // SAFETY: the shares cover the first `length` elements of every
        // output exactly once, and each share's fill wrote every element
        // of it or panicked; a panic on a worker thread is raised again
        // when the scope above ends, before this line.
        unsafe { out.set_len(length) };
    }
    outputs
}

/// Groups of point indices within `distance` of one another (transitively),
/// as one group id per point (each id below `points.len()`; groups are
/// numbered in the order of their first point).
pub fn weld(points: &[Vec3], distance: f32) -> Vec<usize> {
    weld_corners(&[points], &[], distance)
        .group_of()
        .iter()
        .map(|&g| g as usize)
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
    smooth_normals_numbered(parts, options).0
}

/// What smoothing's welding found that the tangent stage needs again: the
/// exact position numbers of each part's whole triangles' corners (corners
/// with bit-identical positions, `-0.0` as `0.0`, within one weld scope
/// share a number, numbered in order of first appearance) and each
/// triangle's corner angles. Joining corners into vertices starts from
/// them instead of hashing every corner and measuring every angle again
/// ([`super::tangents::build_mesh_numbered`]).
pub struct PositionNumbers {
    /// One buffer per weld scope (the model, or each object).
    buffers: Vec<Numbered>,
    /// Per part: its buffer and the range of its corners there.
    parts: Vec<(usize, Range<usize>)>,
}

/// One weld scope's position numbers and face angles, back to back.
type Numbered = (Vec<u32>, Vec<FaceAngles>);

/// One part's share of [`PositionNumbers`].
#[derive(Clone, Copy)]
pub struct PartNumbers<'a> {
    /// The position number of each corner.
    pub(crate) positions: &'a [u32],
    /// Each triangle's corner angles.
    pub(crate) faces: &'a [FaceAngles],
}

impl PositionNumbers {
    /// Part `part`'s numbers (of its whole triangles), if any.
    pub fn part(&self, part: usize) -> Option<PartNumbers<'_>> {
        let (buffer, range) = self.parts.get(part)?;
        let (positions, faces) = &self.buffers[*buffer];
        Some(PartNumbers {
            positions: &positions[range.clone()],
            faces: &faces[range.start / 3..range.end / 3],
        })
    }
}

/// [`smooth_normals`], and the exact position numbers welding found (in
/// the object and model modes; `None` in the others, which do not weld).
pub fn smooth_normals_numbered(
    parts: &[&[Vec3]],
    options: &SmoothingOptions,
) -> (Vec<Vec<Vec3>>, Option<PositionNumbers>) {
    smooth_normals_indexed(parts, &[], options)
}

/// [`smooth_normals_numbered`], given each part's vertex indices where
/// known (one per corner; corners with equal indices in one part have
/// bit-identical positions, as the corners of one OBJ `v` line): welding
/// then looks up each vertex's position once instead of each corner's.
/// The same normals and numbers, bit for bit.
pub fn smooth_normals_indexed(
    parts: &[&[Vec3]],
    indices: &[Option<&[u32]>],
    options: &SmoothingOptions,
) -> (Vec<Vec<Vec3>>, Option<PositionNumbers>) {
    let (normals, _, numbers) = smooth_normals_all(parts, indices, options);
    (normals, numbers)
}

/// [`smooth_normals`], and the number of crease comparisons (one face
/// normal against another) it made: at most [`WORK_PER_CORNER`] + 1 per
/// corner for any input, which tests check.
pub fn smooth_normals_counted(
    parts: &[&[Vec3]],
    options: &SmoothingOptions,
) -> (Vec<Vec<Vec3>>, u64) {
    let (normals, comparisons, _) = smooth_normals_all(parts, &[], options);
    (normals, comparisons)
}

/// Normals, crease comparisons and position numbers of [`smooth_normals`].
fn smooth_normals_all(
    parts: &[&[Vec3]],
    indices: &[Option<&[u32]>],
    options: &SmoothingOptions,
) -> (Vec<Vec<Vec3>>, u64, Option<PositionNumbers>) {
    // Each part's indices of its whole triangles.
    let indices: Vec<Option<&[u32]>> = (0..parts.len())
        .map(|i| {
            let given = indices.get(i).copied().flatten()?;
            (given.len() == parts[i].len()).then(|| &given[..given.len() / 3 * 3])
        })
        .collect();
    let cos_crease = f64::from(options.crease_degrees.clamp(0.0, 180.0))
        .to_radians()
        .cos();
    let mut comparisons = 0;
    let mut numbers = None;
    let mut normals: Vec<Vec<Vec3>> = match options.mode {
        Smoothing::Face | Smoothing::File => parts
            .iter()
            .map(|p| {
                face_data(&[whole(p)])
                    .iter()
                    .flat_map(|f| [unit_or(f.normal, DVec3::Y); 3])
                    .collect()
            })
            .collect(),
        Smoothing::Object => {
            let mut buffers = Vec::with_capacity(parts.len());
            let mut ranges = Vec::with_capacity(parts.len());
            let normals = parts
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let (mut normals, work, numbered) =
                        smooth_scope(&[whole(p)], &indices[i..=i], options, cos_crease);
                    comparisons += work;
                    ranges.push((i, 0..numbered.0.len()));
                    buffers.push(numbered);
                    normals.pop().unwrap_or_default()
                })
                .collect();
            numbers = Some(PositionNumbers {
                buffers,
                parts: ranges,
            });
            normals
        }
        Smoothing::Model => {
            // One scope of every part's whole triangles, back to back.
            let scope: Vec<&[Vec3]> = parts.iter().map(|p| whole(p)).collect();
            let (normals, work, numbered) = smooth_scope(&scope, &indices, options, cos_crease);
            comparisons += work;
            let mut start = 0;
            let ranges = scope
                .iter()
                .map(|s| {
                    start += s.len();
                    (0, start - s.len()..start)
                })
                .collect();
            numbers = Some(PositionNumbers {
                buffers: vec![numbered],
                parts: ranges,
            });
            normals
        }
    };
    for (n, p) in normals.iter_mut().zip(parts) {
        n.resize(p.len(), Vec3::Y);
    }
    (normals, comparisons, numbers)
}

/// The whole triangles of a soup (trailing corners left out).
fn whole(p: &[Vec3]) -> &[Vec3] {
    &p[..p.len() / 3 * 3]
}

/// Threads worth starting for `items` units of work.
pub(crate) fn threads_for(items: usize) -> usize {
    // Below ~64k items per thread, starting threads costs more than it
    // saves. Asking the system for the number of cores reads cgroup files
    // each time, which adds up over thousands of small objects: only ask
    // when there are enough items for two threads.
    const PER_THREAD: usize = 65_536;
    if items < 2 * PER_THREAD {
        return 1;
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    cores.min(items / PER_THREAD).max(1)
}

/// One weld group's running state in [`smooth_scope`]: 32 bytes, so that
/// the per-corner passes touch one cache line per corner at most.
#[derive(Clone, Copy)]
struct Group {
    /// The weighted sum of the group's face normals, in corner order; its
    /// direction once `shared`.
    sum: DVec3,
    /// Corners in the group.
    count: u32,
    /// Every corner of the group takes the normalised sum (so far).
    shared: bool,
}

/// Smooth normals of one weld scope: `slices` hold whole triangles, taken
/// back to back (with their vertex indices where known, see
/// [`weld_corners`]); one normal per corner of each, the crease comparisons
/// made, and the corners' exact position numbers and the face data (back
/// to back).
fn smooth_scope(
    slices: &[&[Vec3]],
    indices: &[Option<&[u32]>],
    options: &SmoothingOptions,
    cos_crease: f64,
) -> (Vec<Vec<Vec3>>, u64, Numbered) {
    let faces = face_data(slices);
    let welded = weld_corners(slices, indices, options.weld_distance);
    let groups_of_corners = welded.group_of();
    let group_of = &*groups_of_corners;
    let count = group_of.len();
    let (mut groups, angles) = group_sums(&faces, group_of, welded.groups);
    if cos_crease > -1.0 {
        unshare_creased(&mut groups, &faces, group_of, cos_crease);
    }
    let mut work: u64 = groups
        .iter()
        .filter(|g| g.shared)
        .map(|g| u64::from(g.count))
        .sum();
    let unshared = smooth_unshared(&groups, group_of, &faces, cos_crease, &mut work);

    // Of the face data only the angles are needed from here on (by the
    // tangent stage): the rest is freed before the normals are written,
    // which then reuse its memory instead of faulting in fresh pages
    // (5,700 fewer page faults at 10⁶ triangles).
    drop(faces);

    // The shared normals, every corner at once (on every core); the other
    // corners hold +Y until they are filled in below.
    let lengths: Vec<usize> = slices.iter().map(|s| s.len()).collect();
    let mut normals = fill_back_to_back(&lengths, threads_for(count), |range| {
        group_of[range].iter().map(|&g| {
            let group = &groups[g as usize];
            if group.shared {
                group.sum.as_vec3()
            } else {
                Vec3::Y
            }
        })
    });
    if let Some((order, sorted)) = unshared {
        // Back to each corner's own slice.
        let first = {
            let mut first = Vec::with_capacity(slices.len() + 1);
            let mut sum = 0;
            for s in slices {
                first.push(sum);
                sum += s.len();
            }
            first.push(sum);
            first
        };
        for (&k, n) in order.iter().zip(sorted) {
            let k = k as usize;
            let s = first.partition_point(|&x| x <= k) - 1;
            normals[s][k - first[s]] = n;
        }
    }
    drop(groups_of_corners);
    (normals, work, (welded.position_of, angles))
}

/// Every group's sum, adding its corners in corner order: the order in
/// which the direct comparison adds them, so the same bits. Small groups
/// take their normalised sum in every corner (`shared`) where it has a
/// direction. Also returns the face angles the tangent stage needs,
/// copied out on the way, so that the rest of the face data can be freed
/// early.
fn group_sums(
    faces: &[Face],
    group_of: &[u32],
    group_count: usize,
) -> (Vec<Group>, Vec<FaceAngles>) {
    let mut groups = vec![
        Group {
            sum: DVec3::ZERO,
            count: 0,
            shared: false,
        };
        group_count
    ];
    let mut angles = Vec::with_capacity(faces.len());
    for (face, corners) in faces.iter().zip(group_of.chunks_exact(3)) {
        angles.push(FaceAngles::of(face));
        for (j, &g) in corners.iter().enumerate() {
            let group = &mut groups[g as usize];
            group.sum += face.contribution(j);
            group.count += 1;
        }
    }
    for group in &mut groups {
        if group.count as usize <= DIRECT_GROUP {
            if let Some(direction) = group.sum.try_normalize() {
                group.sum = direction;
                group.shared = true;
            }
        }
    }
    (groups, angles)
}

/// Unshares the groups some face of which is not shown to be within the
/// crease angle of every other. Where every pair of a group's faces is
/// within the crease angle, each corner's sum of the faces within the
/// crease angle of its own is the whole sum. Shown with a margin: each
/// face lies within half the angle (less 1e-9 radians) of the sum's
/// direction. At 180 degrees (`cos_crease` -1) every pair is within, and
/// this is not called.
fn unshare_creased(groups: &mut [Group], faces: &[Face], group_of: &[u32], cos_crease: f64) {
    let crease = cos_crease.clamp(-1.0, 1.0).acos();
    let cos_half = ((crease - 1e-9) / 2.0).cos();
    for (face, corners) in faces.iter().zip(group_of.chunks_exact(3)) {
        // A degenerate face adds nothing to any sum and, in its own
        // corners, takes the whole sum (its fallback) either way.
        if face.normal == DVec3::ZERO {
            continue;
        }
        for &g in corners {
            let group = &mut groups[g as usize];
            if group.shared && face.normal.dot(group.sum) < cos_half {
                group.shared = false;
            }
        }
    }
}

/// The normals of the corners of the groups that are not shared: the
/// corners (ascending, as contiguous runs, a counting sort by group) and
/// their normals, compared corner by corner; `None` when every group is
/// shared. Adds the crease comparisons made to `work`.
fn smooth_unshared(
    groups: &[Group],
    group_of: &[u32],
    faces: &[Face],
    cos_crease: f64,
    work: &mut u64,
) -> Option<(Vec<u32>, Vec<Vec3>)> {
    let mut run_of = vec![u32::MAX; groups.len()];
    let mut starts = vec![0u32];
    for (g, group) in groups.iter().enumerate() {
        if !group.shared {
            run_of[g] = starts.len() as u32 - 1;
            starts.push(starts[starts.len() - 1] + group.count);
        }
    }
    let runs = starts.len() - 1;
    if runs == 0 {
        return None;
    }
    let mut order = vec![0u32; starts[runs] as usize];
    let mut next = starts.clone();
    for (k, &g) in group_of.iter().enumerate() {
        let run = run_of[g as usize];
        if run != u32::MAX {
            order[next[run as usize] as usize] = k as u32;
            next[run as usize] += 1;
        }
    }
    let sorted = smooth_runs(&starts, &order, faces, cos_crease, work);
    Some((order, sorted))
}

/// The normals of the runs of corners `order[starts[r]..starts[r + 1]]`
/// (one weld group each), in `order`'s order, by [`smooth_group`]; the
/// runs are split between threads at run boundaries. Adds the crease
/// comparisons made to `work`.
fn smooth_runs(
    starts: &[u32],
    order: &[u32],
    faces: &[Face],
    cos_crease: f64,
    work: &mut u64,
) -> Vec<Vec3> {
    let count = order.len();
    let runs = starts.len() - 1;
    let mut sorted = vec![Vec3::Y; count];
    let threads = threads_for(count);
    let mut bounds = vec![0usize];
    for t in 1..threads {
        // The first run starting at or after an even share of corners.
        let target = (count * t / threads) as u32;
        let run = starts.partition_point(|&s| s < target).min(runs);
        if run > *bounds.last().unwrap_or(&0) {
            bounds.push(run);
        }
    }
    if *bounds.last().unwrap_or(&0) < runs {
        bounds.push(runs);
    }
    *work += std::thread::scope(|scope| {
        let mut rest = sorted.as_mut_slice();
        let mut handles = Vec::new();
        for pair in bounds.windows(2) {
            let (first, last) = (pair[0], pair[1]);
            let corners = (starts[last] - starts[first]) as usize;
            let (mine, next) = rest.split_at_mut(corners);
            rest = next;
            handles.push(scope.spawn(move || {
                let mut work = 0;
                let base = starts[first] as usize;
                let mut scratch = Scratch::default();
                for run in first..last {
                    let (a, b) = (starts[run] as usize, starts[run + 1] as usize);
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
    sorted
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
    faces: &[Face],
    cos_crease: f64,
    out: &mut [Vec3],
    scratch: &mut Scratch,
) -> u64 {
    let contributions = &mut scratch.contributions;
    contributions.clear();
    contributions.extend(run.iter().map(|&k| {
        let face = &faces[k as usize / 3];
        (face.normal, face.contribution(k as usize % 3))
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
    let faces: Vec<Vec<Face>> = parts.iter().map(|p| face_data(&[*p])).collect();
    let cos_crease = f64::from(options.crease_degrees.clamp(0.0, 180.0))
        .to_radians()
        .cos();
    let distance = f64::from(options.weld_distance);
    let mut out = Vec::new();
    for (p, part) in parts.iter().enumerate() {
        let mut normals = Vec::with_capacity(part.len());
        let whole = part.len() / 3 * 3;
        for (c, position) in part.iter().enumerate() {
            if c >= whole {
                normals.push(Vec3::Y);
                continue;
            }
            let own = faces[p][c / 3].normal;
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
                for (d, x) in other[..other.len() / 3 * 3].iter().enumerate() {
                    if x.as_dvec3().distance(position.as_dvec3()) <= distance {
                        let face = faces[q][d / 3];
                        total += face.contribution(d % 3);
                        if own.dot(face.normal) >= cos_crease - 1e-12 {
                            sum += face.contribution(d % 3);
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

    /// Every element of every output is the value of its place in the
    /// back-to-back sequence, whatever the lengths (empty ones among them)
    /// and however many threads share the work; too few values panic
    /// rather than leave an element unwritten.
    #[test]
    fn back_to_back_filling_writes_every_element_once() {
        let layouts: [&[usize]; 5] = [&[], &[0], &[7], &[0, 5, 0, 17, 3, 0], &[1, 1, 1, 1, 1]];
        for lengths in layouts {
            for threads in 0..6 {
                let outputs =
                    fill_back_to_back(lengths, threads, |range| range.map(|i| (i as u64) * 7 + 1));
                let mut start = 0;
                for (out, &length) in outputs.iter().zip(lengths) {
                    let expected: Vec<u64> =
                        (start..start + length).map(|i| i as u64 * 7 + 1).collect();
                    assert_eq!(*out, expected, "{lengths:?} on {threads} threads");
                    start += length;
                }
                assert_eq!(outputs.len(), lengths.len());
            }
        }
        let short = std::panic::catch_unwind(|| {
            fill_back_to_back(&[4, 4], 2, |range| range.skip(1).map(|i| i.to_string()))
        });
        assert!(short.is_err());
    }

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

    /// `corner_angle` is glam's `angle_between`, bit for bit: on random
    /// vectors of every scale and sign, on (anti)parallel and orthogonal
    /// pairs, whose cosines sit at the polynomial's ends and at its sign
    /// change, and on zero, tiny, huge and non-finite vectors (NaN where
    /// glam gives NaN).
    #[test]
    fn corner_angle_is_glams_angle_between_bit_for_bit() {
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        let mut random = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Any f32 bit pattern, finite or not, half the time; a value
            // of moderate size the other half.
            if x & 1 == 0 {
                f32::from_bits((x >> 32) as u32)
            } else {
                ((x >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 8.0
            }
        };
        let mut pairs: Vec<(Vec3, Vec3)> = (0..200_000)
            .map(|_| {
                let mut v = || Vec3::new(random(), random(), random());
                (v(), v())
            })
            .collect();
        let special = [
            Vec3::ZERO,
            Vec3::X,
            -Vec3::X,
            Vec3::Y,
            Vec3::new(1.0, 1e-7, 0.0),
            Vec3::new(-1.0, 1e-7, 0.0),
            Vec3::new(1e-30, 0.0, 0.0),
            Vec3::new(1e30, 1e30, 0.0),
            Vec3::new(f32::MAX, 0.0, 0.0),
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(f32::NAN, 1.0, 0.0),
            Vec3::new(-0.0, 0.0, -0.0),
        ];
        for &u in &special {
            for &v in &special {
                pairs.push((u, v));
            }
        }
        for (u, v) in pairs {
            let (ours, glams) = (corner_angle(u, v), u.angle_between(v));
            assert!(
                ours.to_bits() == glams.to_bits() || ours.is_nan() && glams.is_nan(),
                "angle between {u} and {v}: {ours} against glam's {glams}"
            );
        }
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

    /// Adversarial soups against the direct oracle, bit for bit: many
    /// corners sharing a position (points of a small lattice, each copy
    /// jittered well within the weld distance), faces repeated and
    /// repeated reversed, degenerate faces (a point used twice), and
    /// hinges folded to within rounding of the crease angle, where the
    /// one-sum shortcut must give way to the corner-by-corner comparison.
    /// Groups stay within `DIRECT_GROUP` corners and the points' clusters
    /// far apart, so the oracle's sums are the same sums in the same order.
    #[test]
    fn adversarial_soups_match_the_oracle_bit_for_bit() {
        // A small deterministic generator (xorshift), so failures reproduce.
        let state = std::cell::Cell::new(0x2545_f491_4f6c_dd1d_u64);
        let next = |n: usize| {
            let mut x = state.get();
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            state.set(x);
            (x >> 33) as usize % n
        };
        let creases = [0.0, 30.0, 45.0, 60.0, 89.99, 90.0, 90.01, 135.0, 180.0];
        for round in 0..60 {
            let weld_distance = if round % 2 == 0 { 0.0 } else { 1e-4 };
            let pool: Vec<Vec3> = (0..4 + round % 7)
                .map(|_| Vec3::new(next(3) as f32, next(3) as f32, next(2) as f32 * 0.5))
                .collect();
            let jitter = |p: Vec3| {
                if weld_distance == 0.0 {
                    p
                } else {
                    p + Vec3::new(next(9) as f32, next(9) as f32, next(9) as f32) * 2e-6
                }
            };
            let mut parts = [Vec::new(), Vec::new()];
            for i in 0..8 {
                let t = [0, 1, 2].map(|_| pool[next(pool.len())]);
                let part = &mut parts[i % 2];
                part.extend(t.map(jitter));
                match next(4) {
                    0 => part.extend(t.map(jitter)),
                    1 => part.extend([t[0], t[2], t[1]].map(jitter)),
                    _ => {}
                }
            }
            let parts: Vec<&[Vec3]> = parts.iter().map(|p| p.as_slice()).collect();
            for mode in [Smoothing::Object, Smoothing::Model] {
                for crease_degrees in creases {
                    let o = SmoothingOptions {
                        mode,
                        crease_degrees,
                        weld_distance,
                    };
                    let fast = smooth_normals(&parts, &o);
                    let slow = naive_normals(&parts, &o);
                    assert_eq!(
                        fast, slow,
                        "round {round}, {mode:?}, crease {crease_degrees}"
                    );
                }
            }
        }
        // Hinges: two triangles on a common edge, folded by the crease
        // angle and by a little less and more.
        for crease_degrees in [1.0f32, 30.0, 60.0, 90.0, 120.0, 179.0] {
            for offset in [-1e-6f32, -1e-7, 0.0, 1e-7, 1e-6] {
                let fold = crease_degrees.to_radians() + offset;
                let hinge = [
                    Vec3::ZERO,
                    Vec3::X,
                    Vec3::Y,
                    Vec3::X,
                    Vec3::ZERO,
                    Vec3::new(0.0, -fold.cos(), fold.sin()),
                ];
                let o = options(Smoothing::Model, crease_degrees);
                assert_eq!(
                    smooth_normals(&[&hinge], &o),
                    naive_normals(&[&hinge], &o),
                    "crease {crease_degrees}, fold off by {offset}"
                );
            }
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

    /// Welding from vertex indices gives the same normals and position
    /// numbers, bit for bit, as hashing every corner: random soups whose
    /// vertices repeat positions under other indices (an object's copy of
    /// another's boundary, `-0.0` against `0.0`), positions within the
    /// weld distance, trailing corners, parts with and without indices,
    /// in the object and model modes.
    #[test]
    fn indexed_welding_matches_hashing_bit_for_bit() {
        let mut next = crate::mesh::tests::uniform_stream(0x9e37_79b9_7f4a_7c15);
        for round in 0..80 {
            let mut pick = |n: usize| (next() * n as f32) as usize % n;
            let points: Vec<Vec3> = (0..3 + round % 9)
                .map(|_| Vec3::new(pick(3) as f32, pick(3) as f32, pick(2) as f32 * 0.5))
                .collect();
            // Vertices: the points, some twice, some negated zeros, some
            // moved within the weld distance.
            let vertices: Vec<Vec3> = (0..2 * points.len())
                .map(|i| {
                    let p = points[i % points.len()];
                    match pick(4) {
                        0 => Vec3::select(p.cmpeq(Vec3::ZERO), Vec3::splat(-0.0), p),
                        1 => Vec3::new(p.x + 2e-6 * pick(3) as f32, p.y, p.z),
                        _ => p,
                    }
                })
                .collect();
            let mut parts: Vec<(Vec<Vec3>, Vec<u32>)> = (0..1 + round % 3)
                .map(|_| {
                    let corners = 3 * (1 + pick(12)) + pick(3);
                    let indices: Vec<u32> =
                        (0..corners).map(|_| pick(vertices.len()) as u32).collect();
                    let positions = indices.iter().map(|&i| vertices[i as usize]).collect();
                    (positions, indices)
                })
                .collect();
            if round % 5 == 0 {
                // Negated zeros under one index are one position either way.
                for (positions, _) in &mut parts {
                    for p in positions.iter_mut() {
                        *p = Vec3::select(p.cmpeq(Vec3::ZERO), Vec3::ZERO, *p);
                    }
                }
            }
            let positions: Vec<&[Vec3]> = parts.iter().map(|(p, _)| p.as_slice()).collect();
            let indices: Vec<Option<&[u32]>> = parts
                .iter()
                .enumerate()
                .map(|(i, (_, x))| ((i + round) % 4 != 0).then_some(x.as_slice()))
                .collect();
            // Indices numbered within a larger model (far beyond the
            // corners' count) are hashed instead, with the same results.
            let offset: Vec<Vec<u32>> = parts
                .iter()
                .map(|(_, x)| x.iter().map(|&i| i + 1_000_000).collect())
                .collect();
            let sparse: Vec<Option<&[u32]>> = offset.iter().map(|x| Some(&x[..])).collect();
            for mode in [Smoothing::Object, Smoothing::Model] {
                for weld_distance in [0.0, 1e-4] {
                    let options = SmoothingOptions {
                        mode,
                        crease_degrees: [30.0, 60.0, 180.0][round % 3],
                        weld_distance,
                    };
                    let (hashed, hashed_numbers) = smooth_normals_numbered(&positions, &options);
                    let (indexed, indexed_numbers) =
                        smooth_normals_indexed(&positions, &indices, &options);
                    let bits = |n: &[Vec<Vec3>]| -> Vec<Vec<[u32; 3]>> {
                        n.iter()
                            .map(|p| p.iter().map(|v| v.to_array().map(f32::to_bits)).collect())
                            .collect()
                    };
                    assert_eq!(bits(&hashed), bits(&indexed), "round {round}, {mode:?}");
                    let (far, _) = smooth_normals_indexed(&positions, &sparse, &options);
                    assert_eq!(bits(&hashed), bits(&far), "round {round}, {mode:?}");
                    let (a, b) = (hashed_numbers.unwrap(), indexed_numbers.unwrap());
                    for part in 0..parts.len() {
                        let (a, b) = (a.part(part).unwrap(), b.part(part).unwrap());
                        assert_eq!(a.positions, b.positions, "round {round}, {mode:?}");
                    }
                }
            }
        }
    }
}
