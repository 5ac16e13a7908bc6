//! `tessellation = "auto"`: each parametric object's grid chosen so that
//! its flat triangles stay within `[output] max_pixel_error` pixels of the
//! exact surface, as seen from the scene's camera at its output size.
//!
//! The rule. Linear interpolation of `r(u, v)` over a parameter cell of
//! `du x dv` is at most `(1/8)(M_uu du^2 + 2 M_uv du dv + M_vv dv^2)` away
//! from the surface (to second order, the largest gap being at the
//! midpoint of the cell's diagonal), where `M_xy` bound the second
//! derivatives' components along the surface normal: the coefficients
//! `L`, `M`, `N` of the second fundamental form, that is the normal
//! curvatures times the squared parameter speeds. The tangential
//! components only slide a point within the surface and leave the
//! silhouette and depth alone. With `2 du dv <= du^2 + dv^2` that is at most `e` when
//! `du = sqrt(4e / (M_uu + M_uv))` and `dv = sqrt(4e / (M_vv + M_uv))`.
//! `e` is the world-space length that projects to `max_pixel_error` pixels
//! at the nearest point of the object's bounding sphere (never nearer than
//! the near plane), divided by the transform's largest scale to bring it
//! into object space. The counts `ceil(1 / du)`, `ceil(1 / dv)` are rounded
//! *up* to a short ladder (3, 4, 6, 8, 12, 16, ...), which keeps the bound
//! and lets objects at similar distances share one mesh
//! (`Scene::mesh_sources`).
//!
//! The bounds `M_xy` are estimated once per distinct shape from the
//! surface's own analytic first derivatives, differenced on a fine sample
//! grid and projected on its normal there, with a safety margin for maxima
//! between samples: one mechanism for
//! every [`ParametricSurface`], no per-shape formula. A plane's are zero, so
//! it gets the minimum grid.
//!
//! The counts are computed when a mesh is asked for ([`Scene::object_mesh`],
//! [`Scene::mesh_sources`]), from the scene as it then is, so a knob or a
//! command-line size applied after loading is always taken into account.
//! Objects outside the view are not culled to the minimum: a viewer that
//! turns towards them keeps the meshes it built.

use glam::DVec3;

use super::{Object, Scene, Shape, MIN_SEGMENTS};
use crate::mesh::{ParametricSurface, MAX_SEGMENTS};

/// Default `[output] max_pixel_error`, in pixels.
pub const DEFAULT_MAX_PIXEL_ERROR: f32 = 0.5;

/// Sample intervals per parameter direction of the grid the second
/// derivatives are estimated on.
const SAMPLES: u32 = 64;

/// Parameter step of the central differences of the first derivatives:
/// small against a sample interval, large against f64 round-off.
const STEP: f64 = 1e-5;

/// Factor on the sampled maxima of the second derivatives. Between two
/// samples `1/64` apart a smooth second derivative can rise a little above
/// the larger sample (by `1 - cos(pi/64)` of it for a circle); 1.25 covers
/// that with room for the flag's faster waves.
const MARGIN: f64 = 1.25;

/// What choosing an object's grid needs to know of its shape, in object
/// space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceBounds {
    /// Bound on `|d2r/du2 . n|` (`L`).
    pub m_uu: f64,
    /// Bound on `|d2r/du dv . n|` (`M`).
    pub m_uv: f64,
    /// Bound on `|d2r/dv2 . n|` (`N`).
    pub m_vv: f64,
    /// Centre of a sphere enclosing the surface.
    pub centre: DVec3,
    /// Its radius.
    pub radius: f64,
}

/// Derivative of `f` along one parameter at `x`, by central differences
/// kept inside `[0, 1]` (one-sided at the edges).
fn difference(f: impl Fn(f64) -> DVec3, x: f64) -> DVec3 {
    let (a, b) = ((x - STEP).max(0.0), (x + STEP).min(1.0));
    (f(b) - f(a)) / (b - a)
}

