//! The CPU double-precision reference: optical depth between two points and
//! single-scattering radiance along a ray, by adaptive Simpson quadrature.
//!
//! Error control: each interval is split until the two-panel Simpson
//! estimate differs from the one-panel estimate by at most 15·tol·(interval
//! share) (Richardson: the difference over 15 estimates the error of the
//! refined value), with `tol = REL_TOL × the integral's magnitude from a
//! first coarse pass`, so the stated bound is a relative error of about
//! [`REL_TOL`] per integral for integrands smooth on the initial grid. The
//! initial grid has [`INITIAL_PANELS`] panels, so a density that falls over
//! one Mie scale height is seen on paths up to ~100 scale heights long;
//! recursion stops at depth [`MAX_DEPTH`].

use super::{
    cornette_shanks_phase, hits_ground, ray_sphere, rayleigh_phase, Atmosphere, Densities, Sun,
};
use glam::DVec3;

/// Relative tolerance of every integral.
pub const REL_TOL: f64 = 1e-7;
/// Panels of the initial grid of every integral.
pub const INITIAL_PANELS: usize = 64;
/// How finely an integral starts and how far it refines: relative
/// tolerance (of every nested integral; the radiance integral gets ten
/// times it) and initial panels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Precision {
    pub rel_tol: f64,
    pub panels: usize,
}

/// The oracle of the tests: [`REL_TOL`] on [`INITIAL_PANELS`] panels.
pub const PRECISE: Precision = Precision {
    rel_tol: REL_TOL,
    panels: INITIAL_PANELS,
};

/// For whole images (the CPU reference renderer): 16 initial panels and a
/// 1e-6 tolerance, about 15 times cheaper than [`PRECISE`] (the nested
/// integrals cost panels² evaluations a pixel); its radiance is within
/// 1e-5 of [`PRECISE`]'s on the views tested in `tests.rs`.
pub const IMAGE: Precision = Precision {
    rel_tol: 1e-6,
    panels: 16,
};

/// Deepest bisection.
pub const MAX_DEPTH: u32 = 24;

/// The reference's own cut of a tall atmosphere: what it leaves out is
/// below 1e-12 of the vertical column and of an optical depth of one, far
/// below its integrals' 1e-7 tolerance (and a million times below the GPU
/// pass's cut, [`super::CUT_TOLERANCE`], which it is the oracle for).
pub const REFERENCE_CUT: f64 = 1e-12;

/// The stretches of `[t0, t1]` along `origin + t·direction` (origin
/// relative to the planet centre, direction unit) that the integrals
/// cover: all of it when the atmosphere's top lies below the altitude
/// where its air is negligible at [`REFERENCE_CUT`]; otherwise the part
/// inside that sphere, split where the ray crosses the spheres where a
/// profile's air ends far below it, so that each stretch's initial grid
/// of [`Precision::panels`] resolves the profiles alive on it.
pub fn pieces(
    atmosphere: &Atmosphere,
    origin: DVec3,
    direction: DVec3,
    t0: f64,
    t1: f64,
) -> Vec<(f64, f64)> {
    if t1 <= t0 {
        return Vec::new();
    }
    let cuts = atmosphere.negligible_altitudes(REFERENCE_CUT);
    let outer = cuts.iter().copied().fold(0.0, f64::max);
    let radius = |h: f64| atmosphere.bottom_radius + h;
    if radius(outer) >= atmosphere.top_radius {
        return vec![(t0, t1)];
    }
    let Some((enter, leave)) = ray_sphere(origin, direction, radius(outer)) else {
        return Vec::new();
    };
    let (a, b) = (t0.max(enter), t1.min(leave));
    if b <= a {
        return Vec::new();
    }
    let mut breaks = vec![a, b];
    for &h in &cuts {
        // A profile whose air ends above an eighth of the outer cut has
        // eight or more of the initial panels on a vertical ray through
        // it, more on a slanted one: splitting there would only add
        // panels (Earth's Mie and ozone, at about 40 km of 270, are not).
        if h > 0.0 && h < outer / 8.0 {
            if let Some((c0, c1)) = ray_sphere(origin, direction, radius(h)) {
                breaks.extend([c0, c1].into_iter().filter(|&t| t > a && t < b));
            }
        }
    }
    breaks.sort_by(f64::total_cmp);
    breaks.windows(2).map(|w| (w[0], w[1])).collect()
}

