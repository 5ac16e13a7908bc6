//! [`OpticalDepthTable`]: the density integrals from a point to the top of
//! the atmosphere (Rayleigh, Mie, ozone; metres), over altitude × the
//! cosine of the zenith angle of the direction, as 32-bit floats, baked in
//! double precision on the CPU (both cores).
//!
//! Mapping `horizon` (after Bruneton 2017's transmittance table, split at
//! the horizontal). All rows but the last hold *upward* directions only
//! (μ ≥ 0): x_μ = (d − d_min)/(d_max − d_min), with d the distance to the
//! top, d_min = R_top − r (straight up) and d_max = √(R_top² − r²)
//! (horizontal). The last row holds the horizontal ray alone, F(h), over
//! all W texels. A downward ray that misses the ground passes its lowest
//! point, at radius r·√(1 − μ²), and climbs back: its optical depth is
//! 2·F(lowest point) − (the upward ray from r at −μ), because the stretch
//! before the lowest point mirrors the stretch of the horizontal ray from
//! the lowest point that the upward ray skips. Rows and the last row's
//! columns follow the altitude axis of [`altitude_of_unit`].
//!
//! Why: one 2D table over all directions must follow, across the
//! horizon, the optical depth of rays that skim the ground, which changes
//! steeply with the direction; split, those rays come from the 1D row,
//! indexed by their lowest point, and the 2D part only holds rays that
//! climb. Measured at 256 × 64 with manual bilinear filtering, over
//! 300 × 600 rays that miss the ground: max transmittance error 7.0e-5,
//! with ozone (in closed form) and without, where the single Bruneton
//! table had 1.8e-4 without ozone. The
//! ozone channel is still baked, but its tent's kinks defeat any texel
//! grid (up to 2.6e-3 at 256 × 64); the pass integrates ozone in closed
//! form instead ([`super::ozone`]), unless `od_ozone = "table"`.
//!
//! Only directions that miss the ground are looked up: a direction into
//! the planet is shadowed by an explicit test rather than an infinite
//! value a filter would smear. Texel centres sit on x = 0 and x = 1
//! exactly (u = (x·(W−1) + 0.5)/W), so the ground, the top, the zenith
//! and the horizontal are sampled without extrapolation.
//!
//! The table spans the altitudes up to [`Atmosphere::effective_top_radius`]
//! (the `top_radius`, or where a tall atmosphere's air ends).
//!
//! `seed` is the linear altitude × linear cosine mapping over all W × H
//! texels, for comparison (rays below the horizon are clamped to it).
//!
//! Sampling is manual bilinear from four texel fetches, the same
//! arithmetic here ([`OpticalDepthTable::lookup`]) as in
//! `glsl/include/atmosphere.glsl`.

use super::quadrature::densities_to_top;
use super::{Atmosphere, Densities};
use glam::DVec3;

pub use super::model::{OzoneDepth, TableMapping};

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
}

impl Frame {
    /// The frame spans the atmosphere up to its effective top: a tall
    /// atmosphere's rows and columns then sample the air rather than the
    /// empty shell above it (the column from above the cut is below
    /// [`super::CUT_TOLERANCE`]; lookups there clamp to the top row).
    fn new(a: &Atmosphere) -> Frame {
        Frame {
            bottom: a.bottom_radius,
            top: a.effective_top_radius(),
        }
    }

    fn thickness(&self) -> f64 {
        self.top - self.bottom
    }

    /// ρ = √(r² − R²) at altitude `alt`, without a planet-scale difference.
    fn rho(&self, alt: f64) -> f64 {
        (alt * (2.0 * self.bottom + alt)).sqrt()
    }

    /// Distance from radius `r` along cosine `mu` to the top sphere.
    fn distance_to_top(&self, r: f64, mu: f64) -> f64 {
        let disc = (self.top - r) * (self.top + r) + r * r * mu * mu;
        (-r * mu + disc.max(0.0).sqrt()).max(0.0)
    }

    /// Radius, and the shortest (straight up) and longest (horizontal)
    /// upward distances to the top, at altitude `alt`.
    fn upward_range(&self, alt: f64) -> (f64, f64, f64) {
        let r = self.bottom + alt;
        let d_min = self.thickness() - alt;
        let d_max = ((self.top - r) * (self.top + r)).max(0.0).sqrt();
        (r, d_min, d_max)
    }

