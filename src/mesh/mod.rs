//! Triangle meshes tessellated from analytic parametric surfaces or loaded
//! from OBJ models (`obj`, with `smoothing` and `tangents`).
//!
//! A [`ParametricSurface`] supplies `r(u, v)` and its exact derivatives;
//! [`tessellate`] samples it on a regular grid and emits GPU-ready
//! [`Vertex`] data with analytic normals and tangents, so shading quality
//! does not depend on how finely the surface is cut.

pub mod heap;
pub mod height;
pub mod inspect;
mod join;
pub mod mikktspace;
pub mod obj;
mod shapes;
pub mod smoothing;
mod surface;
pub mod tangents;
mod weld;

pub use shapes::{CylinderSurface, FlagSurface, PlaneSurface, SphereSurface, TorusSurface};
pub use surface::{derived_normal, derived_tangent, ParametricSurface};

use glam::{DVec3, Vec3};

/// Largest number of segments [`tessellate`] accepts in either direction.
///
/// 4096 x 4096 cells is already ~16.8 M vertices (~800 MB of vertex data);
/// the cap keeps vertex indices well inside `u32` and bounds memory.
pub const MAX_SEGMENTS: u32 = 4096;

/// One vertex as the renderer uploads it (48 bytes, no padding).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct Vertex {
    /// Object-space position.
    pub position: [f32; 3],
    /// Object-space unit normal.
    pub normal: [f32; 3],
    /// `xyz`: unit tangent along `+u`, orthogonal to the normal. `w`: the
    /// handedness, `+1` or `-1`, such that `cross(normal, tangent) * w`
    /// follows `+v`.
    pub tangent: [f32; 4],
    /// Texture coordinates, equal to the surface parameters `(u, v)`.
    pub uv: [f32; 2],
}

/// An indexed triangle list; triangles are counter-clockwise when seen from
/// the side their normals point to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex data.
    pub vertices: Vec<Vertex>,
    /// Three indices into `vertices` per triangle.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// A sphere `(centre, radius)` enclosing every vertex.
    ///
    /// The centre is the middle of the axis-aligned bounding box, which is
    /// exact for the symmetric shapes this crate makes and never more than
    /// `sqrt(3)/2` times the optimum radius otherwise. An empty mesh gives
    /// `(0, 0)`.
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let Some((min, max)) = self.bounding_box() else {
            return (Vec3::ZERO, 0.0);
        };
        let centre = (min + max) * 0.5;
        let radius = self
            .vertices
            .iter()
            .map(|v| Vec3::from(v.position).distance(centre))
            .fold(0.0_f32, f32::max);
        (centre, radius)
    }

    /// The axis-aligned box `(min, max)` around every vertex; `None`
    /// without vertices.
    pub fn bounding_box(&self) -> Option<(Vec3, Vec3)> {
        let mut points = self.vertices.iter().map(|v| Vec3::from(v.position));
        let first = points.next()?;
        Some(points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }

    /// Number of triangles (`indices.len() / 3`).
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// Samples `surface` on a `(u_segments + 1) x (v_segments + 1)` grid and
/// joins the samples into triangles.
///
/// Segment counts are clamped to `1..=MAX_SEGMENTS` so that any input gives a
/// valid mesh. Vertex `(i, j)` (the `i`-th along `u`, `j`-th along `v`) is at
/// index `j * (u_segments + 1) + i`. Seams are not welded: the first and last
/// columns are separate vertices with `u = 0` and `u = 1`, which texturing
/// needs. Triangles that collapse to a point or a line (the fan around a
/// sphere pole) are left out, because they add nothing but rasterizer work.
pub fn tessellate(surface: &dyn ParametricSurface, u_segments: u32, v_segments: u32) -> Mesh {
    let us = u_segments.clamp(1, MAX_SEGMENTS);
    let vs = v_segments.clamp(1, MAX_SEGMENTS);
    let cols = us + 1;
    let count = cols as usize * (vs as usize + 1);

    // Positions are kept in f64 for the degeneracy test below, so that it
    // sees exactly coincident pole samples rather than f32 round-off.
    let mut exact = Vec::with_capacity(count);
    let mut vertices = Vec::with_capacity(count);
    for j in 0..=vs {
        let v = f64::from(j) / f64::from(vs);
        for i in 0..=us {
            let u = f64::from(i) / f64::from(us);
            let position = surface.position(u, v);
            let (normal, tangent) = frame(surface, u, v);
            exact.push(position);
            vertices.push(Vertex {
                position: position.as_vec3().to_array(),
                normal: normal.as_vec3().to_array(),
                tangent: tangent.as_vec4().to_array(),
                uv: [u as f32, v as f32],
            });
        }
    }

    let mut indices = Vec::with_capacity(us as usize * vs as usize * 6);
    for j in 0..vs {
        for i in 0..us {
            let i00 = j * cols + i;
            let i10 = i00 + 1;
            let i01 = i00 + cols;
            let i11 = i01 + 1;
            // (u, v) -> (u+1, v) -> (u+1, v+1) turns from du towards dv, so
            // its geometric normal is du x dv: counter-clockwise seen from
            // the front. Same for the second half of the cell.
            for tri in [[i00, i10, i11], [i00, i11, i01]] {
                if !is_degenerate(&exact, tri) {
                    indices.extend_from_slice(&tri);
                }
            }
        }
    }

    Mesh { vertices, indices }
}

/// Unit normal and tangent (with handedness in `w`) at `(u, v)`, never NaN
/// and always orthonormal, whatever the surface returns.
fn frame(surface: &dyn ParametricSurface, u: f64, v: f64) -> (DVec3, glam::DVec4) {
    let normal = surface::unit(surface.normal(u, v)).unwrap_or(DVec3::Y);
    // Gram-Schmidt: for the analytic frame du is already orthogonal to
    // du x dv, but a surface may override `normal`, and the shader's TBN
    // matrix assumes an orthonormal basis.
    let raw = surface.tangent(u, v);
    let tangent = surface::unit(raw - normal * normal.dot(raw))
        .unwrap_or_else(|| normal.any_orthonormal_vector());
    let handedness = if normal.cross(tangent).dot(surface.dv(u, v)) < 0.0 {
        -1.0
    } else {
        1.0
    };
    (normal, tangent.extend(handedness))
}

/// True when the triangle has (almost) no area relative to its size.
fn is_degenerate(points: &[DVec3], tri: [u32; 3]) -> bool {
    let [a, b, c] = tri.map(|i| points[i as usize]);
    let longest = (b - a)
        .length_squared()
        .max((c - a).length_squared())
        .max((c - b).length_squared());
    let twice_area = (b - a).cross(c - a).length();
    // The ratio is ~sin(smallest angle); 1e-10 only catches truly collapsed
    // triangles, far below any thin but real sliver a 4096-segment grid
    // produces.
    twice_area.is_nan() || twice_area <= 1e-10 * longest
}

#[cfg(test)]
mod tests;
