//! What the OBJ loader makes of a model file, for `aerial mesh`: counts of
//! objects, triangles and vertices, how many boundary points were welded
//! across objects, triangles of zero area and of zero UV area, triangles
//! without texture coordinates, mirrored triangles, non-finite
//! attributes, the worst tangent-frame error, and the time of each stage.

use super::heap::HeapReuse;
use super::obj::{
    load_obj, model_frames_numbered, model_normals_numbered, AssetWarning, ModelOptions, ObjError,
};
use super::smoothing::weld;
use super::tangents::{is_collapsed, max_orthonormality_error};
use std::path::Path;
use std::time::Instant;

/// Seconds per stage.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct StageSeconds {
    /// Reading and parsing the OBJ and its MTL.
    pub load: f64,
    /// Welding and normal generation.
    pub smoothing: f64,
    /// Tangent frames and splitting vertices at seams.
    pub tangents: f64,
}

/// The report of one model.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MeshReport {
    pub file: String,
    /// `face`, `object`, `model` or `file`.
    pub smoothing: &'static str,
    pub objects: usize,
    /// Triangles in the file (after splitting polygons).
    pub triangles: usize,
    /// Triangle corners as read (three per triangle).
    pub corners: usize,
    /// Vertices after joining equal corners and splitting at UV seams and
    /// handedness changes.
    pub vertices: usize,
    /// Weld points shared by corners of more than one object: the
    /// boundaries `model` smoothing joins.
    pub welded_boundary_points: usize,
    /// Triangles of zero area, collapsed to a line or a point (left out).
    pub collapsed_triangles: usize,
    /// Triangles kept (not collapsed) with texture coordinates whose UV
    /// area is zero: their UVs give no tangent direction, so their frames
    /// come from the normal alone.
    pub zero_uv_area_triangles: usize,
    /// Triangles of objects without texture coordinates (any face of the
    /// file without them leaves them all out). Not a defect: their frames
    /// come from the normal, as nothing needs UVs there.
    pub triangles_without_uvs: usize,
    /// Triangles whose UVs are mirrored (handedness −1).
    pub mirrored_triangles: usize,
    /// Vertex attribute values that are NaN or infinite (0 by design).
    pub non_finite_attributes: usize,
    /// Largest | |N| − 1 |, | |T| − 1 |, |N·T| or | |w| − 1 | over the vertices.
    pub max_orthonormality_error: f32,
    pub seconds: StageSeconds,
    /// Processor time per stage, over every thread (a stage split over
    /// the cores takes more of it than of the wall clock; waiting for a
    /// core on a busy machine takes none).
    pub cpu_seconds: StageSeconds,
    /// Problems with the MTL libraries and material references that
    /// loading worked around (textures are never opened here).
    pub warnings: Vec<String>,
    /// The same, for `--strict`.
    #[serde(skip)]
    pub asset_warnings: Vec<AssetWarning>,
    /// The files the model was read from (the OBJ, its MTL libraries and
    /// their textures; see [`crate::mesh::obj::ObjModel::files`]). Not
    /// part of the JSON report.
    #[serde(skip)]
    pub files: Vec<std::path::PathBuf>,
}

