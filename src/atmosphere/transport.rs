//! Full light transport in double precision: the radiance reaching a point
//! with every order of scattering and of ground reflection, the reference
//! that single scattering ([`reference`](mod@super::reference)) is a part
//! of.
//!
//! # What it covers
//! The model of [`Atmosphere`] and [`Sun`] exactly as the single-scattering
//! reference reads it: exponential Rayleigh and Mie density profiles, the
//! ozone tent (absorbing only), Rayleigh scattering with its phase function,
//! Mie scattering with the Cornette–Shanks phase function of `mie_g` and
//! absorption `mie_extinction − mie_scattering`, a Lambertian ground of
//! `ground_albedo`, and a point sun of irradiance `sun.irradiance` along
//! `sun.direction` whose light is cut off by the planet (the hard shadow).
//! Light may scatter or reflect any number of times in any order: sky light
//! on the ground, ground light in the sky, the ground seen through the air
//! lit by either. The top of the air is the reference's own
//! ([`reference::REFERENCE_CUT`]): `top_radius`, or lower where a tall
//! atmosphere holds a negligible column above.
//!
//! # What it leaves out
//! Polarisation (Rayleigh light is partly polarised, which changes second
//! and higher orders by a few per cent at most; the model has no Stokes
//! vector); the sun's disc for lighting (the sun is a point, as in the
//! single-scattering reference, and its disc seen directly, order zero, is
//! not part of any radiance here); refraction (rays are straight); any
//! spectral resolution beyond the model's three wavelengths (each channel
//! is a monochromatic problem of its own); a non-Lambertian ground; light
//! from anything but the sun (no stars, moon or airglow).
//!
//! # Estimator
//! The radiance along a ray is split as L = L₁ + L≥₂. L₁ (light that
//! scattered once in the air or reflected once on the ground) is
//! [`reference::radiance`] itself, the adaptive quadrature to 1e-7, so the
//! single-scattering part of [`full_radiance`] *is* today's integral.
//!
//! L≥₂ is an unbiased Monte Carlo estimate, with its standard error, by
//! backward path tracing from the viewer, one channel at a time (each
//! channel's coefficients are those of a grey medium; a path never mixes
//! them):
//! - *Free flight by delta tracking* against piecewise-constant majorants:
//!   the ray's stretch inside the air is cut at the point nearest the
//!   planet's centre and then into stretches of doubling length away from
//!   it (the first one [`first_piece`]-long), so the altitude is monotonic
//!   on each stretch and its lowest and highest points bound the densities:
//!   the exponentials by their value at the lowest point, the ozone tent by
//!   its largest value between the two. A tentative collision at x is real
//!   with probability σₜ(x)/σ̄; then the path's weight is multiplied by the
//!   single-scattering albedo σₛ(x)/σₜ(x) (absorption by ozone and Mie) and
//!   it scatters. Delta tracking needs no optical depth at all, so no
//!   quadrature error enters the multiple-scattering part.
//! - *Next-event estimation* towards the sun at every vertex from the
//!   second on (the first vertex's is L₁): the phase function (or
//!   albedo/π·cos at the ground) times the sun's transmittance, zero in the
//!   planet's shadow. The transmittance is estimated without bias by ratio
//!   tracking against the same majorants: the product of 1 − σₜ(xᵢ)/σ̄ over
//!   the tentative collisions.
//! - *New directions* are drawn from the scattering event's own density:
//!   Rayleigh or Mie in proportion to their scattering coefficients at x,
//!   the Rayleigh phase function by rejection from the uniform sphere
//!   (acceptance (1 + μ²)/2) and Cornette–Shanks by rejection from
//!   Henyey–Greenstein of the same g (Cornette–Shanks is HG·(1 + μ²)·const,
//!   so the same acceptance), so a scattering leaves the weight unchanged; at
//!   the ground a cosine-weighted direction, weight × albedo.
//! - *Russian roulette* once the weight falls below [`ROULETTE_WEIGHT`]:
//!   the path survives with probability weight/[`ROULETTE_WEIGHT`] and then
//!   carries exactly that weight, so the expectation is unchanged.
//!   `max_order` cuts every path after that many events (a deliberate
//!   truncation; [`UNLIMITED`] leaves it to roulette and escape).
//!
//! The standard error is the sample standard deviation of the per-path
//! estimates over √paths, per channel. Paths are split into fixed blocks
//! whose random streams derive from (seed, path, channel) by SplitMix64, and
//! the blocks are summed in their order whatever the number of threads, so
//! a seed gives the same bits on any machine.
//!
//! # Bias
//! - The multiple-scattering part: none from the estimator (delta and ratio
//!   tracking, exact sampling, roulette are unbiased); the majorant of a
//!   stretch is taken a millimetre below its lowest point, so rounding of
//!   an altitude (~1e-9 m) cannot push a density above it.
//! - The single-scattering part: the reference's 1e-7 relative tolerance.
//! - The top of the air ([`reference::REFERENCE_CUT`], below 1e-12 of the
//!   column) and `max_order` when finite: the tail beyond order N is about
//!   by_order[N]·q/(1 − q) with q the ratio of successive orders (0.1–0.5 in
//!   Earth's air; see the tests).
//!
//! All of it is checked in the tests below: energy conservation over an
//! albedo-1 ground, the single-scattering part against the quadrature, the
//! Monte Carlo's own order 1 against the quadrature, the transmittance
//! estimator against [`reference::densities_to_top`], orders 1 and 2 of a
//! thin homogeneous slab against an independent quadrature, the order
//! count, and the multiple-to-single ratios of Earth's sky.

