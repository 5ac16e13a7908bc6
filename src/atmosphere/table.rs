//! [`OpticalDepthTable`]: the density integrals from a point to the top of
//! the atmosphere (Rayleigh, Mie, ozone; metres), over altitude × the
//! cosine of the zenith angle of the direction, as 32-bit floats, baked in
//! double precision on the CPU (both cores).
//!
//! Mapping (`horizon`, after Bruneton 2017's transmittance table): with
//! H = √(R_top² − R²), ρ = √(r² − R²) and d the distance to the top along
//! the direction, x_r = ρ/H and x_μ = (d − d_min)/(d_max − d_min) with
//! d_min = R_top − r, d_max = ρ + H. Only directions that miss the ground
//! are in the table (x_μ = 1 is the horizon), so texels are spent where
//! the optical depth changes fastest, and a direction into the planet is
//! shadowed by an explicit test rather than an infinite value a filter
//! would smear. Texel centres sit on x = 0 and x = 1 exactly
//! (u = (x·(W−1) + 0.5)/W), so the ground, the top and the horizon are
//! sampled without extrapolation. `seed` is the linear altitude × linear cosine mapping,
//! for comparison (rays below the horizon are clamped to it).
//!
//! Sampling is manual bilinear from four texel fetches, the same
//! arithmetic here ([`OpticalDepthTable::lookup`]) as in
//! `glsl/atmosphere.frag`.

use super::reference::densities_to_top;
use super::{Atmosphere, Densities};
use glam::DVec3;

pub use crate::scene::TableMapping;

/// Added to the Rayleigh and Mie density integrals (metres) before their
/// logarithm is stored: 1 m of ground-level air is an optical depth of
/// 3e-5 at most (Earth's blue), far below the table's error.
pub const LOG_OFFSET: f64 = 1.0;

/// Density integrals to the top of the atmosphere, `width` (direction) ×
/// `height` (altitude) texels, RGBA: ln(Rayleigh + LOG_OFFSET) + h/H_R,
/// ln(Mie + LOG_OFFSET) + h/H_M (h the texel's altitude), ozone, unused.
#[derive(Clone, Debug)]
pub struct OpticalDepthTable {
    pub width: u32,
    pub height: u32,
    pub mapping: TableMapping,
    /// Row-major, `height` rows of `width` texels.
    pub texels: Vec<[f32; 4]>,
    /// Wall-clock bake time in seconds.
    pub bake_seconds: f64,
}

/// Geometry of the mapping for one atmosphere.
struct Frame {
    bottom: f64,
    top: f64,
    h: f64,
}

impl Frame {
    fn new(a: &Atmosphere) -> Frame {
        Frame {
            bottom: a.bottom_radius,
            top: a.top_radius,
            h: ((a.top_radius - a.bottom_radius) * (a.top_radius + a.bottom_radius)).sqrt(),
        }
    }

    /// Distance from radius `r` along cosine `mu` to the top sphere.
    fn distance_to_top(&self, r: f64, mu: f64) -> f64 {
        let disc = (self.top - r) * (self.top + r) + r * r * mu * mu;
        (-r * mu + disc.max(0.0).sqrt()).max(0.0)
    }

    /// (x_mu, x_r) in [0, 1]² for altitude `alt` and cosine `mu`.
    fn to_unit(&self, mapping: TableMapping, alt: f64, mu: f64) -> (f64, f64) {
        let alt = alt.clamp(0.0, self.top - self.bottom);
        let r = self.bottom + alt;
        match mapping {
            TableMapping::Horizon => {
                let rho = (alt * (2.0 * self.bottom + alt)).sqrt();
                let d = self.distance_to_top(r, mu);
                let d_min = (self.top - self.bottom) - alt;
                let d_max = rho + self.h;
                let x_mu = if d_max > d_min {
                    (d - d_min) / (d_max - d_min)
                } else {
                    0.0
                };
                (x_mu.clamp(0.0, 1.0), rho / self.h)
            }
            TableMapping::Seed => ((1.0 - mu) * 0.5, alt / (self.top - self.bottom)),
        }
    }

    /// Inverse of `Frame::to_unit`: (altitude, mu).
    fn unit_to_ray(&self, mapping: TableMapping, x_mu: f64, x_r: f64) -> (f64, f64) {
        match mapping {
            TableMapping::Horizon => {
                let rho = self.h * x_r;
                let r = (rho * rho + self.bottom * self.bottom).sqrt();
                let alt = (rho * rho / (r + self.bottom)).min(self.top - self.bottom);
                let d_min = (self.top - self.bottom) - alt;
                let d_max = rho + self.h;
                let d = d_min + x_mu * (d_max - d_min);
                let mu = if d == 0.0 {
                    1.0
                } else {
                    ((self.h * self.h - rho * rho - d * d) / (2.0 * r * d)).clamp(-1.0, 1.0)
                };
                (alt, mu)
            }
            TableMapping::Seed => (x_r * (self.top - self.bottom), 1.0 - 2.0 * x_mu),
        }
    }
}