/// Loads `path` as the renderer would with `options` and reports on it.
pub fn inspect(path: &Path, options: &ModelOptions) -> Result<MeshReport, ObjError> {
    let file = path.display().to_string();
    // Each stage reuses the memory the one before freed (see `HeapReuse`).
    let _reuse = HeapReuse::enter();
    let (start, cpu_start) = (Instant::now(), process_cpu_seconds());
    let model = load_obj(path)?;
    let (load, cpu_load) = (start.elapsed().as_secs_f64(), process_cpu_seconds());

    let start = Instant::now();
    let smoothed = model_normals_numbered(&model, options, &file)?;
    let mode = smoothed.mode;
    let (smoothing, cpu_smoothing) = (start.elapsed().as_secs_f64(), process_cpu_seconds());

    let start = Instant::now();
    let numbers = smoothed.positions;
    let meshes =
        model_frames_numbered(&model, smoothed.normals, numbers.as_ref(), options.tangents);
    // Smoothing's position numbers and face data are no longer needed:
    // freed before the boundary count below allocates its own arrays.
    drop(numbers);
    let (tangents, cpu_tangents) = (start.elapsed().as_secs_f64(), process_cpu_seconds());

    // Boundary points: weld groups holding corners of two or more parts.
    let points: Vec<glam::Vec3> = model
        .parts
        .iter()
        .flat_map(|p| p.positions.iter().copied())
        .collect();
    let part_of: Vec<usize> = model
        .parts
        .iter()
        .enumerate()
        .flat_map(|(i, p)| std::iter::repeat_n(i, p.positions.len()))
        .collect();
    let groups = weld(&points, options.weld_tolerance * model.diagonal());
    let mut first_part = vec![usize::MAX; points.len()];
    let mut shared = vec![false; points.len()];
    for (point, &group) in groups.iter().enumerate() {
        let part = part_of[point];
        if first_part[group] == usize::MAX {
            first_part[group] = part;
        } else if first_part[group] != part {
            shared[group] = true;
        }
    }

    let mut report = MeshReport {
        file,
        smoothing: mode.name(),
        objects: model.parts.len(),
        triangles: model.parts.iter().map(|p| p.triangle_count()).sum(),
        corners: points.len(),
        vertices: 0,
        welded_boundary_points: shared.iter().filter(|&&s| s).count(),
        collapsed_triangles: 0,
        zero_uv_area_triangles: 0,
        triangles_without_uvs: 0,
        mirrored_triangles: 0,
        non_finite_attributes: 0,
        max_orthonormality_error: 0.0,
        seconds: StageSeconds {
            load,
            smoothing,
            tangents,
        },
        cpu_seconds: StageSeconds {
            load: cpu_load - cpu_start,
            smoothing: cpu_smoothing - cpu_load,
            tangents: cpu_tangents - cpu_smoothing,
        },
        warnings: model.warnings.iter().map(|w| w.to_string()).collect(),
        asset_warnings: model.warnings.clone(),
        files: model.files.clone(),
    };
    for (mesh, stats) in &meshes {
        report.vertices += mesh.vertices.len();
        report.collapsed_triangles += stats.collapsed;
        report.mirrored_triangles += stats.mirrored;
        report.non_finite_attributes += mesh
            .vertices
            .iter()
            .map(|v| {
                v.position
                    .iter()
                    .chain(&v.normal)
                    .chain(&v.tangent)
                    .chain(&v.uv)
                    .filter(|x| !x.is_finite())
                    .count()
            })
            .sum::<usize>();
        report.max_orthonormality_error = report
            .max_orthonormality_error
            .max(max_orthonormality_error(mesh));
    }
    for part in &model.parts {
        let kept = part
            .positions
            .chunks_exact(3)
            .map(|t| !is_collapsed(t[0], t[1], t[2]));
        match &part.uvs {
            None => report.triangles_without_uvs += kept.filter(|&k| k).count(),
            Some(uvs) => {
                report.zero_uv_area_triangles += kept
                    .zip(uvs.chunks_exact(3))
                    .filter(|&(k, uv)| k && zero_uv_area(uv[0], uv[1], uv[2]))
                    .count()
            }
        }
    }
    Ok(report)
}

/// Whether a triangle's texture coordinates span no area (to the same
/// tolerance the tangent frames use): they give no tangent direction.
fn zero_uv_area(a: glam::Vec2, b: glam::Vec2, c: glam::Vec2) -> bool {
    let (d1, d2) = ((b - a).as_dvec2(), (c - a).as_dvec2());
    let det = d1.perp_dot(d2);
    let scale = d1.length_squared().max(d2.length_squared());
    !(det.is_finite() && det.abs() > 1e-12 * scale)
}

/// Processor time of this process so far, over every thread: on a shared
/// machine it tells work apart from time spent waiting for a core.
pub fn process_cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec; the clock id is a constant
    // every Linux supports.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}