use super::{
    cornette_shanks_phase, hits_ground, ray_sphere, rayleigh_phase, reference, Atmosphere, Sun,
};
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// `max_order` that leaves the number of events to Russian roulette and to
/// the paths' escape.
pub const UNLIMITED: u32 = u32::MAX;

/// Weight below which a path plays Russian roulette.
pub const ROULETTE_WEIGHT: f64 = 0.25;

/// Paths per block of the deterministic split over threads.
const BLOCK: u32 = 64;

/// How much work an estimate does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TransportSettings {
    /// Paths per channel.
    pub paths: u32,
    /// Seed of the random streams: the same seed gives the same estimate.
    pub seed: u64,
    /// Highest order of scattering counted (1: single scattering only);
    /// [`UNLIMITED`] for all of them.
    pub max_order: u32,
}

impl Default for TransportSettings {
    fn default() -> Self {
        TransportSettings {
            paths: 1 << 16,
            seed: 0,
            max_order: UNLIMITED,
        }
    }
}

/// The radiance along one ray, per channel, in the units of
/// [`reference::radiance`].
#[derive(Clone, Debug, PartialEq)]
pub struct TransportEstimate {
    /// `single + multiple`: all orders up to `max_order`.
    pub radiance: DVec3,
    /// Order 1: [`reference::radiance`] (single scattering and the sun-lit
    /// ground), exact to its quadrature's tolerance.
    pub single: DVec3,
    /// Orders 2 to `max_order`: the Monte Carlo estimate.
    pub multiple: DVec3,
    /// Standard error of `multiple` (and so of `radiance`).
    pub std_error: DVec3,
    /// The radiance of each order: `by_order[0]` is `single`, `by_order[k]`
    /// the estimate of order k + 1, up to the highest order any path
    /// reached; they sum to `radiance`.
    pub by_order: Vec<DVec3>,
}

/// Radiance reaching `origin` (relative to the planet centre) from
/// `direction` (pointing away from the viewer) with every order of
/// scattering and ground reflection up to `settings.max_order`; the sun's
/// disc (order zero) is not included, as in [`reference::radiance`].
pub fn full_radiance(
    atmosphere: &Atmosphere,
    sun: &Sun,
    origin: DVec3,
    direction: DVec3,
    settings: TransportSettings,
) -> TransportEstimate {
    let direction = direction.normalize();
    let single = if settings.max_order >= 1 {
        reference::radiance(atmosphere, sun, origin, direction)
    } else {
        DVec3::ZERO
    };
    let medium = Medium::new(atmosphere, sun);
    let tally = estimate(&medium, settings, 2, &|_: &mut Rng| {
        (origin, direction, 1.0)
    });
    let (multiple, std_error) = tally.mean_and_error();
    let mut by_order = vec![single];
    by_order.extend(tally.orders.iter().skip(1).map(|o| tally.per_path(*o)));
    TransportEstimate {
        radiance: single + multiple,
        single,
        multiple,
        std_error,
        by_order,
    }
}

