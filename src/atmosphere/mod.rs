//! The physical atmosphere model, in double precision: density profiles
//! (exponential Rayleigh and Mie, the ozone tent), extinction, the phase
//! functions and cancellation-free ray–sphere intersection.
//!
//! Single scattering only. The sun is a point for lighting (a sample is lit
//! when the ray from it towards the sun's centre misses the planet: a hard
//! planet shadow, no partial disc), and a disc of the given angular radius
//! only when seen directly.
//!
//! [`model`] holds the types (planet and air, sun, table settings) that
//! scenes are read into; [`quadrature`](mod@quadrature) integrates the model
//! adaptively (the oracle of the tests);
//! [`transport`] adds every order of scattering and ground reflection to
//! it (an unbiased Monte Carlo estimate with its standard error);
//! [`table`] bakes the optical-depth table the GPU pass samples;
//! [`ozone`] integrates the ozone layer along a ray in closed form;
//! [`coefficients`] derives scattering coefficients from physical
//! quantities (the seed's optional Rayleigh and Mie formulas).
//!
//! A tall atmosphere (`top_radius` far above the air, up to 1e9 m) is cut
//! at the altitude where the air it could still hold is negligible
//! ([`Atmosphere::negligible_altitude`]): the GPU pass, its tables and the
//! reference then spend their samples where the air is.

pub mod coefficients;
pub mod model;
pub mod ozone;
pub mod quadrature;
pub mod table;
pub mod transport;

use glam::DVec3;
use std::f64::consts::PI;

pub use model::{Atmosphere, Sky, Sun};
pub use table::{OpticalDepthTable, OzoneDepth, TableMapping};

/// The three density profiles at one point: Rayleigh, Mie and ozone, each
/// dimensionless (1 at the ground for the exponentials, 1 at the ozone
/// peak).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Densities {
    pub rayleigh: f64,
    pub mie: f64,
    pub ozone: f64,
}

impl Densities {
    pub fn scaled(self, k: f64) -> Densities {
        Densities {
            rayleigh: self.rayleigh * k,
            mie: self.mie * k,
            ozone: self.ozone * k,
        }
    }

    pub fn plus(self, o: Densities) -> Densities {
        Densities {
            rayleigh: self.rayleigh + o.rayleigh,
            mie: self.mie + o.mie,
            ozone: self.ozone + o.ozone,
        }
    }
}

impl Atmosphere {
    /// The density profiles at altitude `h` above the ground (metres).
    pub fn densities(&self, h: f64) -> Densities {
        let [start, peak, end] = self.ozone_layer;
        let ozone = if h <= start || h >= end {
            0.0
        } else if h <= peak {
            (h - start) / (peak - start)
        } else {
            (end - h) / (end - peak)
        };
        Densities {
            rayleigh: (-h / self.rayleigh_scale_height).exp(),
            mie: (-h / self.mie_scale_height).exp(),
            ozone,
        }
    }

    /// Extinction optical depth per channel for integrated densities
    /// (density-weighted path lengths in metres).
    pub fn optical_depth(&self, d: Densities) -> DVec3 {
        self.rayleigh_scattering * d.rayleigh
            + self.mie_extinction * d.mie
            + self.ozone_absorption * d.ozone
    }

    /// Transmittance per channel for integrated densities.
    pub fn transmittance(&self, d: Densities) -> DVec3 {
        let t = self.optical_depth(d);
        DVec3::new((-t.x).exp(), (-t.y).exp(), (-t.z).exp())
    }

    /// Altitude of `p` (relative to the planet centre) above the ground.
    pub fn altitude(&self, p: DVec3) -> f64 {
        p.length() - self.bottom_radius
    }

