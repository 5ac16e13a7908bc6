//! The physical atmosphere model, in double precision: density profiles
//! (exponential Rayleigh and Mie, the ozone tent), extinction, the phase
//! functions and cancellation-free ray–sphere intersection.
//!
//! Single scattering only. The sun is a point for lighting (a sample is lit
//! when the ray from it towards the sun's centre misses the planet: a hard
//! planet shadow, no partial disc), and a disc of the given angular radius
//! only when seen directly.
//!
//! [`reference`](mod@reference) integrates the model adaptively (the oracle of the tests);
//! [`table`] bakes the optical-depth table the GPU pass samples;
//! [`ozone`] integrates the ozone layer along a ray in closed form;
//! [`coefficients`] derives scattering coefficients from physical
//! quantities (the seed's optional Rayleigh and Mie formulas).

pub mod coefficients;
pub mod ozone;
pub mod reference;
pub mod table;

use glam::DVec3;
use std::f64::consts::PI;

pub use crate::scene::{Atmosphere, Sky, Sun};
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
}

/// The sun's light on an object at `point` (world space): a directional
/// light along `sun.direction` whose colour is the irradiance at the top of
/// the atmosphere times the transmittance from `point` to the top towards
/// the sun, zero in the planet's shadow ([`reference::sun_transmittance`],
/// in f64).
///
/// The renderer evaluates it once per object, at the centre of its
/// bounding sphere, so one object is lit by one colour: exact for objects
/// small against the scale heights; across a 20 m sphere under a sun 1°
/// above the horizon the transmittance varies by a few per cent in blue
/// (see `tests.rs`, `sun_light_varies_little_across_a_small_object`).
pub fn sun_light_at(sky: &Sky, point: DVec3) -> DVec3 {
    sky.sun.irradiance
        * reference::sun_transmittance(
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