/// Irradiance from the sky on a surface at `point` (relative to the planet
/// centre) facing `normal`: the cosine-weighted integral over the
/// hemisphere of the radiance of every order from 1 to `settings.max_order`
/// (so the sky and, for a tilted surface, the ground), without the sun's
/// direct light. Returns the irradiance and its standard error, per
/// channel, in the units of `sun.irradiance`. A point below the ground is
/// taken on the ground above it (as in [`reference::sun_transmittance`]);
/// directions below the horizon of a point on the ground see the ground at
/// that very point.
pub fn sky_irradiance(
    atmosphere: &Atmosphere,
    sun: &Sun,
    point: DVec3,
    normal: DVec3,
    settings: TransportSettings,
) -> (DVec3, DVec3) {
    let medium = Medium::new(atmosphere, sun);
    let point = medium.lift(point);
    let normal = normal.normalize();
    let tally = estimate(&medium, settings, 1, &|rng: &mut Rng| {
        (point, cosine_direction(normal, rng), PI)
    });
    tally.mean_and_error()
}

/// The length of the first stretch of constant majorant on each side of a
/// ray's lowest point: half the smaller scale height. Later stretches double.
pub fn first_piece(atmosphere: &Atmosphere) -> f64 {
    0.5 * atmosphere
        .rayleigh_scale_height
        .min(atmosphere.mie_scale_height)
}

/// A deterministic random stream: SplitMix64 (Steele, Lea and Flood 2014),
/// started from a hash of the seed, the path and the channel.
struct Rng(u64);