    /// The altitude of each density profile (Rayleigh, Mie, ozone) above
    /// which what it holds along any ray is negligible at `tolerance`:
    /// the exponentials where the bound of [`column_above`] on both
    /// stretches of a ray above it is at most `tolerance` × min(H,
    /// 1/β_max): below `tolerance` of the vertical column from the ground
    /// (≈ H, so of the in-scattering a ray through the air collects) and
    /// below an optical depth of `tolerance` (so of any transmittance);
    /// the ozone tent at its end, where it is exactly zero (0 when it
    /// absorbs nothing). An altitude may lie above the top (a profile
    /// that matters all the way up); the callers take the minimum.
    pub fn negligible_altitudes(&self, tolerance: f64) -> [f64; 3] {
        let top = self.top_radius;
        let exponential = |scale_height: f64, extinction: DVec3| {
            let beta = extinction.max_element();
            let allowed = if beta > 0.0 {
                tolerance * scale_height.min(1.0 / beta)
            } else {
                tolerance * scale_height
            };
            // 2·e^(−h/H)·(√(π R_top H) + 2H) ≤ allowed.
            let bound_at_ground =
                2.0 * ((std::f64::consts::PI * top * scale_height).sqrt() + 2.0 * scale_height);
            scale_height * (bound_at_ground / allowed).ln().max(0.0)
        };
        let ozone = if self.ozone_absorption.max_element() > 0.0 {
            self.ozone_layer[2]
        } else {
            0.0
        };
        [
            exponential(self.rayleigh_scale_height, self.rayleigh_scattering),
            exponential(self.mie_scale_height, self.mie_extinction),
            ozone,
        ]
    }

    /// The highest of [`Atmosphere::negligible_altitudes`]: above it the
    /// atmosphere holds nothing that matters at `tolerance`.
    pub fn negligible_altitude(&self, tolerance: f64) -> f64 {
        let [r, m, o] = self.negligible_altitudes(tolerance);
        r.max(m).max(o)
    }

    /// The radius the GPU pass and its tables treat as the top of the
    /// atmosphere: `top_radius`, or lower where the air above is
    /// negligible at [`CUT_TOLERANCE`]. Never thinner than
    /// [`MIN_CUT_THICKNESS`] of the planet's radius, which float32
    /// altitudes resolve. For Earth's default 60 km it is `top_radius`
    /// (the cut is at 168 km for `top_radius` = 1e9 m).
    pub fn effective_top_radius(&self) -> f64 {
        self.cut_top_radius(CUT_TOLERANCE)
    }

    /// `top_radius` lowered to the negligible altitude at `tolerance`.
    pub fn cut_top_radius(&self, tolerance: f64) -> f64 {
        let floor = self.bottom_radius * MIN_CUT_THICKNESS;
        let cut = self.negligible_altitude(tolerance).max(floor);
        self.top_radius.min(self.bottom_radius + cut)
    }

    /// This atmosphere with its top at [`Atmosphere::effective_top_radius`]:
    /// what the GPU pass draws.
    pub fn effective(&self) -> Atmosphere {
        Atmosphere {
            top_radius: self.effective_top_radius(),
            ..self.clone()
        }
    }
}

/// The error target of the cut of [`Atmosphere::effective_top_radius`]:
/// the air it leaves out is below a millionth of the vertical column and
/// of an optical depth of one, a thousandth of the pass's own 1e-3 median
/// error bound.
pub const CUT_TOLERANCE: f64 = 1e-6;

/// The thinnest cut atmosphere, as a fraction of the planet's radius: ten
/// times the thinnest shell the scene accepts.
pub const MIN_CUT_THICKNESS: f64 = 1e-5;

/// A bound on ∫ e^(−h/H) ds along a ray that starts at altitude `h` (at
/// most `top` from the centre) and climbs or runs horizontally: the
/// density column of an exponential profile the ray can still meet.
///
/// Why it holds: from radius r₀ ≥ R + h along cosine μ ≥ 0 the radius at
/// distance s is at least √(r₀² + s²) = r₀ + s²/(√(r₀² + s²) + r₀) ≥
/// r₀ + s²/(2r₀ + s). For s ≤ 2r₀ the gain is at least s²/(4r₀), a
/// Gaussian whose half-line integral is √(π r₀ H); beyond 2r₀ it is at
/// least s/2, whose tail integral is 2H·e^(−r₀/H) ≤ 2H. With r₀ ≤ `top`:
/// column ≤ e^(−h/H)·(√(π·top·H) + 2H). Any stretch of a ray that lies
/// above an altitude is one such climb or two (split at its lowest point,
/// each half a climb from there), hence the factor 2 of
/// [`Atmosphere::negligible_altitudes`]. Tested against a brute-force
/// integral of the horizontal column (the bound is about √2 above it).
pub fn column_above(h: f64, scale_height: f64, top: f64) -> f64 {
    (-h / scale_height).exp()
        * ((std::f64::consts::PI * top * scale_height).sqrt() + 2.0 * scale_height)
}