/// Adaptive Simpson over `[a, b]` of a function with several outputs
/// (`N` of them), each controlled to `tol` absolute.
fn adaptive<const N: usize>(
    f: &mut dyn FnMut(f64) -> [f64; N],
    a: f64,
    b: f64,
    precision: Precision,
) -> [f64; N] {
    let (rel, panels) = (precision.rel_tol, precision.panels.max(1));
    fn simpson<const N: usize>(fa: &[f64; N], fm: &[f64; N], fb: &[f64; N], h: f64) -> [f64; N] {
        std::array::from_fn(|i| h / 6.0 * (fa[i] + 4.0 * fm[i] + fb[i]))
    }
    #[allow(clippy::too_many_arguments)]
    fn recurse<const N: usize>(
        f: &mut dyn FnMut(f64) -> [f64; N],
        a: f64,
        b: f64,
        fa: [f64; N],
        fm: [f64; N],
        fb: [f64; N],
        whole: [f64; N],
        tol: &[f64; N],
        depth: u32,
    ) -> [f64; N] {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = simpson(&fa, &flm, &fm, m - a);
        let right = simpson(&fm, &frm, &fb, b - m);
        let converged = (0..N).all(|i| (left[i] + right[i] - whole[i]).abs() <= 15.0 * tol[i]);
        if converged || depth >= MAX_DEPTH {
            return std::array::from_fn(|i| {
                left[i] + right[i] + (left[i] + right[i] - whole[i]) / 15.0
            });
        }
        let half: [f64; N] = std::array::from_fn(|i| tol[i] * 0.5);
        let l = recurse(f, a, m, fa, flm, fm, left, &half, depth + 1);
        let r = recurse(f, m, b, fm, frm, fb, right, &half, depth + 1);
        std::array::from_fn(|i| l[i] + r[i])
    }
    if b <= a {
        return [0.0; N];
    }
    let h = (b - a) / panels as f64;
    let points: Vec<f64> = (0..=2 * panels).map(|i| a + 0.5 * h * i as f64).collect();
    let values: Vec<[f64; N]> = points.iter().map(|&t| f(t)).collect();
    // The coarse pass sets the absolute tolerance from the integral's size.
    let mut coarse = [0.0; N];
    for k in 0..panels {
        let s = simpson(&values[2 * k], &values[2 * k + 1], &values[2 * k + 2], h);
        for i in 0..N {
            coarse[i] += s[i].abs();
        }
    }
    let tol: [f64; N] = std::array::from_fn(|i| (coarse[i] * rel / panels as f64).max(1e-300));
    let mut total = [0.0; N];
    for k in 0..panels {
        let (fa, fm, fb) = (values[2 * k], values[2 * k + 1], values[2 * k + 2]);
        let whole = simpson(&fa, &fm, &fb, h);
        let (a0, b0) = (points[2 * k], points[2 * k + 2]);
        let part = recurse(f, a0, b0, fa, fm, fb, whole, &tol, 0);
        for i in 0..N {
            total[i] += part[i];
        }
    }
    total
}

/// Density integrals (metres) along the segment from `a` to `b`, both
/// relative to the planet centre.
pub fn densities_between(atmosphere: &Atmosphere, a: DVec3, b: DVec3) -> Densities {
    densities_between_with(atmosphere, a, b, PRECISE)
}

/// [`densities_between`] at `precision`.
pub fn densities_between_with(
    atmosphere: &Atmosphere,
    a: DVec3,
    b: DVec3,
    precision: Precision,
) -> Densities {
    let length = a.distance(b);
    if length == 0.0 {
        return Densities::default();
    }
    let direction = (b - a) / length;
    let mut sum = [0.0; 3];
    for (t0, t1) in pieces(atmosphere, a, direction, 0.0, length) {
        let part = adaptive(
            &mut |t| {
                let d = atmosphere.densities(atmosphere.altitude(a + t * direction));
                [d.rayleigh, d.mie, d.ozone]
            },
            t0,
            t1,
            precision,
        );
        for (s, p) in sum.iter_mut().zip(part) {
            *s += p;
        }
    }
    Densities {
        rayleigh: sum[0],
        mie: sum[1],
        ozone: sum[2],
    }
}