impl Rng {
    fn new(seed: u64, path: u64, channel: u64) -> Rng {
        let mut r = Rng(seed);
        let a = r.next_u64();
        let mut r = Rng(a ^ path.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let b = r.next_u64();
        Rng(b ^ channel.wrapping_mul(0xABC9_8388_FB8F_AC03))
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// An exponential variate of mean 1.
    fn exponential(&mut self) -> f64 {
        -(1.0 - self.uniform()).ln()
    }
}

/// One channel's coefficients.
#[derive(Clone, Copy, Debug)]
struct Channel {
    rayleigh: f64,
    mie_scattering: f64,
    mie_extinction: f64,
    ozone: f64,
    albedo: f64,
    irradiance: f64,
}

/// The atmosphere and sun as the paths see them.
struct Medium<'a> {
    atmosphere: &'a Atmosphere,
    channels: [Channel; 3],
    bottom: f64,
    /// The top of the air: the reference's cut.
    top: f64,
    sun: DVec3,
    piece: f64,
}

/// What ends a free flight.
enum Event {
    Escape,
    Ground(DVec3),
    Scatter(DVec3, f64, f64),
}

/// Stretches of one ray with a constant majorant each: their boundaries
/// in increasing distance.
struct Pieces {
    bounds: [f64; 72],
    count: usize,
}

impl Pieces {
    fn push(&mut self, t: f64) {
        self.bounds[self.count] = t;
        self.count += 1;
    }
}

impl<'a> Medium<'a> {
    fn new(atmosphere: &'a Atmosphere, sun: &Sun) -> Medium<'a> {
        let cut = atmosphere.negligible_altitude(reference::REFERENCE_CUT);
        let top = atmosphere
            .top_radius
            .min(atmosphere.bottom_radius + cut)
            .max(atmosphere.bottom_radius);
        let channel = |i: usize| Channel {
            rayleigh: atmosphere.rayleigh_scattering[i],
            mie_scattering: atmosphere.mie_scattering[i],
            mie_extinction: atmosphere.mie_extinction[i],
            ozone: atmosphere.ozone_absorption[i],
            albedo: atmosphere.ground_albedo[i],
            irradiance: sun.irradiance[i],
        };
        Medium {
            atmosphere,
            channels: [channel(0), channel(1), channel(2)],
            bottom: atmosphere.bottom_radius,
            top,
            sun: sun.direction.normalize(),
            piece: first_piece(atmosphere).max(1e-3),
        }
    }

    /// `p`, or the point on the ground above it (a hair above, so that the
    /// horizon test sees the upper hemisphere) when it lies below.
    fn lift(&self, p: DVec3) -> DVec3 {
        let floor = self.bottom * (1.0 + 1e-12);
        let r = p.length();
        if r < floor {
            if r > 0.0 {
                p * (floor / r)
            } else {
                DVec3::new(0.0, floor, 0.0)
            }
        } else {
            p
        }
    }

    fn altitude(&self, x: DVec3) -> f64 {
        (x.length() - self.bottom).max(0.0)
    }

    /// Extinction and scattering at altitude `h`, and the Rayleigh share of
    /// the scattering.
    fn coefficients(&self, c: &Channel, h: f64) -> (f64, f64, f64) {
        let d = self.atmosphere.densities(h);
        let rayleigh = c.rayleigh * d.rayleigh;
        let mie = c.mie_scattering * d.mie;
        let extinction = rayleigh + c.mie_extinction * d.mie + c.ozone * d.ozone;
        (extinction, rayleigh + mie, rayleigh)
    }

    fn extinction(&self, c: &Channel, h: f64) -> f64 {
        let d = self.atmosphere.densities(h);
        c.rayleigh * d.rayleigh + c.mie_extinction * d.mie + c.ozone * d.ozone
    }

    /// A bound on the extinction between altitudes `lo` and `hi`.
    fn majorant(&self, c: &Channel, lo: f64, hi: f64) -> f64 {
        let d = self.atmosphere.densities((lo - 1e-3).max(0.0));
        let [start, peak, end] = self.atmosphere.ozone_layer;
        let ozone = if c.ozone <= 0.0 || hi <= start || lo >= end {
            0.0
        } else if lo <= peak && peak <= hi {
            1.0
        } else {
            let tent = |h: f64| self.atmosphere.densities(h).ozone;
            tent(lo).max(tent(hi)) + 1e-12
        };
        c.rayleigh * d.rayleigh + c.mie_extinction * d.mie + c.ozone * ozone
    }

    /// The stretch of `p + t·d` (`d` unit) inside the air: its ends and
    /// whether it ends on the ground.
    fn segment(&self, p: DVec3, d: DVec3) -> Option<(f64, f64, bool)> {
        let (enter, leave) = ray_sphere(p, d, self.top)?;
        if leave <= 0.0 {
            return None;
        }
        let start = enter.max(0.0);
        if hits_ground(self.atmosphere, p, d) {
            let end = match ray_sphere(p, d, self.bottom) {
                Some((g, _)) => g,
                None => -p.dot(d),
            };
            Some((start, end.max(start), true))
        } else {
            Some((start, leave, false))
        }
    }

    fn pieces(&self, p: DVec3, d: DVec3, t0: f64, t1: f64) -> Pieces {
        let lowest = (-p.dot(d)).clamp(t0, t1);
        let step = self.piece.max((t1 - t0) * 1e-9);
        let at = |k: u32| step * ((1u64 << k) - 1) as f64;
        let mut pieces = Pieces {
            bounds: [0.0; 72],
            count: 0,
        };
        pieces.push(t0);
        // Before the lowest point: boundaries at lowest − step·(2^k − 1),
        // largest k first.
        let mut k = 0;
        while lowest - at(k + 1) > t0 {
            k += 1;
        }
        while k >= 1 {
            pieces.push(lowest - at(k));
            k -= 1;
        }
        if lowest > t0 {
            pieces.push(lowest);
        }
        let mut k = 1;
        while lowest + at(k) < t1 {
            pieces.push(lowest + at(k));
            k += 1;
        }
        if t1 > pieces.bounds[pieces.count - 1] {
            pieces.push(t1);
        }
        pieces
    }

    /// The majorant of the stretch [a, b] of `p + t·d` that lies on one
    /// side of the lowest point.
    fn piece_majorant(&self, c: &Channel, p: DVec3, d: DVec3, a: f64, b: f64) -> f64 {
        let (ha, hb) = (self.altitude(p + a * d), self.altitude(p + b * d));
        self.majorant(c, ha.min(hb), ha.max(hb))
    }

    /// Samples where the ray from `p` along `d` first interacts.
    fn free_flight(&self, c: &Channel, p: DVec3, d: DVec3, rng: &mut Rng) -> Event {
        let Some((t0, t1, ground)) = self.segment(p, d) else {
            return Event::Escape;
        };
        let pieces = self.pieces(p, d, t0, t1);
        for w in pieces.bounds[..pieces.count].windows(2) {
            let (a, b) = (w[0], w[1]);
            let majorant = self.piece_majorant(c, p, d, a, b);
            if majorant <= 0.0 {
                continue;
            }
            let mut t = a;
            loop {
                t += rng.exponential() / majorant;
                if t >= b {
                    break;
                }
                let x = p + t * d;
                let (extinction, scattering, rayleigh) = self.coefficients(c, self.altitude(x));
                if rng.uniform() * majorant < extinction {
                    return Event::Scatter(x, scattering / extinction, rayleigh / scattering);
                }
            }
        }
        if ground {
            let x = p + t1 * d;
            Event::Ground(self.lift(x))
        } else {
            Event::Escape
        }
    }

    /// An unbiased estimate (ratio tracking) of the transmittance from `p`
    /// towards the sun: zero when the planet is in the way.
    fn sun_transmittance(&self, c: &Channel, p: DVec3, rng: &mut Rng) -> f64 {
        let d = self.sun;
        if hits_ground(self.atmosphere, p, d) {
            return 0.0;
        }
        let Some((t0, t1, _)) = self.segment(p, d) else {
            return 1.0;
        };
        self.ratio_tracking(c, p, d, t0, t1, rng)
    }

    fn ratio_tracking(&self, c: &Channel, p: DVec3, d: DVec3, t0: f64, t1: f64, rng: &mut Rng) -> f64 {
        let pieces = self.pieces(p, d, t0, t1);
        let mut transmittance = 1.0;
        for w in pieces.bounds[..pieces.count].windows(2) {
            let (a, b) = (w[0], w[1]);
            let majorant = self.piece_majorant(c, p, d, a, b);
            if majorant <= 0.0 {
                continue;
            }
            let mut t = a;
            loop {
                t += rng.exponential() / majorant;
                if t >= b {
                    break;
                }
                let extinction = self.extinction(c, self.altitude(p + t * d));
                transmittance *= 1.0 - extinction / majorant;
            }
        }
        transmittance
    }

    /// One path of channel `c` from `origin` along `direction`: adds the
    /// radiance of each order from `first_order` to `max_order` (scaled by
    /// `factor`) to `orders` and returns their sum.
    #[allow(clippy::too_many_arguments)]
    fn walk(
        &self,
        c: usize,
        origin: DVec3,
        direction: DVec3,
        factor: f64,
        first_order: u32,
        max_order: u32,
        rng: &mut Rng,
        orders: &mut Vec<[f64; 3]>,
    ) -> f64 {
        let ch = &self.channels[c];
        let (mut p, mut d) = (origin, direction);
        let mut weight = factor;
        let mut total = 0.0;
        let mut order = 0u32;
        let mut add = |order: u32, value: f64, total: &mut f64| {
            let k = order as usize - 1;
            if orders.len() <= k {
                orders.resize(k + 1, [0.0; 3]);
            }
            orders[k][c] += value;
            *total += value;
        };
        while order < max_order {
            match self.free_flight(ch, p, d, rng) {
                Event::Escape => break,
                Event::Ground(x) => {
                    order += 1;
                    let normal = x.normalize();
                    if order >= first_order {
                        let cos = normal.dot(self.sun);
                        if cos > 0.0 {
                            let t = self.sun_transmittance(ch, x, rng);
                            let value = weight * ch.albedo / PI * cos * ch.irradiance * t;
                            add(order, value, &mut total);
                        }
                    }
                    weight *= ch.albedo;
                    p = x;
                    d = cosine_direction(normal, rng);
                }
                Event::Scatter(x, albedo, rayleigh_share) => {
                    order += 1;
                    weight *= albedo;
                    let g = self.atmosphere.mie_g;
                    if order >= first_order && !hits_ground(self.atmosphere, x, self.sun) {
                        let mu = d.dot(self.sun);
                        let phase = rayleigh_share * rayleigh_phase(mu)
                            + (1.0 - rayleigh_share) * cornette_shanks_phase(mu, g);
                        let t = self.sun_transmittance(ch, x, rng);
                        add(order, weight * phase * ch.irradiance * t, &mut total);
                    }
                    let mu = if rng.uniform() < rayleigh_share {
                        sample_rayleigh(rng)
                    } else {
                        sample_cornette_shanks(g, rng)
                    };
                    p = x;
                    d = around(d, mu, TAU * rng.uniform());
                }
            }
            if weight <= 0.0 {
                break;
            }
            if weight < ROULETTE_WEIGHT {
                if rng.uniform() * ROULETTE_WEIGHT >= weight {
                    break;
                }
                weight = ROULETTE_WEIGHT;
            }
        }
        total
    }
}

/// A unit vector at cosine `mu` from the unit vector `axis`, at azimuth
/// `phi` in a frame around it.
fn around(axis: DVec3, mu: f64, phi: f64) -> DVec3 {
    // Duff et al. 2017's branchless orthonormal basis.
    let sign = 1.0f64.copysign(axis.z);
    let a = -1.0 / (sign + axis.z);
    let b = axis.x * axis.y * a;
    let u = DVec3::new(1.0 + sign * axis.x * axis.x * a, sign * b, -sign * axis.x);
    let v = DVec3::new(b, sign + axis.y * axis.y * a, -axis.y);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    (axis * mu + (u * phi.cos() + v * phi.sin()) * s).normalize()
}

/// A cosine-weighted direction about `normal`.
fn cosine_direction(normal: DVec3, rng: &mut Rng) -> DVec3 {
    let mu = rng.uniform().sqrt();
    around(normal, mu.max(1e-12), TAU * rng.uniform())
}

/// The cosine of a scattering angle drawn from the Rayleigh phase function.
fn sample_rayleigh(rng: &mut Rng) -> f64 {
    loop {
        let mu = 2.0 * rng.uniform() - 1.0;
        if 2.0 * rng.uniform() < 1.0 + mu * mu {
            return mu;
        }
    }
}

/// The cosine of a scattering angle drawn from Cornette–Shanks of `g`.
fn sample_cornette_shanks(g: f64, rng: &mut Rng) -> f64 {
    loop {
        let xi = rng.uniform();
        let mu = if g.abs() < 1e-6 {
            2.0 * xi - 1.0
        } else {
            let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
            ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
        };
        if 2.0 * rng.uniform() < 1.0 + mu * mu {
            return mu;
        }
    }
}

/// Sums of the per-path estimates of each channel.
#[derive(Clone, Debug, Default)]
struct Tally {
    paths: u64,
    sum: [f64; 3],
    squares: [f64; 3],
    /// Sum over paths of each order's radiance (index: order − 1).
    orders: Vec<[f64; 3]>,
}

impl Tally {
    fn merge(&mut self, o: &Tally) {
        self.paths += o.paths;
        for c in 0..3 {
            self.sum[c] += o.sum[c];
            self.squares[c] += o.squares[c];
        }
        if self.orders.len() < o.orders.len() {
            self.orders.resize(o.orders.len(), [0.0; 3]);
        }
        for (a, b) in self.orders.iter_mut().zip(&o.orders) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
    }

