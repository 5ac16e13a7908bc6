//! The ozone layer's density integral along a ray to the top of the
//! atmosphere, in closed form rather than from the optical-depth table.
//!
//! Why not the table: the tent profile's start, peak and end are kinks of
//! the density. A ray whose lowest point lies a distance δ below a kink
//! crosses the shell above it along a chord that grows as √δ, so its
//! optical depth grows as δ^(3/2), and the set of such rays is a curve
//! through the table, not a row or a column. Bilinear filtering of a
//! 256 × 64 table misses it by up to 2.6e-3 in transmittance (Earth's
//! green, measured), 26 times the table's 1e-4 goal.
//!
//! The closed form: within each shell of the tent (start → peak, peak →
//! end) the density is linear in the altitude, and a ray meets a shell in
//! at most two intervals, bounded by its crossings of the two spheres
//! (split at the ray's lowest point when it stays above the inner one).
//! On each interval the altitude is a smooth, monotonic function of the
//! distance (nearly a parabola), so three-point Gauss–Legendre, exact for
//! polynomials of degree five, integrates it to a relative error of about
//! 2e-8 on Earth (measured against the adaptive reference; two points
//! gave 8e-6, as the altitude's quartic term over a 400 km interval is
//! beyond them). Every distance comes from the ray's lowest point (its
//! altitude computed without a planet-scale difference), so the same
//! arithmetic holds in 32-bit floats: `ozone_to_top` in
//! `glsl/include/atmosphere.glsl` does this arithmetic, written without
//! early exits (a CPU driver runs both sides of a divergent branch).

use super::Atmosphere;

/// Three-point Gauss–Legendre nodes (on [−1, 1]) and weights.
const GAUSS_NODE: f64 = 0.774_596_669_241_483_4; // √(3/5)
const GAUSS_WEIGHTS: [f64; 2] = [5.0 / 9.0, 8.0 / 9.0];

/// The ray from altitude `alt` (radius R + alt) along cosine `mu` of its
/// zenith angle, described from its lowest point (the foot of the
/// perpendicular from the planet centre, behind the start when `mu` > 0).
struct Ray {
    bottom: f64,
    /// Distance along the ray from the lowest point to the start.
    start: f64,
    /// ρ² = r² − R² at the lowest point.
    rho2_low: f64,
    /// Altitude of the lowest point.
    alt_low: f64,
}

impl Ray {
    fn new(bottom: f64, alt: f64, mu: f64) -> Ray {
        let (rho2_low, alt_low) = super::lowest_point(bottom, alt, mu);
        Ray {
            bottom,
            start: (bottom + alt) * mu,
            rho2_low,
            alt_low,
        }
    }

    /// Distances from the start (negative: behind it) where the ray meets
    /// the sphere at altitude `k`, or `None` when it passes above it.
    fn crossings(&self, k: f64) -> Option<(f64, f64)> {
        // Half the chord, from R_k² − r_low² as a product.
        let disc = (k - self.alt_low) * (2.0 * self.bottom + k + self.alt_low);
        if disc < 0.0 {
            return None;
        }
        let half = disc.sqrt();
        Some((-half - self.start, half - self.start))
    }

    /// Altitude at distance `s` from the start.
    fn altitude(&self, s: f64) -> f64 {
        let u = s + self.start;
        let rho2 = self.rho2_low + u * u;
        rho2 / ((rho2 + self.bottom * self.bottom).sqrt() + self.bottom)
    }

    /// ∫ density over [a, b] of a density linear in the altitude,
    /// `slope` · (h − `zero`).
    fn linear_integral(&self, a: f64, b: f64, zero: f64, slope: f64) -> f64 {
        if b <= a {
            return 0.0;
        }
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        let f = |s: f64| slope * (self.altitude(s) - zero);
        half * (GAUSS_WEIGHTS[0] * (f(mid - half * GAUSS_NODE) + f(mid + half * GAUSS_NODE))
            + GAUSS_WEIGHTS[1] * f(mid))
    }
}

/// The ozone density integral (metres at peak density) from altitude `alt`
/// along cosine `mu` to the top of the atmosphere. The ray must miss the
/// ground (the caller shadows rays into the planet).
pub fn ozone_to_top(atmosphere: &Atmosphere, alt: f64, mu: f64) -> f64 {
    // The effective top, as the pass's: it never cuts the layer while the
    // layer absorbs (see Atmosphere::negligible_altitudes).
    let top = atmosphere.effective_top_radius() - atmosphere.bottom_radius;
    let ray = Ray::new(atmosphere.bottom_radius, alt.clamp(0.0, top), mu);
    let Some((_, end)) = ray.crossings(top) else {
        return 0.0;
    };
    let [start, peak, stop] = atmosphere.ozone_layer;
    // (lower, upper altitude, altitude where the density is zero, slope).
    let shells = [
        (start, peak, start, 1.0 / (peak - start)),
        (peak, stop, stop, -1.0 / (stop - peak)),
    ];
    let mut sum = 0.0;
    for (lower, upper, zero, slope) in shells {
        let upper = upper.min(top);
        if lower >= upper {
            continue;
        }
        // Inside the upper sphere, outside the lower one, ahead of the
        // start and before the top: at most two intervals.
        let Some((in0, in1)) = ray.crossings(upper) else {
            continue;
        };
        let (a, b) = (in0.max(0.0), in1.min(end));
        // Outside the lower sphere: split where the ray enters and leaves
        // it; when it passes above it, split at the lowest point anyway,
        // so each interval's altitude is monotonic and Gauss's error on
        // the longest chord is 2^7 times smaller.
        let (c0, c1) = ray.crossings(lower).unwrap_or((-ray.start, -ray.start));
        sum += ray.linear_integral(a, b.min(c0), zero, slope);
        sum += ray.linear_integral(a.max(c1), b, zero, slope);
    }
    sum
}