/// The sun's light on an object at `point` (world space): a directional
/// light along `sun.direction` whose colour is the irradiance at the top of
/// the atmosphere times the transmittance from `point` to the top towards
/// the sun, zero in the planet's shadow ([`quadrature::sun_transmittance`],
/// in f64).
///
/// The renderer's shaders compute the same at every shaded point, from
/// the optical-depth table (`glsl/include/object_air.glsl`), and the CPU
/// CPU renderer calls [`quadrature::sun_transmittance`] per pixel:
/// across a 20 m sphere under a sun 1° above the horizon the
/// transmittance varies by a few per cent in blue, across a 600 m one by
/// tens of per cent (`tests/suite/atmosphere_objects.rs`).
pub fn sun_light_at(sky: &Sky, point: DVec3) -> DVec3 {
    sky.sun.irradiance
        * quadrature::sun_transmittance(
            &sky.atmosphere,
            point - sky.atmosphere.center,
            sky.sun.direction,
        )
}

/// Rayleigh phase function, normalised over the sphere:
/// 3/(16π)·(1 + μ²), μ the cosine of the scattering angle.
pub fn rayleigh_phase(mu: f64) -> f64 {
    3.0 / (16.0 * PI) * (1.0 + mu * mu)
}

/// Cornette–Shanks phase function, normalised over the sphere:
/// 3/(8π)·(1 − g²)(1 + μ²) / ((2 + g²)(1 + g² − 2gμ)^(3/2)).
pub fn cornette_shanks_phase(mu: f64, g: f64) -> f64 {
    let g2 = g * g;
    3.0 / (8.0 * PI) * (1.0 - g2) * (1.0 + mu * mu)
        / ((2.0 + g2) * (1.0 + g2 - 2.0 * g * mu).powf(1.5))
}

/// The distances along the ray `origin + t·direction` (origin relative to
/// the sphere's centre, `direction` a unit vector) where it crosses the
/// sphere of `radius`, nearest first (possibly negative), or `None` if it
/// misses.
///
/// Cancellation-free: the discriminant is R² − |o − (o·d)d|², formed as
/// (R − p)(R + p) from the distance p of the line to the centre, instead of
/// (o·d)² − (|o|² − R²), whose two terms are ~4e13 m² at planet scale; the
/// smaller root comes from c/q (Vieta) instead of a difference of nearly
/// equal numbers.
pub fn ray_sphere(origin: DVec3, direction: DVec3, radius: f64) -> Option<(f64, f64)> {
    let b = origin.dot(direction);
    let perpendicular = (origin - b * direction).length();
    let discriminant = (radius - perpendicular) * (radius + perpendicular);
    if discriminant < 0.0 {
        return None;
    }
    let length = origin.length();
    let c = (length - radius) * (length + radius);
    let q = -b - b.signum() * discriminant.sqrt();
    if q == 0.0 {
        // Origin at the centre's tangent point with b = 0: both roots 0.
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (q, c / q);
    Some((t0.min(t1), t0.max(t1)))
}

/// Whether the ray from `p` (relative to the centre) towards `direction`
/// hits the planet: the horizon test μ < −√(1 − (R/r)²), written with the
/// altitude so it holds at 1 m above the ground.
pub fn hits_ground(atmosphere: &Atmosphere, p: DVec3, direction: DVec3) -> bool {
    let r = p.length();
    let h = r - atmosphere.bottom_radius;
    if h < 0.0 {
        return true;
    }
    let mu = p.dot(direction) / r;
    mu < -(h * (2.0 * atmosphere.bottom_radius + h)).sqrt() / r
}

/// The lowest point of the line through a point at altitude `alt` along
/// cosine `mu` of its zenith angle (the foot of the perpendicular from the
/// planet centre; behind the point when `mu` > 0), for a planet of radius
/// `bottom`: (ρ² = r² − R² there, its altitude). Both are negative when the
/// line passes below the ground (−R² and −R for a vertical one).
///
/// ρ² − r²μ² is formed as (ρ − r|μ|)(ρ + r|μ|), so a nearly horizontal
/// line needs no planet-scale difference; chords computed from these
/// depend on r² at the lowest point, which they hold to a few m².
pub fn lowest_point(bottom: f64, alt: f64, mu: f64) -> (f64, f64) {
    let r = bottom + alt;
    let rho = (alt * (2.0 * bottom + alt)).sqrt();
    let rho2_low = (rho - r * mu.abs()) * (rho + r * mu.abs());
    let r_low = (rho2_low + bottom * bottom).max(0.0).sqrt();
    (rho2_low, rho2_low / (r_low + bottom))
}

#[cfg(test)]
mod tests;