    fn per_path(&self, sum: [f64; 3]) -> DVec3 {
        if self.paths == 0 {
            DVec3::ZERO
        } else {
            DVec3::from_array(sum) / self.paths as f64
        }
    }

    /// The mean over paths and its standard error.
    fn mean_and_error(&self) -> (DVec3, DVec3) {
        let n = self.paths as f64;
        if self.paths < 2 {
            return (self.per_path(self.sum), DVec3::ZERO);
        }
        let error = |c: usize| {
            let variance = (self.squares[c] - self.sum[c] * self.sum[c] / n).max(0.0) / (n - 1.0);
            (variance / n).sqrt()
        };
        (
            self.per_path(self.sum),
            DVec3::new(error(0), error(1), error(2)),
        )
    }
}

/// What starts a path: its origin, direction and the factor its radiance
/// is scaled by (the inverse of the start's own density, when sampled).
type Start<'s> = dyn Fn(&mut Rng) -> (DVec3, DVec3, f64) + Sync + 's;

/// Runs `settings.paths` paths per channel from `start`, counting orders
/// `first_order..=settings.max_order`, over all cores, deterministically.
fn estimate(medium: &Medium, settings: TransportSettings, first_order: u32, start: &Start) -> Tally {
    if settings.max_order < first_order || settings.paths == 0 {
        return Tally::default();
    }
    let blocks = settings.paths.div_ceil(BLOCK) as usize;
    let run_block = |b: usize| {
        let mut tally = Tally::default();
        let mut orders = Vec::new();
        let first = b as u32 * BLOCK;
        for path in first..(first + BLOCK).min(settings.paths) {
            for c in 0..3 {
                let mut rng = Rng::new(settings.seed, path as u64, c as u64);
                let (origin, direction, factor) = start(&mut rng);
                let value = medium.walk(
                    c,
                    origin,
                    direction,
                    factor,
                    first_order,
                    settings.max_order,
                    &mut rng,
                    &mut orders,
                );
                tally.sum[c] += value;
                tally.squares[c] += value * value;
            }
            tally.paths += 1;
        }
        tally.orders = orders;
        tally
    };
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(blocks);
    let mut results: Vec<Option<Tally>> = vec![None; blocks];
    if threads <= 1 {
        for (b, r) in results.iter_mut().enumerate() {
            *r = Some(run_block(b));
        }
    } else {
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    let run_block = &run_block;
                    scope.spawn(move || {
                        (t..blocks)
                            .step_by(threads)
                            .map(|b| (b, run_block(b)))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            for h in handles {
                for (b, tally) in h.join().expect("a transport thread panicked") {
                    results[b] = Some(tally);
                }
            }
        });
    }
    let mut total = Tally::default();
    for r in results.iter().flatten() {
        total.merge(r);
    }
    total
}

/// The higher orders alone (2 and up) reaching `origin` from `direction`:
/// [`full_radiance`]'s `multiple` and `std_error`, without its
/// single-scattering quadrature (for callers that have L₁ already).
pub fn multiple_radiance(
    atmosphere: &Atmosphere,
    sun: &Sun,
    origin: DVec3,
    direction: DVec3,
    settings: TransportSettings,
) -> (DVec3, DVec3) {
    let direction = direction.normalize();
    let medium = Medium::new(atmosphere, sun);
    estimate(&medium, settings, 2, &|_: &mut Rng| (origin, direction, 1.0)).mean_and_error()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    fn sun(direction: DVec3) -> Sun {
        Sun {
            direction: direction.normalize(),
            irradiance: DVec3::ONE,
            angular_radius: 0.004675,
            disc: false,
        }
    }

    fn probe_earth() -> Atmosphere {
        Atmosphere {
            ground_albedo: DVec3::splat(0.1),
            ..Atmosphere::earth()
        }
    }

    /// A unit vector `elevation` degrees above the horizontal at azimuth
    /// `azimuth` degrees from +x (in the x–z plane), with +y up.
    fn dir(elevation: f64, azimuth: f64) -> DVec3 {
        let (e, a) = (elevation.to_radians(), azimuth.to_radians());
        DVec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin())
    }