/// Density integrals from `p` (relative to the centre, inside the
/// atmosphere) along `direction` to the top of the atmosphere, or `None`
/// when the ray hits the ground first.
pub fn densities_to_top(atmosphere: &Atmosphere, p: DVec3, direction: DVec3) -> Option<Densities> {
    densities_to_top_with(atmosphere, p, direction, PRECISE)
}

/// [`densities_to_top`] at `precision`.
pub fn densities_to_top_with(
    atmosphere: &Atmosphere,
    p: DVec3,
    direction: DVec3,
    precision: Precision,
) -> Option<Densities> {
    if hits_ground(atmosphere, p, direction) {
        return None;
    }
    let (_, exit) = ray_sphere(p, direction, atmosphere.top_radius)?;
    Some(densities_between_with(
        atmosphere,
        p,
        p + exit.max(0.0) * direction,
        precision,
    ))
}

/// The stretch of the ray `origin + t·direction` inside the atmosphere, and
/// whether it ends on the ground.
pub fn atmosphere_segment(
    atmosphere: &Atmosphere,
    origin: DVec3,
    direction: DVec3,
) -> Option<(f64, f64, bool)> {
    let (t0, t1) = ray_sphere(origin, direction, atmosphere.top_radius)?;
    if t1 <= 0.0 {
        return None;
    }
    let start = t0.max(0.0);
    // A ray from a point on the ground (g0 = 0) into it hits it at
    // distance 0; one pointing away from it has g1 = 0 and misses.
    match ray_sphere(origin, direction, atmosphere.bottom_radius) {
        Some((g0, g1)) if g0 >= 0.0 && g1 > 0.0 => Some((start, g0, true)),
        _ => Some((start, t1, false)),
    }
}

/// Single-scattered radiance (per unit of `sun.irradiance`'s scale, i.e.
/// in units of the irradiance per steradian) reaching `origin` (relative to
/// the planet centre) from `direction` (unit, pointing away from the
/// viewer), plus the directly lit ground where the ray hits it (Lambertian,
/// `ground_albedo`/π, lit by the transmitted sun only). The sun disc is not
/// included.
pub fn radiance(atmosphere: &Atmosphere, sun: &Sun, origin: DVec3, direction: DVec3) -> DVec3 {
    radiance_with(atmosphere, sun, origin, direction, PRECISE)
}

/// [`radiance`] at `precision`.
pub fn radiance_with(
    atmosphere: &Atmosphere,
    sun: &Sun,
    origin: DVec3,
    direction: DVec3,
    precision: Precision,
) -> DVec3 {
    let Some((start, end, ground)) = atmosphere_segment(atmosphere, origin, direction) else {
        return DVec3::ZERO;
    };
    let (mut radiance, view) =
        scattering(atmosphere, sun, origin, direction, start, end, precision);
    if ground {
        let p = origin + end * direction;
        let normal = p.normalize();
        let cos = normal.dot(sun.direction);
        if cos > 0.0 {
            let to_sun =
                densities_to_top_with(atmosphere, p * (1.0 + 1e-12), sun.direction, precision)
                    .unwrap_or_default();
            radiance += atmosphere.ground_albedo / std::f64::consts::PI
                * cos
                * sun.irradiance
                * atmosphere.transmittance(to_sun)
                * view;
        }
    }
    radiance
}

/// Aerial perspective in front of a surface `distance` along the ray from
/// `origin` (relative to the planet centre; `direction` unit): the
/// single-scattered radiance in-scattered between the two, and the
/// transmittance of that path, so the surface's radiance L reaches the
/// viewer as L·transmittance + in-scattered. Only the stretch inside the
/// atmosphere counts; a surface in front of it gets (0, 1).
pub fn aerial_perspective(
    atmosphere: &Atmosphere,
    sun: &Sun,
    origin: DVec3,
    direction: DVec3,
    distance: f64,
) -> (DVec3, DVec3) {
    aerial_perspective_with(atmosphere, sun, origin, direction, distance, PRECISE)
}