    /// x_μ in [0, 1] of an upward cosine `mu` ≥ 0 at altitude `alt`.
    fn upward_unit(&self, alt: f64, mu: f64) -> f64 {
        let (r, d_min, d_max) = self.upward_range(alt);
        if d_max > d_min {
            ((self.distance_to_top(r, mu) - d_min) / (d_max - d_min)).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// Inverse of [`Frame::upward_unit`]: the cosine.
    fn upward_cosine(&self, alt: f64, x_mu: f64) -> f64 {
        let (r, d_min, d_max) = self.upward_range(alt);
        let d = d_min + x_mu * (d_max - d_min).max(0.0);
        if d == 0.0 {
            1.0
        } else {
            // |p + d·ω| = R_top: d² + 2 r d μ + r² = R_top².
            (((self.top - r) * (self.top + r) - d * d) / (2.0 * r * d)).clamp(0.0, 1.0)
        }
    }
}

/// The altitude axis of the upward part's rows and of the horizontal row's
/// columns: altitude h = top · x² / (x² + (1 − x)²) for x ∈ [0, 1].
///
/// Texels crowd towards both ends, as h ∝ x² near the ground and
/// top − h ∝ (1 − x)² near the top. Near the ground the optical depth
/// changes fastest (a ρ-linear axis, Bruneton's, does the same there).
/// Near the top a horizontal ray's path to the top grows as √(top − h),
/// which no linear filter follows on a ρ-linear axis (measured: 1.9e-3
/// transmittance error at 59 km), and which this axis makes linear in x.
/// Its inverse, √q / (√q + √(1 − q)) with q = h / top, costs two square
/// roots and a division per lookup (an `asin` axis with the same ends cost
/// the shader about 15 % more).
fn altitude_of_unit(thickness: f64, x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    thickness * x * x / (x * x + (1.0 - x) * (1.0 - x))
}

/// Inverse of [`altitude_of_unit`].
fn unit_of_altitude(thickness: f64, alt: f64) -> f64 {
    let q = (alt / thickness).clamp(0.0, 1.0);
    q.sqrt() / (q.sqrt() + (1.0 - q).sqrt())
}

/// The stored form of the density integrals `d` from altitude `alt`.
fn encode(atmosphere: &Atmosphere, alt: f64, d: Densities) -> [f32; 4] {
    // Logarithms plus h/H: the optical depth falls roughly as exp(-h/H)
    // with the texel's own altitude h (rows are linear in sqrt(h), not h),
    // and near the horizontal it is roughly exponential in the altitude.
    // What is left is nearly linear in both texel coordinates, which
    // bilinear filtering follows; LOG_OFFSET keeps a path of length 0
    // finite.
    [
        ((d.rayleigh + LOG_OFFSET).ln() + alt / atmosphere.rayleigh_scale_height) as f32,
        ((d.mie + LOG_OFFSET).ln() + alt / atmosphere.mie_scale_height) as f32,
        d.ozone as f32,
        0.0,
    ]
}

/// Inverse of [`encode`] for a filtered value `v` at altitude `alt`.
fn decode(atmosphere: &Atmosphere, alt: f64, v: [f64; 3]) -> Densities {
    Densities {
        rayleigh: ((v[0] - alt / atmosphere.rayleigh_scale_height).exp() - LOG_OFFSET).max(0.0),
        mie: ((v[1] - alt / atmosphere.mie_scale_height).exp() - LOG_OFFSET).max(0.0),
        ozone: v[2],
    }
}

impl OpticalDepthTable {
    /// Bakes the table for `atmosphere`, every texel integrated with the
    /// reference quadrature, rows split between two threads. `height` is
    /// at least 3 (the scene's validation says so).
    pub fn bake(
        atmosphere: &Atmosphere,
        width: u32,
        height: u32,
        mapping: TableMapping,
    ) -> OpticalDepthTable {
        let started = std::time::Instant::now();
        let (w, h) = (width.max(2) as usize, height.max(3) as usize);
        let frame = Frame::new(atmosphere);
        // Texels integrate up to the effective top, as the pass sees the
        // atmosphere: what lies above it is below CUT_TOLERANCE, and a
        // tall atmosphere's texels then cost what a default one's do
        // (integrated to the nominal top, the reference's own cut at
        // 1e-12 took them 280 km up and the bake 1.5 times as long).
        let effective = atmosphere.effective();
        // The ray (altitude, cosine) of texel (x, y).
        let ray = |x: usize, y: usize| -> (f64, f64) {
            let u = x as f64 / (w - 1) as f64;
            match mapping {
                TableMapping::Horizon if y == h - 1 => {
                    (altitude_of_unit(frame.thickness(), u), 0.0)
                }
                TableMapping::Horizon => {
                    let alt = altitude_of_unit(frame.thickness(), y as f64 / (h - 2) as f64);
                    (alt, frame.upward_cosine(alt, u))
                }
                TableMapping::Linear => {
                    let alt = y as f64 / (h - 1) as f64 * frame.thickness();
                    // Directions into the ground hold the horizon's value
                    // (the pass shadows them before looking them up).
                    let horizon = -frame.rho(alt) / (frame.bottom + alt);
                    (alt, (1.0 - 2.0 * u).max(horizon))
                }
            }
        };
        let row = |y: usize| -> Vec<[f32; 4]> {
            (0..w)
                .map(|x| {
                    let (alt, mu) = ray(x, y);
                    let r = atmosphere.bottom_radius + alt;
                    let p = DVec3::new(0.0, r, 0.0);
                    let dir = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), mu, 0.0);
                    // Exactly on the horizon the ground test may round either
                    // way; the grazing integral is finite, so take it.
                    let d = densities_to_top(&effective, p, dir).unwrap_or_else(|| {
                        let d = frame.distance_to_top(r, mu);
                        super::quadrature::densities_between(&effective, p, p + d * dir)
                    });
                    encode(atmosphere, alt, d)
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

    /// Bilinear filter of the first three channels at texel coordinates
    /// (`fx`, `fy`), between rows `first_row` and `last_row` (equal: that
    /// row alone), as `table_texels` and `table_row` in the shader.
    fn filtered(&self, fx: f64, fy: f64, first_row: usize, last_row: usize) -> [f64; 3] {
        let w = self.width as usize;
        let x0 = (fx.floor().max(0.0) as usize).min(w - 2);
        let y0 = (fy.floor().max(0.0) as usize)
            .clamp(first_row, last_row.saturating_sub(1).max(first_row));
        let y1 = (y0 + 1).min(last_row);
        let (ax, ay) = (fx - x0 as f64, (fy - y0 as f64).clamp(0.0, 1.0));
        let texel = |x: usize, y: usize| self.texels[y * w + x];
        let mut out = [0f64; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let t00 = f64::from(texel(x0, y0)[c]);
            let t10 = f64::from(texel(x0 + 1, y0)[c]);
            let t01 = f64::from(texel(x0, y1)[c]);
            let t11 = f64::from(texel(x0 + 1, y1)[c]);
            *o = (t00 * (1.0 - ax) + t10 * ax) * (1.0 - ay) + (t01 * (1.0 - ax) + t11 * ax) * ay;
        }
        out
    }

    /// Density integrals to the top from altitude `alt` along cosine `mu`,
    /// by manual bilinear filtering of four texels (as the shader does).
    /// Directions into the ground must be handled by the caller.
    pub fn lookup(&self, atmosphere: &Atmosphere, alt: f64, mu: f64) -> Densities {
        let frame = Frame::new(atmosphere);
        let alt = alt.clamp(0.0, frame.thickness());
        let (w, h) = (self.width as usize, self.height as usize);
        let last = (w - 1) as f64;
        match self.mapping {
            TableMapping::Linear => {
                let fx = ((1.0 - mu) * 0.5).clamp(0.0, 1.0) * last;
                let fy = alt / frame.thickness() * (h - 1) as f64;
                decode(atmosphere, alt, self.filtered(fx, fy, 0, h - 1))
            }
            TableMapping::Horizon => {
                let upward = |mu: f64| {
                    let fx = frame.upward_unit(alt, mu) * last;
                    let fy = unit_of_altitude(frame.thickness(), alt) * (h - 2) as f64;
                    decode(atmosphere, alt, self.filtered(fx, fy, 0, h - 2))
                };
                if mu >= 0.0 {
                    return upward(mu);
                }
                // Down to the lowest point (above the ground, as the ray
                // misses it) and back up.
                let (_, alt_low) = super::lowest_point(frame.bottom, alt, mu);
                let alt_low = alt_low.max(0.0);
                let fx = unit_of_altitude(frame.thickness(), alt_low) * last;
                let horizontal = decode(
                    atmosphere,
                    alt_low,
                    self.filtered(fx, (h - 1) as f64, h - 1, h - 1),
                );
                let up = upward(-mu);
                Densities {
                    rayleigh: (2.0 * horizontal.rayleigh - up.rayleigh).max(0.0),
                    mie: (2.0 * horizontal.mie - up.mie).max(0.0),
                    ozone: (2.0 * horizontal.ozone - up.ozone).max(0.0),
                }
            }
        }
    }

    /// The density integrals the atmosphere pass uses towards the sun from
    /// altitude `alt` along cosine `mu`: Rayleigh and Mie from the table,
    /// ozone as `ozone` says.
    pub fn densities(
        &self,
        atmosphere: &Atmosphere,
        alt: f64,
        mu: f64,
        ozone: OzoneDepth,
    ) -> Densities {
        let mut d = self.lookup(atmosphere, alt, mu);
        if ozone == OzoneDepth::Exact {
            d.ozone = super::ozone::ozone_to_top(atmosphere, alt, mu);
        }
        d
    }
}