    #[test]
    #[ignore]
    fn explore_probes() {
        let a = probe_earth();
        let paths: u32 = std::env::var("PATHS").ok().and_then(|s| s.parse().ok()).unwrap_or(20000);
        let cases = [
            ("ground, sun 45, view 45 away", 0.0, dir(45.0, 0.0), dir(45.0, 180.0)),
            ("ground, sun 0, view 10 towards", 0.0, dir(0.0, 0.0), dir(10.0, 0.0)),
            ("10 km, sun 10, view -1 towards", 10_000.0, dir(10.0, 0.0), dir(-1.0, 0.0)),
            ("10 km, sun 10, view -1 side", 10_000.0, dir(10.0, 0.0), dir(-1.0, 90.0)),
            ("10 km, sun 10, view -1 away", 10_000.0, dir(10.0, 0.0), dir(-1.0, 180.0)),
        ];
        for (name, h, s, d) in cases {
            let origin = DVec3::new(0.0, a.bottom_radius + h, 0.0);
            let t = Instant::now();
            let e = full_radiance(&a, &sun(s), origin, d, TransportSettings { paths, seed: 1, max_order: UNLIMITED });
            let el = t.elapsed();
            let ratio = e.radiance / e.single;
            let rel = e.std_error / e.single;
            println!("{name}: ratio {ratio:.4} ± {rel:.4}  single {:?} orders {:?} in {el:?}", e.single, e.by_order.iter().take(6).map(|o| o / e.single).collect::<Vec<_>>());
        }
    }
}