impl OpticalDepthTable {
    /// Bakes the table for `atmosphere`, every texel integrated with the
    /// reference quadrature, rows split between two threads.
    pub fn bake(
        atmosphere: &Atmosphere,
        width: u32,
        height: u32,
        mapping: TableMapping,
    ) -> OpticalDepthTable {
        let started = std::time::Instant::now();
        let (w, h) = (width.max(2) as usize, height.max(2) as usize);
        let frame = Frame::new(atmosphere);
        let row = |y: usize| -> Vec<[f32; 4]> {
            (0..w)
                .map(|x| {
                    let x_mu = x as f64 / (w - 1) as f64;
                    let x_r = y as f64 / (h - 1) as f64;
                    let (alt, mu) = frame.unit_to_ray(mapping, x_mu, x_r);
                    let r = atmosphere.bottom_radius + alt;
                    // The seed's mapping also has directions into the
                    // ground: they hold the horizon's value (the pass
                    // shadows them before looking them up).
                    let horizon = -(alt * (2.0 * atmosphere.bottom_radius + alt)).sqrt() / r;
                    let mu = mu.max(horizon);
                    let p = DVec3::new(0.0, r, 0.0);
                    let dir = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), mu, 0.0);
                    // Exactly on the horizon the ground test may round either
                    // way; the grazing integral is finite, so take it.
                    let d = densities_to_top(atmosphere, p, dir).unwrap_or_else(|| {
                        let d = frame.distance_to_top(r, mu);
                        super::reference::densities_between(atmosphere, p, p + d * dir)
                    });
                    // Logarithms plus h/H: near the horizon the optical
                    // depth is roughly exponential in the altitude of the
                    // ray's lowest point, and it falls as exp(-h/H) with
                    // the texel's own altitude h (rows are linear in
                    // sqrt(h), not h). What is left is nearly linear in
                    // both texel coordinates, which bilinear filtering
                    // follows; LOG_OFFSET keeps a path of length 0 finite.
                    [
                        ((d.rayleigh + LOG_OFFSET).ln() + alt / atmosphere.rayleigh_scale_height)
                            as f32,
                        ((d.mie + LOG_OFFSET).ln() + alt / atmosphere.mie_scale_height) as f32,
                        d.ozone as f32,
                        0.0,
                    ]
                })
                .collect()
        };
        let half = h / 2;
        let (low, high) = std::thread::scope(|s| {
            let low = s.spawn(|| (0..half).flat_map(row).collect::<Vec<_>>());
            let high: Vec<_> = (half..h).flat_map(row).collect();
            (low.join().expect("table bake thread"), high)
        });
        let mut texels = low;
        texels.extend(high);
        OpticalDepthTable {
            width: w as u32,
            height: h as u32,
            mapping,
            texels,
            bake_seconds: started.elapsed().as_secs_f64(),
        }
    }

    /// Bytes of the table.
    pub fn bytes(&self) -> usize {
        self.texels.len() * 16
    }

    /// Density integrals to the top from altitude `alt` along cosine `mu`,
    /// by manual bilinear filtering of four texels (as the shader does).
    /// Directions into the ground must be handled by the caller.
    pub fn lookup(&self, atmosphere: &Atmosphere, alt: f64, mu: f64) -> Densities {
        let frame = Frame::new(atmosphere);
        let (x_mu, x_r) = frame.to_unit(self.mapping, alt, mu);
        let fx = x_mu * (self.width - 1) as f64;
        let fy = x_r * (self.height - 1) as f64;
        let x0 = (fx.floor() as usize).min(self.width as usize - 2);
        let y0 = (fy.floor() as usize).min(self.height as usize - 2);
        let (ax, ay) = (fx - x0 as f64, fy - y0 as f64);
        let texel = |x: usize, y: usize| self.texels[y * self.width as usize + x];
        let mut out = [0f64; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let t00 = f64::from(texel(x0, y0)[c]);
            let t10 = f64::from(texel(x0 + 1, y0)[c]);
            let t01 = f64::from(texel(x0, y0 + 1)[c]);
            let t11 = f64::from(texel(x0 + 1, y0 + 1)[c]);
            *o = (t00 * (1.0 - ax) + t10 * ax) * (1.0 - ay) + (t01 * (1.0 - ax) + t11 * ax) * ay;
        }
        let alt = alt.clamp(0.0, atmosphere.top_radius - atmosphere.bottom_radius);
        Densities {
            rayleigh: ((out[0] - alt / atmosphere.rayleigh_scale_height).exp() - LOG_OFFSET)
                .max(0.0),
            mie: ((out[1] - alt / atmosphere.mie_scale_height).exp() - LOG_OFFSET).max(0.0),
            ozone: out[2],
        }
    }
}