/// The second-derivative bounds and bounding sphere of `surface`, from a
/// `(SAMPLES + 1)^2` grid of samples.
pub fn surface_bounds(surface: &dyn ParametricSurface) -> SurfaceBounds {
    let (mut m_uu, mut m_uv, mut m_vv) = (0.0f64, 0.0f64, 0.0f64);
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut points = Vec::with_capacity(((SAMPLES + 1) * (SAMPLES + 1)) as usize);
    for j in 0..=SAMPLES {
        let v = f64::from(j) / f64::from(SAMPLES);
        for i in 0..=SAMPLES {
            let u = f64::from(i) / f64::from(SAMPLES);
            // Only the second derivatives' components along the normal
            // (the second fundamental form) move a flat triangle off the
            // surface; the tangential ones only slide points within it.
            let n = surface.normal(u, v);
            let normal_part = |d: DVec3| d.dot(n).abs();
            let uu = normal_part(difference(|x| surface.du(x, v), u));
            let vv = normal_part(difference(|y| surface.dv(u, y), v));
            // The mixed derivative two ways: equal for a smooth surface,
            // but each difference has its own round-off.
            let uv = normal_part(difference(|y| surface.du(u, y), v))
                .max(normal_part(difference(|x| surface.dv(x, v), u)));
            // `max` would drop a NaN; a non-finite surface must not look flat.
            for (m, x) in [(&mut m_uu, uu), (&mut m_uv, uv), (&mut m_vv, vv)] {
                *m = if x.is_nan() { f64::INFINITY } else { m.max(x) };
            }
            let p = surface.position(u, v);
            (lo, hi) = (lo.min(p), hi.max(p));
            points.push(p);
        }
    }
    let centre = (lo + hi) * 0.5;
    let farthest = points
        .iter()
        .map(|p| p.distance(centre))
        .fold(0.0, f64::max);
    let (m_uu, m_uv, m_vv) = (MARGIN * m_uu, MARGIN * m_uv, MARGIN * m_vv);
    // Between samples the surface leaves their hull by at most the chord
    // error of a sample cell.
    let cell = 1.0 / f64::from(SAMPLES);
    let between = (m_uu + 2.0 * m_uv + m_vv) * cell * cell / 8.0;
    SurfaceBounds {
        m_uu,
        m_uv,
        m_vv,
        centre,
        radius: farthest + between,
    }
}

/// The smallest count of the ladder `3, 4, 6, 8, 12, 16, 24, ...` (`3 * 2^k`
/// and `4 * 2^k`) that is at least `n`, within `MIN_SEGMENTS..=MAX_SEGMENTS`.
pub fn ladder_up(n: f64) -> u32 {
    // NaN asks for the maximum, the safe side.
    let n = if n.is_nan() { f64::INFINITY } else { n };
    let mut step = MIN_SEGMENTS;
    while step < MAX_SEGMENTS && f64::from(step) < n {
        // 3 -> 4 -> 6 -> 8 -> 12: alternately times 4/3 and 3/2.
        step = if step.is_power_of_two() {
            step / 2 * 3
        } else {
            step / 3 * 4
        };
    }
    step.min(MAX_SEGMENTS)
}

/// The segments `(1 / du, 1 / dv)` the bound asks for to keep the chord
/// error of `bounds`' surface within `allowed` (object-space length),
/// before rounding: 0 along a flat direction, infinite or NaN when the
/// bounds or `allowed` are not usable numbers.
pub fn required_segments(bounds: &SurfaceBounds, allowed: f64) -> (f64, f64) {
    // 1 / sqrt(4e / m), written so that m = 0 gives 0 rather than NaN.
    let count = |m: f64| (m / (4.0 * allowed)).sqrt();
    (
        count(bounds.m_uu + bounds.m_uv),
        count(bounds.m_vv + bounds.m_uv),
    )
}

/// The grid `(u, v)` that keeps the chord error of `bounds`' surface within
/// `allowed`: [`required_segments`] rounded up the ladder.
pub fn segments_for_error(bounds: &SurfaceBounds, allowed: f64) -> (u32, u32) {
    let (u, v) = required_segments(bounds, allowed);
    (ladder_up(u), ladder_up(v))
}

impl Scene {
    /// World length per pixel at distance 1 along the view axis, inverted:
    /// `(height / 2) / tan(fov_y / 2)` pixels per unit length.
    pub fn pixels_per_unit_at_distance_one(&self) -> f64 {
        let half_fov = f64::from(self.camera.fov_y_degrees).to_radians() * 0.5;
        f64::from(self.output.height) * 0.5 / half_fov.tan()
    }

    /// A warning when some auto objects need a finer grid than the largest
    /// (`MAX_SEGMENTS` per direction): they get the largest, and their
    /// chord error is above `max_pixel_error`. `None` when every auto
    /// object's bound is met.
    pub fn tessellation_ceiling(&self) -> Option<String> {
        let max = f64::from(MAX_SEGMENTS);
        let short = self
            .objects
            .iter()
            .zip(self.auto_bounds())
            .filter_map(|(object, bounds)| {
                let bounds = bounds?;
                let (u, v) = required_segments(&bounds, self.allowed_error(object, &bounds));
                // NaN (unusable numbers) also falls back to the largest.
                (!(u <= max && v <= max)).then_some(())
            })
            .count();
        (short > 0).then(|| {
            format!(
                "tessellation auto: {short} object(s) need more than {MAX_SEGMENTS} segments \
                 for max_pixel_error {}; they get {MAX_SEGMENTS}, and their error is larger",
                self.output.max_pixel_error
            )
        })
    }