/// [`aerial_perspective`] at `precision`.
pub fn aerial_perspective_with(
    atmosphere: &Atmosphere,
    sun: &Sun,
    origin: DVec3,
    direction: DVec3,
    distance: f64,
    precision: Precision,
) -> (DVec3, DVec3) {
    match atmosphere_segment(atmosphere, origin, direction) {
        Some((start, end, _)) if distance > start => scattering(
            atmosphere,
            sun,
            origin,
            direction,
            start,
            end.min(distance),
            precision,
        ),
        _ => (DVec3::ZERO, DVec3::ONE),
    }
}

/// Single scattering along `origin + t·direction` for t in [start, end]
/// (inside the atmosphere): the in-scattered radiance reaching the point at
/// `start`, and the transmittance from `start` to `end`.
fn scattering(
    atmosphere: &Atmosphere,
    sun: &Sun,
    origin: DVec3,
    direction: DVec3,
    start: f64,
    end: f64,
    precision: Precision,
) -> (DVec3, DVec3) {
    let mu = direction.dot(sun.direction);
    let phase_r = rayleigh_phase(mu);
    let phase_m = cornette_shanks_phase(mu, atmosphere.mie_g);
    let entry = origin + start * direction;
    let integrand = |t: f64| -> [f64; 3] {
        let p = origin + t * direction;
        let Some(to_sun) = densities_to_top_with(atmosphere, p, sun.direction, precision) else {
            return [0.0; 3];
        };
        let view = densities_between_with(atmosphere, entry, p, precision);
        let transmittance = atmosphere.transmittance(to_sun.plus(view));
        let d = atmosphere.densities(atmosphere.altitude(p));
        let scattering = atmosphere.rayleigh_scattering * (d.rayleigh * phase_r)
            + atmosphere.mie_scattering * (d.mie * phase_m);
        (scattering * transmittance * sun.irradiance).to_array()
    };
    let outer = Precision {
        rel_tol: precision.rel_tol * 10.0,
        ..precision
    };
    let mut integrand = integrand;
    let mut sum = DVec3::ZERO;
    for (t0, t1) in pieces(atmosphere, origin, direction, start, end) {
        sum += DVec3::from_array(adaptive(&mut integrand, t0, t1, outer));
    }
    let view = atmosphere.transmittance(densities_between_with(
        atmosphere,
        entry,
        origin + end * direction,
        precision,
    ));
    (sum, view)
}

/// Transmittance per channel of sunlight reaching `point` (relative to the
/// planet centre) from the sun along `sun_direction` (unit): through the
/// atmosphere to its top, zero when the planet is in the way (the point
/// sun's hard shadow, as everywhere in this model), one when the ray never
/// enters the atmosphere. Works inside the atmosphere and from space. A
/// point below the ground is taken at the ground straight above it: a
/// surface half-buried in the planet is lit as if it stood on it.
pub fn sun_transmittance(atmosphere: &Atmosphere, point: DVec3, sun_direction: DVec3) -> DVec3 {
    let r = point.length();
    let p = if r < atmosphere.bottom_radius && r > 0.0 {
        point * (atmosphere.bottom_radius / r)
    } else {
        point
    };
    if hits_ground(atmosphere, p, sun_direction) {
        return DVec3::ZERO;
    }
    if p.length() <= atmosphere.top_radius {
        // From inside only the top sphere's exit matters (the ground was
        // tested above); no ground root near t = 0 to misjudge at r = R.
        return densities_to_top(atmosphere, p, sun_direction)
            .map_or(DVec3::ZERO, |d| atmosphere.transmittance(d));
    }
    match ray_sphere(p, sun_direction, atmosphere.top_radius) {
        Some((entry, exit)) if exit > 0.0 => atmosphere.transmittance(densities_between(
            atmosphere,
            p + entry.max(0.0) * sun_direction,
            p + exit * sun_direction,
        )),
        _ => DVec3::ONE,
    }
}
