//! The [`ParametricSurface`] trait: a surface `r(u, v)` over the unit square
//! with analytic first derivatives, from which [`crate::mesh::tessellate`]
//! builds positions, normals and tangents.
//!
//! Everything here is `f64` so that the analytic derivatives can be checked
//! against finite differences to tight tolerances; vertices are narrowed to
//! `f32` only when the mesh is written.

use glam::DVec3;

/// Parameter steps tried, smallest first, when a derivative vanishes at a
/// point (a sphere pole, a spindle torus's inner ring) and the limit
/// direction has to be read from a nearby regular point.
const FALLBACK_STEPS: [f64; 4] = [1e-7, 1e-5, 1e-3, 1e-1];

/// A smooth surface `r(u, v)` with `u, v` in `[0, 1]`.
///
/// Implementors give the position and its analytic partial derivatives; the
/// normal and tangent have robust defaults built from them. Implementations
/// are expected to orient themselves so that `du x dv` points outward (or to
/// the "front" side for open surfaces), because the tessellator derives the
/// triangle winding from the same orientation.
pub trait ParametricSurface {
    /// The point `r(u, v)`.
    fn position(&self, u: f64, v: f64) -> DVec3;

    /// The analytic partial derivative `dr/du`.
    fn du(&self, u: f64, v: f64) -> DVec3;

    /// The analytic partial derivative `dr/dv`.
    fn dv(&self, u: f64, v: f64) -> DVec3;

    /// The unit normal `normalize(du x dv)`.
    ///
    /// Where the cross product vanishes (for example a sphere pole, where
    /// `du` is zero) the normal is taken from nearby points stepped towards
    /// the middle of the parameter square, which converges to the limit
    /// normal. It never returns NaN: if nothing nearby is regular either, it
    /// falls back to `+Y`.
    fn normal(&self, u: f64, v: f64) -> DVec3 {
        derived_normal(self, u, v)
    }

    /// The unit tangent `normalize(du)`, following `+u`.
    ///
    /// Where `du` vanishes the direction is taken from nearby points stepped
    /// in `v` (then `u`), as for [`ParametricSurface::normal`]. It never
    /// returns NaN; the tessellator additionally makes it orthogonal to the
    /// normal.
    fn tangent(&self, u: f64, v: f64) -> DVec3 {
        derived_tangent(self, u, v)
    }
}

/// The default [`ParametricSurface::normal`]: `normalize(du x dv)`, or the
/// limit from nearby regular points where that degenerates, or `+Y` if no
/// nearby point is regular either. Never NaN.
///
/// Public so that surfaces which override `normal` with a closed form can
/// still use it at their own degenerate points.
pub fn derived_normal<S: ParametricSurface + ?Sized>(surface: &S, u: f64, v: f64) -> DVec3 {
    if let Some(n) = regular_normal(surface, u, v) {
        return n;
    }
    for step in FALLBACK_STEPS {
        let (su, sv) = step_inwards(u, v, step);
        // Step in v first: the usual degeneracy (a pole) is a whole v = const
        // line, so moving along u alone would not leave it.
        for (pu, pv) in [(u, sv), (su, v), (su, sv)] {
            if let Some(n) = regular_normal(surface, pu, pv) {
                return n;
            }
        }
    }
    DVec3::Y
}

/// The default [`ParametricSurface::tangent`]: `normalize(du)`, or the limit
/// from nearby points where `du` vanishes, or `+X`. Never NaN.
pub fn derived_tangent<S: ParametricSurface + ?Sized>(surface: &S, u: f64, v: f64) -> DVec3 {
    if let Some(t) = unit(surface.du(u, v)) {
        return t;
    }
    for step in FALLBACK_STEPS {
        let (su, sv) = step_inwards(u, v, step);
        for (pu, pv) in [(u, sv), (su, v), (su, sv)] {
            if let Some(t) = unit(surface.du(pu, pv)) {
                return t;
            }
        }
    }
    DVec3::X
}

/// `normalize(du x dv)` if the cross product is clearly non-zero relative to
/// the derivative lengths, which keeps round-off near a degenerate point from
/// producing an arbitrary direction.
fn regular_normal<S: ParametricSurface + ?Sized>(surface: &S, u: f64, v: f64) -> Option<DVec3> {
    let du = surface.du(u, v);
    let dv = surface.dv(u, v);
    let n = du.cross(dv);
    let scale = du.length() * dv.length();
    if !(scale.is_finite() && n.is_finite()) || n.length() <= 1e-12 * scale || scale == 0.0 {
        return None;
    }
    unit(n)
}

/// Normalises `v`, or `None` when it is zero, tiny or not finite.
pub(crate) fn unit(v: DVec3) -> Option<DVec3> {
    let len = v.length();
    if len.is_finite() && len > 1e-300 {
        let n = v / len;
        n.is_finite().then_some(n)
    } else {
        None
    }
}

/// Moves `(u, v)` by `step` towards the centre of the unit square, so the
/// probe stays inside the parameter domain at both edges.
fn step_inwards(u: f64, v: f64, step: f64) -> (f64, f64) {
    let towards = |x: f64| if x < 0.5 { x + step } else { x - step };
    (towards(u), towards(v))
}