    /// The object-space chord error an auto object with surface `bounds`
    /// is allowed: `max_pixel_error` pixels at the nearest point of its
    /// bounding sphere (no nearer than the near plane), in world length,
    /// over the transform's largest scale (which stretches object-space
    /// errors at most that much).
    fn allowed_error(&self, object: &Object, bounds: &SurfaceBounds) -> f64 {
        let transform = &object.transform;
        let scale = f64::from(transform.max_scale());
        let centre = transform.matrix_f64().transform_point3(bounds.centre);
        let surface_distance = self.camera.eye.distance(centre) - bounds.radius * scale;
        let distance = surface_distance.max(f64::from(self.camera.near));
        let world = f64::from(self.output.max_pixel_error) * distance
            / self.pixels_per_unit_at_distance_one();
        world / scale
    }

    /// The grid an auto object with surface `bounds` gets.
    fn auto_segments(&self, object: &Object, bounds: &SurfaceBounds) -> (u32, u32) {
        segments_for_error(bounds, self.allowed_error(object, bounds))
    }

    /// Object `index`'s grid `(u, v)`: its own `tessellation`, or for an
    /// auto object the one chosen by screen-space error (see the module
    /// documentation). Out of range or a loaded mesh: its stored value.
    pub fn object_tessellation(&self, index: usize) -> (u32, u32) {
        let Some(object) = self.objects.get(index) else {
            return (MIN_SEGMENTS, MIN_SEGMENTS);
        };
        match (object.auto_tessellation, object.shape.surface()) {
            (true, Some(surface)) => self.auto_segments(object, &surface_bounds(surface.as_ref())),
            _ => object.tessellation,
        }
    }

    /// [`Scene::object_tessellation`] of every object, estimating each
    /// distinct shape's bounds once.
    pub fn tessellations(&self) -> Vec<(u32, u32)> {
        self.objects
            .iter()
            .zip(self.auto_bounds())
            .map(|(object, bounds)| match bounds {
                Some(bounds) => self.auto_segments(object, &bounds),
                None => object.tessellation,
            })
            .collect()
    }

    /// Each object's surface bounds when its grid is chosen by screen-space
    /// error (an auto parametric object), `None` otherwise; each distinct
    /// shape's are estimated once.
    fn auto_bounds(&self) -> Vec<Option<SurfaceBounds>> {
        let mut known: Vec<(&Shape, SurfaceBounds)> = Vec::new();
        self.objects
            .iter()
            .map(|object| {
                if !object.auto_tessellation {
                    return None;
                }
                if let Some((_, bounds)) = known.iter().find(|(shape, _)| **shape == object.shape) {
                    return Some(*bounds);
                }
                let bounds = surface_bounds(object.shape.surface()?.as_ref());
                known.push((&object.shape, bounds));
                Some(bounds)
            })
            .collect()
    }

    /// One line on the grids `tessellation = "auto"` chose, for `aerial
    /// render` to print: the number of auto objects, each distinct grid
    /// with how many objects use it, and the scene's triangle count.
    /// `None` when no object is auto.
    pub fn tessellation_summary(&self) -> Option<String> {
        let counts = self.tessellations();
        let mut grids: Vec<((u32, u32), usize)> = Vec::new();
        let mut auto = 0;
        for (object, &grid) in self.objects.iter().zip(&counts) {
            if !object.auto_tessellation || matches!(object.shape, Shape::Mesh { .. }) {
                continue;
            }
            auto += 1;
            match grids.iter_mut().find(|(g, _)| *g == grid) {
                Some((_, n)) => *n += 1,
                None => grids.push((grid, 1)),
            }
        }
        if auto == 0 {
            return None;
        }
        grids.sort_unstable();
        let listed: Vec<String> = grids
            .iter()
            .map(|((u, v), n)| format!("{u}x{v} x{n}"))
            .collect();
        Some(format!(
            "tessellation auto (max_pixel_error {}): {auto} objects, grids {}; {} triangles drawn",
            self.output.max_pixel_error,
            listed.join(", "),
            self.triangle_count()
        ))
    }
}

#[cfg(test)]
mod tests;
