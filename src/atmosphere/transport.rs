//! Full light transport in double precision: the radiance reaching a point
//! with every order of scattering and of ground reflection, the reference
//! that single scattering ([`quadrature`](mod@super::quadrature)) is a part
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
//! ([`quadrature::REFERENCE_CUT`]): `top_radius`, or lower where a tall
//! atmosphere holds a negligible column above.
//!
//! # What it leaves out
//! Polarisation (a scalar model, like Bruneton's and Hillaire's: the
//! multiply scattered light of a Rayleigh atmosphere computed without it is
//! off by several per cent in some directions); the sun's disc for lighting
//! (the sun is a point, as in the single-scattering reference; its disc
//! seen directly, order zero, is part of no radiance here); refraction
//! (rays are straight); any spectral resolution beyond the model's three
//! wavelengths (each channel is a monochromatic problem of its own); a
//! non-Lambertian ground; light from anything but the sun.
//!
//! # Estimator
//! The radiance along a ray is split as L = L₁ + L≥₂. L₁ (light that
//! scattered once in the air or reflected once on the ground) is
//! [`quadrature::radiance`] itself, the adaptive quadrature to 1e-7, so the
//! single-scattering part of [`full_radiance`] *is* today's integral.
//!
//! L≥₂ is an unbiased Monte Carlo estimate, with its standard error, by
//! backward path tracing from the viewer, each channel on its own paths
//! (a channel's coefficients are those of a grey medium; a path never
//! mixes them):
//! - *Pieces.* A ray's stretch inside the air is cut at its lowest point
//!   into halves on which the altitude is monotonic, and each half where
//!   its altitude has risen from its lowest by step·(2^k − 1), the step
//!   half the smaller scale height: so the exponential densities on a
//!   piece lie between their values at its two ends and the ozone tent
//!   between its smaller end value and its largest value on the piece,
//!   which gives each piece a control (lower bound) and a majorant of the
//!   extinction: 3 to 7 pieces a ray on average in Earth's air.
//! - *Free flight* by delta tracking against the pieces' majorants: a
//!   tentative collision at x is real with probability σₜ(x)/σ̄; there the
//!   weight is multiplied by the single-scattering albedo σₛ(x)/σₜ(x)
//!   (absorption by ozone and Mie) and the path scatters. On a ray that
//!   would leave the air the first tentative collision is forced into it
//!   (drawn from the majorant's exponential conditioned to fall before the
//!   exit, weight × its probability 1 − e^(−τ̄)), so a thin atmosphere
//!   does not spend most paths on rays that leave it; a ray that ends on
//!   the ground is tracked as it comes. Delta tracking needs no optical
//!   depth, so no quadrature error enters the multiple-scattering part.
//! - *Next-event estimation* towards the sun at every vertex from the
//!   second on (the first vertex's is L₁): the phase function (or
//!   albedo/π·cos at the ground) times the sun's transmittance, zero in the
//!   planet's shadow. The transmittance is estimated without bias by
//!   residual ratio tracking (Novák, Selle and Jarosz 2014) against the
//!   pieces: e^(−∫ control) in closed form times the product of
//!   1 − (σₜ(xᵢ) − control)/(majorant − control) over tentative collisions
//!   at the rate majorant − control; each factor lies in [0, 1], and the
//!   estimate is exact where the density is constant.
//! - *New directions* are drawn from the event's own density: Rayleigh or
//!   Mie in proportion to their scattering coefficients at x, the Rayleigh
//!   phase function by rejection from the uniform sphere (acceptance
//!   (1 + μ²)/2) and Cornette–Shanks by rejection from Henyey–Greenstein of
//!   the same g (Cornette–Shanks is HG·(1 + μ²) up to a constant, so the
//!   same acceptance); at the ground a cosine-weighted direction, weight ×
//!   albedo.
//! - *Russian roulette* once the weight falls below a quarter: the path
//!   survives with probability weight/0.25 and then carries exactly 0.25,
//!   so the expectation is unchanged. `max_order` ends every path after
//!   that many events (a deliberate truncation; [`UNLIMITED`] leaves it to
//!   roulette and escape, which costs about τ² events a path in an
//!   optically thick (τ) non-absorbing atmosphere).
//!
//! The standard error is the sample standard deviation of the per-path
//! estimates over √paths, per channel. Paths are split into fixed blocks
//! whose random streams derive from (seed, path, channel) by SplitMix64
//! (Steele, Lea and Flood 2014), and the blocks' sums are added in their
//! order whatever the number of threads, so a seed gives the same bits on
//! any machine.
//!
//! # Bias
//! - The multiple-scattering part: none from the estimator (delta and
//!   residual ratio tracking, exact sampling and roulette are unbiased).
//!   Controls and majorants are widened by 1e-9 of their value, far beyond
//!   what the rounding of an altitude (~1e-9 m against scale heights of
//!   kilometres) can move a density, so they bound it.
//! - The single-scattering part: the reference's 1e-7 relative tolerance.
//! - The top of the air, cut where the reference cuts it (below 1e-12 of
//!   the column above), and a finite `max_order`: the tail beyond order N
//!   is at most by_order[N − 1]·q/(1 − q) when successive orders fall by
//!   q (q ≤ 0.5 in Earth's air, about 0.35 in blue; see the tests).
//!
//! # Cost
//! In Earth's air a path of one channel costs 1–2 µs of one core in an
//! optimised build (about 5 µs unoptimised): 20 000 paths, some 70 ms,
//! put the standard error of the sky's radiance at 0.2–0.6 % of it, and
//! the error falls as 1/√paths.
//!
//! The tests check: energy conservation over an albedo-1 ground, the
//! single-scattering part against the quadrature, the Monte Carlo's own
//! order 1 against the quadrature, the transmittance estimator against
//! [`quadrature::densities_to_top`], orders 1 and 2 of a thin homogeneous
//! slab against an independent quadrature, the order count, and the
//! multiple-to-single ratios of Earth's sky against an independent
//! tracer's.

use super::{
    cornette_shanks_phase, hits_ground, quadrature, ray_sphere, rayleigh_phase, Atmosphere, Sun,
};
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// `max_order` that leaves the number of events to Russian roulette and to
/// the paths' escape.
pub const UNLIMITED: u32 = u32::MAX;

/// Weight below which a path plays Russian roulette.
const ROULETTE_WEIGHT: f64 = 0.25;

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
/// [`quadrature::radiance`].
#[derive(Clone, Debug, PartialEq)]
pub struct TransportEstimate {
    /// `single + multiple`: all orders up to `max_order`.
    pub radiance: DVec3,
    /// Order 1: [`quadrature::radiance`] (single scattering and the sun-lit
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
/// disc (order zero) is not included, as in [`quadrature::radiance`].
pub fn full_radiance(
    atmosphere: &Atmosphere,
    sun: &Sun,
    origin: DVec3,
    direction: DVec3,
    settings: TransportSettings,
) -> TransportEstimate {
    let single = if settings.max_order >= 1 {
        quadrature::radiance(atmosphere, sun, origin, direction)
    } else {
        DVec3::ZERO
    };
    let direction = direction.normalize();
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
/// taken on the ground above it (as in [`quadrature::sun_transmittance`]);
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

/// Most boundaries of a [`Track`]: each of its two monotonic halves has
/// at most 32 (its altitudes step by at least 2^−30 of the air's depth).
const MAX_BOUNDS: usize = 72;

/// A ray's stretch through the air, cut into pieces on which the altitude
/// is monotonic and rises (or falls) by a bounded amount: the boundaries'
/// distances, altitudes and exponential densities (Rayleigh, Mie), in
/// increasing distance.
struct Track {
    t: [f64; MAX_BOUNDS],
    h: [f64; MAX_BOUNDS],
    rayleigh: [f64; MAX_BOUNDS],
    mie: [f64; MAX_BOUNDS],
    count: usize,
}

impl Track {
    fn pieces(&self) -> usize {
        self.count.saturating_sub(1)
    }
}

impl<'a> Medium<'a> {
    fn new(atmosphere: &'a Atmosphere, sun: &Sun) -> Medium<'a> {
        let cut = atmosphere.negligible_altitude(quadrature::REFERENCE_CUT);
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
            piece: (0.5
                * atmosphere
                    .rayleigh_scale_height
                    .min(atmosphere.mie_scale_height))
            .max(1e-3),
        }
    }

    /// `p`, or the point on the ground above it when it lies below: a hair
    /// above (4e-15 of the radius, some ten units in the last place of
    /// its length), so that the horizon test sees the upper hemisphere.
    fn lift(&self, p: DVec3) -> DVec3 {
        let floor = self.bottom * (1.0 + 4e-15);
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

    /// The pieces of [t0, t1] along `p + t·d` (`d` unit, inside the air):
    /// away from the lowest point of each monotonic half, boundaries where
    /// the altitude has risen by step·(2^k − 1), the step half the smaller
    /// scale height, so the densities' ratio across a piece stays modest
    /// where they matter and the pieces number O(log(depth/step)).
    fn track(&self, p: DVec3, d: DVec3, t0: f64, t1: f64) -> Track {
        let mut track = Track {
            t: [0.0; MAX_BOUNDS],
            h: [0.0; MAX_BOUNDS],
            rayleigh: [0.0; MAX_BOUNDS],
            mie: [0.0; MAX_BOUNDS],
            count: 0,
        };
        let a = self.atmosphere;
        let (rayleigh_height, mie_height) = (a.rayleigh_scale_height, a.mie_scale_height);
        let push = |track: &mut Track, t: f64, h: f64| {
            let i = track.count;
            track.t[i] = t;
            track.h[i] = h;
            track.rayleigh[i] = (-h / rayleigh_height).exp();
            track.mie[i] = (-h / mie_height).exp();
            track.count += 1;
        };
        let h0 = self.altitude(p + t0 * d);
        push(&mut track, t0, h0);
        if t1 <= t0 {
            return track;
        }
        let h1 = self.altitude(p + t1 * d);
        let middle = -p.dot(d);
        let rho = (p - p.dot(d) * d).length();
        let depth = self.top - self.bottom;
        let step = self.piece.max(depth * 2f64.powi(-30));
        let rise = |k: i32| step * (2f64.powi(k) - 1.0);
        // Distance from the lowest point of the line to where it is at
        // altitude h.
        let half = |h: f64| {
            let r = self.bottom + h;
            ((r - rho).max(0.0) * (r + rho)).sqrt()
        };
        if middle > t0 {
            // Falling from t0 to b, lowest at b.
            let b = middle.min(t1);
            let hb = if b == t1 {
                h1
            } else {
                (rho - self.bottom).max(0.0)
            };
            let mut k = 1;
            while hb + rise(k + 1) < h0 {
                k += 1;
            }
            while k >= 1 {
                let h = hb + rise(k);
                if h < h0 {
                    let t = (middle - half(h)).clamp(t0, b);
                    if t > track.t[track.count - 1] {
                        push(&mut track, t, h);
                    }
                }
                k -= 1;
            }
            if b > track.t[track.count - 1] {
                push(&mut track, b, hb);
            }
        }
        if middle < t1 {
            // Rising from a to t1, lowest at a.
            let (a, ha) = (track.t[track.count - 1], track.h[track.count - 1]);
            let mut k = 1;
            while ha + rise(k) < h1 {
                let h = ha + rise(k);
                let t = (middle + half(h)).clamp(a, t1);
                if t > track.t[track.count - 1] {
                    push(&mut track, t, h);
                }
                k += 1;
            }
            if t1 > track.t[track.count - 1] {
                push(&mut track, t1, h1);
            }
        }
        track
    }

    /// The control (a lower bound) and the majorant of the extinction on
    /// piece `i` of `track`: the exponentials at its higher and its lower
    /// end (widened by 1e-9, far beyond the rounding of a point's altitude,
    /// ~1e-9 m, against the piece's), the ozone tent at its smaller end
    /// value (it is concave where it is not zero) and its largest value
    /// between the ends.
    fn piece_bounds(&self, c: &Channel, track: &Track, i: usize) -> (f64, f64) {
        let (lo, hi) = if track.h[i] <= track.h[i + 1] {
            (i, i + 1)
        } else {
            (i + 1, i)
        };
        let exponentials =
            |k: usize| c.rayleigh * track.rayleigh[k] + c.mie_extinction * track.mie[k];
        let mut control = exponentials(hi) * (1.0 - 1e-9);
        let mut majorant = exponentials(lo) * (1.0 + 1e-9);
        let a = self.atmosphere;
        let (h_lo, h_hi) = (track.h[lo], track.h[hi]);
        let [start, peak, end] = a.ozone_layer;
        if c.ozone > 0.0 && h_hi > start && h_lo < end {
            let tent = |h: f64| a.densities(h).ozone;
            let (at_lo, at_hi) = (tent(h_lo), tent(h_hi));
            let max = if h_lo <= peak && peak <= h_hi {
                1.0
            } else {
                at_lo.max(at_hi) + 1e-9
            };
            control += c.ozone * (at_lo.min(at_hi) - 1e-9).max(0.0);
            majorant += c.ozone * max;
        }
        (control, majorant)
    }

    /// Samples where the ray from `p` along `d` first interacts, by delta
    /// tracking, and the factor the path's weight takes from it. A ray
    /// that would leave the air has its first tentative collision forced
    /// into it: drawn from the majorant's exponential conditioned to fall
    /// before the exit, the weight times the probability of that,
    /// 1 − e^(−τ̄); the tracking goes on unconditioned from there (a
    /// null collision may still let it out). A ray that ends on the ground
    /// is tracked as it comes.
    fn free_flight(&self, c: &Channel, p: DVec3, d: DVec3, rng: &mut Rng) -> (Event, f64) {
        let Some((t0, t1, ground)) = self.segment(p, d) else {
            return (Event::Escape, 1.0);
        };
        let track = self.track(p, d, t0, t1);
        let mut majorants = [0.0; MAX_BOUNDS];
        let mut total = 0.0;
        for (i, majorant) in majorants[..track.pieces()].iter_mut().enumerate() {
            *majorant = self.piece_bounds(c, &track, i).1;
            total += *majorant * (track.t[i + 1] - track.t[i]);
        }
        let (mut need, factor) = if ground {
            (rng.exponential(), 1.0)
        } else {
            if total <= 0.0 {
                return (Event::Escape, 1.0);
            }
            let keep = -(-total).exp_m1();
            (-(-keep * rng.uniform()).ln_1p(), keep)
        };
        for (i, &majorant) in majorants[..track.pieces()].iter().enumerate() {
            let (a, b) = (track.t[i], track.t[i + 1]);
            if majorant <= 0.0 {
                continue;
            }
            let mut t = a;
            loop {
                let room = (b - t) * majorant;
                if need >= room {
                    need -= room;
                    break;
                }
                t += need / majorant;
                let x = p + t * d;
                let (extinction, scattering, rayleigh) = self.coefficients(c, self.altitude(x));
                if rng.uniform() * majorant < extinction {
                    let event = Event::Scatter(x, scattering / extinction, rayleigh / scattering);
                    return (event, factor);
                }
                need = rng.exponential();
            }
        }
        if ground {
            (Event::Ground(self.lift(p + t1 * d)), factor)
        } else {
            (Event::Escape, factor)
        }
    }

    /// An unbiased estimate (residual ratio tracking) of the transmittance from `p`
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

    /// Residual ratio tracking (Novák, Selle and Jarosz 2014) over [t0,
    /// t1] of `p + t·d`: on each stretch the control extinction's share in
    /// closed form, e^(−σ_c·length), times the product of
    /// 1 − (σₜ(xᵢ) − σ_c)/(σ̄ − σ_c) over tentative collisions at the rate
    /// σ̄ − σ_c. Unbiased, each factor in [0, 1], and exact where the
    /// density is constant.
    fn ratio_tracking(
        &self,
        c: &Channel,
        p: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        rng: &mut Rng,
    ) -> f64 {
        let track = self.track(p, d, t0, t1);
        let mut depth = 0.0;
        let mut ratio = 1.0;
        for i in 0..track.pieces() {
            let (a, b) = (track.t[i], track.t[i + 1]);
            let (control, majorant) = self.piece_bounds(c, &track, i);
            depth += control * (b - a);
            let residual = majorant - control;
            if residual <= 0.0 {
                continue;
            }
            let mut t = a;
            loop {
                t += rng.exponential() / residual;
                if t >= b {
                    break;
                }
                let extinction = self.extinction(c, self.altitude(p + t * d));
                ratio *= (1.0 - (extinction - control) / residual).clamp(0.0, 1.0);
            }
        }
        (-depth).exp() * ratio
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
            let (event, factor) = self.free_flight(ch, p, d, rng);
            weight *= factor;
            match event {
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
fn estimate(
    medium: &Medium,
    settings: TransportSettings,
    first_order: u32,
    start: &Start,
) -> Tally {
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
    estimate(&medium, settings, 2, &|_: &mut Rng| {
        (origin, direction, 1.0)
    })
    .mean_and_error()
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

    /// The probe settings: Earth with a ground albedo of 0.1 (and
    /// an irradiance of 1).
    fn probe_earth() -> Atmosphere {
        Atmosphere {
            ground_albedo: DVec3::splat(0.1),
            ..Atmosphere::earth()
        }
    }

    /// A unit vector `elevation` degrees above the horizontal at `azimuth`
    /// degrees from +x towards +z, with +y up.
    fn dir(elevation: f64, azimuth: f64) -> DVec3 {
        let (e, a) = (elevation.to_radians(), azimuth.to_radians());
        DVec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin())
    }

    /// `n` paths times `TRANSPORT_TEST_SCALE` (default 1): the statistical
    /// tests hold their assertions at any scale, so a larger one (in an
    /// optimised build) tightens them, down to their fixed margins.
    fn scaled(n: u32) -> u32 {
        let scale: u32 = std::env::var("TRANSPORT_TEST_SCALE")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1);
        n * scale.max(1)
    }

    fn settings(paths: u32, seed: u64, max_order: u32) -> TransportSettings {
        TransportSettings {
            paths,
            seed,
            max_order,
        }
    }

    /// Gauss–Legendre nodes and weights on [a, b].
    fn gauss_legendre(n: usize, a: f64, b: f64) -> Vec<(f64, f64)> {
        (0..n)
            .map(|i| {
                // Newton from Tricomi's estimate of the i-th root.
                let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
                let mut derivative = 0.0;
                for _ in 0..100 {
                    let (mut p0, mut p1) = (1.0, x);
                    for k in 2..=n {
                        let k = k as f64;
                        (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                    }
                    derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                    let dx = p1 / derivative;
                    x -= dx;
                    if dx.abs() < 1e-15 {
                        break;
                    }
                }
                let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
                (0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w)
            })
            .collect()
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_and_an_exponential() {
        let rule = gauss_legendre(8, -1.0, 2.0);
        let x14: f64 = rule.iter().map(|(x, w)| w * x.powi(14)).sum();
        assert!((x14 - (2f64.powi(15) + 1.0) / 15.0).abs() < 1e-11, "{x14}");
        let rule = gauss_legendre(24, 0.0, 3.0);
        let e: f64 = rule.iter().map(|(x, w)| w * (-x).exp()).sum();
        assert!((e - (1.0 - (-3f64).exp())).abs() < 1e-14, "{e}");
    }

    /// The Monte Carlo's own estimate of orders `first..=last` along a ray,
    /// with its standard error.
    fn sampled(
        a: &Atmosphere,
        s: &Sun,
        origin: DVec3,
        direction: DVec3,
        paths: u32,
        first: u32,
        last: u32,
    ) -> (DVec3, DVec3, Vec<DVec3>) {
        let medium = Medium::new(a, s);
        let tally = estimate(&medium, settings(paths, 7, last), first, &|_: &mut Rng| {
            (origin, direction, 1.0)
        });
        let (mean, error) = tally.mean_and_error();
        let orders = tally.orders.iter().map(|o| tally.per_path(*o)).collect();
        (mean, error, orders)
    }

    /// `got` within `sigmas` standard errors plus `margin` (relative) of
    /// `want`, per channel.
    fn agrees(got: DVec3, error: DVec3, want: DVec3, sigmas: f64, margin: f64) -> bool {
        (0..3).all(|c| (got[c] - want[c]).abs() <= sigmas * error[c] + margin * want[c].abs())
    }

    #[test]
    fn ratio_tracking_transmittance_matches_the_quadrature() {
        // The unbiased transmittance of next-event estimation, averaged,
        // against exp(−τ) of the reference's adaptive quadrature: steep,
        // grazing from the ground, grazing high up (the majorant of the
        // stretches far above the ray's lowest point), from the top and
        // through the ozone peak.
        let a = Atmosphere::earth();
        let s = sun(DVec3::Y);
        let medium = Medium::new(&a, &s);
        let mut rng = Rng::new(3, 0, 0);
        for (h, elevation) in [
            (0.0, 90.0),
            (0.0, 0.5),
            (30_000.0, 0.0),
            (59_000.0, -2.0),
            (20_000.0, 20.0),
        ] {
            let p = DVec3::new(0.0, a.bottom_radius + h, 0.0);
            let d = dir(elevation, 0.0);
            let exact = a.transmittance(quadrature::densities_to_top(&a, p, d).unwrap());
            let n = scaled(4000);
            for c in 0..3 {
                let ch = &medium.channels[c];
                let (t0, t1, ground) = medium.segment(p, d).unwrap();
                assert!(!ground);
                let mut sum = 0.0;
                for _ in 0..n {
                    sum += medium.ratio_tracking(ch, p, d, t0, t1, &mut rng);
                }
                let mean = sum / n as f64;
                // The estimate is e^(−τ_c)·R with R in [0, 1] and R = 1
                // unless a residual collision happens, which it does with
                // probability at most τ_r (the residual's optical depth):
                // its variance is at most e^(−2τ_c)·τ_r. (The sample
                // variance would understate it: the collisions are rare.)
                let track = medium.track(p, d, t0, t1);
                let (mut control, mut residual) = (0.0, 0.0);
                for i in 0..track.pieces() {
                    let (lo, hi) = medium.piece_bounds(ch, &track, i);
                    let length = track.t[i + 1] - track.t[i];
                    control += lo * length;
                    residual += (hi - lo) * length;
                }
                let error = (-control).exp() * (residual / n as f64).sqrt();
                assert!(
                    (mean - exact[c]).abs() <= 4.0 * error + 1e-12,
                    "h {h}, elevation {elevation}, channel {c}: {mean} ± {error} against {}",
                    exact[c]
                );
            }
        }
    }

    #[test]
    fn the_single_scattering_part_is_the_reference_integral() {
        // By construction: `single` is `quadrature::radiance`, bit for bit,
        // and `by_order` starts with it.
        let a = probe_earth();
        let s = sun(dir(30.0, 0.0));
        let cases = [
            (0.0, dir(45.0, 180.0)),
            (10_000.0, dir(-30.0, 45.0)),
            (2_000.0, dir(5.0, 10.0)),
        ];
        for (h, d) in cases {
            let origin = DVec3::new(0.0, a.bottom_radius + h, 0.0);
            let e = full_radiance(&a, &s, origin, d, settings(64, 1, UNLIMITED));
            let exact = quadrature::radiance(&a, &s, origin, d);
            assert_eq!(e.single, exact);
            assert_eq!(e.by_order[0], exact);
            let sum = e.by_order.iter().copied().sum::<DVec3>();
            assert!((sum - e.radiance).abs().max_element() <= 1e-12 * e.radiance.max_element());
            let one = full_radiance(&a, &s, origin, d, settings(64, 1, 1));
            assert_eq!(one.radiance, exact);
            assert_eq!(one.multiple, DVec3::ZERO);
        }
    }

    #[test]
    fn the_monte_carlos_own_single_scattering_matches_the_reference_integral() {
        // The same paths with next-event estimation at their first vertex
        // and nothing after it: delta tracking, phase functions, ratio
        // tracking, the shadow and the lit ground against the quadrature.
        let a = probe_earth();
        let s = sun(dir(20.0, 0.0));
        for (h, d) in [(0.0, dir(30.0, 150.0)), (5_000.0, dir(-20.0, 0.0))] {
            let origin = DVec3::new(0.0, a.bottom_radius + h, 0.0);
            let exact = quadrature::radiance(&a, &s, origin, d);
            let (got, error, _) = sampled(&a, &s, origin, d, scaled(3000), 1, 1);
            println!("h {h}: {got} ± {error} against {exact}");
            assert!(
                agrees(got, error, exact, 4.0, 1e-6),
                "{got} ± {error} against {exact}"
            );
            assert!((error / exact).max_element() < 0.05, "{error}");
        }
    }

    /// A thin homogeneous slab: 10 km of air of constant density (scale
    /// heights of 1e15 m) over a planet of 1e10 m, whose ground falls
    /// 0.5 m (5e-5 of the depth) 100 km away, where light travelling
    /// sideways has crossed an optical depth of 2.25 or more; seen in
    /// plane-parallel coordinates by a quadrature that shares nothing with
    /// the path tracer but the phase functions.
    struct Slab {
        atmosphere: Atmosphere,
        sun: Sun,
    }

    impl Slab {
        const DEPTH: f64 = 10_000.0;
        const RADIUS: f64 = 1e10;

        fn new() -> Slab {
            Slab {
                atmosphere: Atmosphere {
                    center: DVec3::ZERO,
                    bottom_radius: Self::RADIUS,
                    top_radius: Self::RADIUS + Self::DEPTH,
                    // Optical depths 0.1, 0.2, 0.4 of Rayleigh and 0.125
                    // of Mie, which absorbs a fifth of what it removes.
                    rayleigh_scattering: DVec3::new(1e-5, 2e-5, 4e-5),
                    rayleigh_scale_height: 1e15,
                    mie_scattering: DVec3::splat(1e-5),
                    mie_extinction: DVec3::splat(1.25e-5),
                    mie_scale_height: 1e15,
                    mie_g: 0.5,
                    ozone_absorption: DVec3::ZERO,
                    ozone_layer: [10_000.0, 25_000.0, 40_000.0],
                    ground_albedo: DVec3::new(0.2, 0.3, 0.4),
                },
                sun: sun(dir(37.0, 0.0)),
            }
        }

        fn point(z: f64) -> DVec3 {
            DVec3::new(0.0, Self::RADIUS + z, 0.0)
        }

        /// Extinction, and σₛ·phase of the scattering cosine `mu`.
        fn medium(&self, c: usize, mu: f64) -> (f64, f64) {
            let a = &self.atmosphere;
            (
                a.rayleigh_scattering[c] + a.mie_extinction[c],
                a.rayleigh_scattering[c] * rayleigh_phase(mu)
                    + a.mie_scattering[c] * cornette_shanks_phase(mu, a.mie_g),
            )
        }

        /// Order-1 radiance at height `z` looking along `w` (unit, +y up):
        /// the air's single scattering in closed form along the ray, plus
        /// the sun-lit ground where it looks down.
        fn single(&self, c: usize, z: f64, w: DVec3) -> f64 {
            let s = self.sun.direction;
            let (extinction, scattering) = self.medium(c, w.dot(s));
            let (mu, mu_s) = (w.y, s.y);
            let length = if mu > 0.0 {
                (Self::DEPTH - z) / mu
            } else {
                z / -mu
            };
            // ∫₀ˡ e^(−σₜ·t − σₜ·(D − z − t·μ)/μₛ) dt.
            let k = extinction * (1.0 - mu / mu_s);
            let run = if (k * length).abs() < 1e-9 {
                length * (1.0 - 0.5 * k * length)
            } else {
                -(-k * length).exp_m1() / k
            };
            let mut radiance = scattering * (-extinction * (Self::DEPTH - z) / mu_s).exp() * run;
            if mu < 0.0 {
                radiance += self.atmosphere.ground_albedo[c] / PI
                    * mu_s
                    * (-extinction * Self::DEPTH / mu_s).exp()
                    * (-extinction * length).exp();
            }
            radiance
        }

        /// ∫ f over the unit sphere: Gauss–Legendre in μ on each side of
        /// the horizon, the trapezoid rule in azimuth.
        fn sphere(n: usize, f: &dyn Fn(DVec3) -> f64) -> f64 {
            let mut sum = 0.0;
            let m = 2 * n;
            for (mu, w) in gauss_legendre(n, -1.0, 0.0)
                .into_iter()
                .chain(gauss_legendre(n, 0.0, 1.0))
            {
                let r = (1.0 - mu * mu).sqrt();
                for j in 0..m {
                    let phi = (j as f64 + 0.5) * TAU / m as f64;
                    sum += w * TAU / m as f64 * f(DVec3::new(r * phi.cos(), mu, r * phi.sin()));
                }
            }
            sum
        }

        /// Order-1 irradiance from the sky on the ground.
        fn ground_irradiance(&self, c: usize, n: usize) -> f64 {
            Self::sphere(n, &|w| {
                if w.y > 0.0 {
                    self.single(c, 0.0, w) * w.y
                } else {
                    0.0
                }
            })
        }

        /// Order-2 radiance along `v` at the bottom of the slab (looking
        /// up) or from above it (looking down): the order-1 radiance of
        /// every direction scattered into `v` along the way, and, looking
        /// down, the ground lit by the order-1 sky.
        fn double(&self, c: usize, v: DVec3, n: usize) -> f64 {
            let (extinction, _) = self.medium(c, 1.0);
            let length = Self::DEPTH / v.y.abs();
            let height = |t: f64| {
                if v.y > 0.0 {
                    t * v.y
                } else {
                    Self::DEPTH + t * v.y
                }
            };
            let mut radiance = 0.0;
            for (t, w) in gauss_legendre(n, 0.0, length) {
                let z = height(t);
                let inscattered =
                    Self::sphere(n, &|u| self.medium(c, v.dot(u)).1 * self.single(c, z, u));
                radiance += w * (-extinction * t).exp() * inscattered;
            }
            if v.y < 0.0 {
                radiance += (-extinction * length).exp() * self.atmosphere.ground_albedo[c] / PI
                    * self.ground_irradiance(c, n);
            }
            radiance
        }
    }

    #[test]
    fn orders_one_and_two_of_a_homogeneous_slab_match_an_independent_quadrature() {
        let slab = Slab::new();
        let (a, s) = (&slab.atmosphere, &slab.sun);
        // Looking up from the ground; looking down from 1 km above the air
        // (the sky's light on the ground comes in here).
        for (z, v) in [(0.0, dir(53.0, 120.0)), (11_000.0, dir(-44.0, 60.0))] {
            let origin = Slab::point(z);
            let start = Instant::now();
            let quadrature = |n| DVec3::from_array(std::array::from_fn(|c| slab.double(c, v, n)));
            let want = quadrature(24);
            let coarse = quadrature(16);
            let quadrature_time = start.elapsed();
            // The quadrature has converged far below the test's margin.
            assert!(
                ((coarse - want) / want).abs().max_element() < 1e-5,
                "{coarse} {want}"
            );
            // Its order 1 against the reference's (the sphere's slant
            // paths are shorter than the slab's by D(1 − μ²)/(2Rμ²) ≈ 1e-6
            // of their length).
            let single = DVec3::from_array(std::array::from_fn(|c| {
                slab.single(c, z.min(Slab::DEPTH), v)
            }));
            let exact = quadrature::radiance(a, s, origin, v);
            assert!(
                ((single - exact) / exact).abs().max_element() < 1e-5,
                "{single} {exact}"
            );
            let start = Instant::now();
            let (got, error, _) = sampled(a, s, origin, v, scaled(16_000), 2, 2);
            println!(
                "z {z}: order 2 {got} ± {error} against {want} ({:?} quadrature, {:?} paths)",
                quadrature_time,
                start.elapsed()
            );
            assert!((error / want).max_element() < 0.01, "{error}");
            assert!(
                agrees(got, error, want, 4.0, 1e-4),
                "{got} ± {error} against {want}"
            );
        }
    }

    #[test]
    fn sky_irradiance_matches_the_quadrature_and_sees_the_ground_below() {
        let slab = Slab::new();
        let (a, s) = (&slab.atmosphere, &slab.sun);
        let ground = Slab::point(0.0);
        let (got, error) = sky_irradiance(a, s, ground, DVec3::Y, settings(scaled(10_000), 5, 1));
        let want = DVec3::from_array(std::array::from_fn(|c| slab.ground_irradiance(c, 24)));
        println!("sky irradiance {got} ± {error} against {want}");
        assert!((error / want).max_element() < 0.01, "{error}");
        assert!(
            agrees(got, error, want, 4.0, 1e-4),
            "{got} ± {error} against {want}"
        );
        // Facing the ground from the ground: the sun-lit ground at the
        // point itself, albedo·μₛ·T, with no variance at all.
        let (got, error) = sky_irradiance(a, s, ground, -DVec3::Y, settings(256, 5, 1));
        let mu_s = s.direction.y;
        let extinction = a.rayleigh_scattering + a.mie_extinction;
        let sun_light = DVec3::from_array(std::array::from_fn(|c| {
            (-extinction[c] * Slab::DEPTH / mu_s).exp()
        }));
        let want = a.ground_albedo * mu_s * sun_light;
        // (The sphere's slant path to the sun is 1e-6 shorter than the
        // slab's, see above.)
        assert!(
            ((got - want) / want).abs().max_element() < 1e-5,
            "{got} against {want}"
        );
        assert!(error.max_element() < 1e-8 * want.max_element(), "{error}");
    }

    /// The flux (per unit of irradiance) leaving the top sphere of a
    /// non-absorbing atmosphere unscattered: the sun's beam through the
    /// annulus of impact parameters between the ground and the top,
    /// E·∫ 2πb·T(b) db, with the reference's chord transmittances.
    fn direct_flux(a: &Atmosphere) -> DVec3 {
        let (bottom, top) = (a.bottom_radius, a.top_radius);
        let panels = 60;
        let width = (top - bottom) / panels as f64;
        let mut flux = DVec3::ZERO;
        for k in 0..panels {
            let lo = bottom + k as f64 * width;
            for (b, w) in gauss_legendre(4, lo, lo + width) {
                let half = ((top - b) * (top + b)).sqrt();
                let depth = quadrature::densities_between(
                    a,
                    DVec3::new(-half, b, 0.0),
                    DVec3::new(half, b, 0.0),
                );
                flux += w * TAU * b * a.transmittance(depth);
            }
        }
        flux
    }

    #[test]
    fn a_non_absorbing_atmosphere_over_a_white_ground_reflects_all_the_light() {
        // Earth's air without ozone and with non-absorbing aerosols over a
        // ground of albedo 1: every photon of the beam of cross-section
        // π·R_top² that enters leaves through the top sphere again, either
        // unscattered (`direct_flux`) or scattered and reflected any number
        // of times. The latter is ∫ over the top sphere of the irradiance
        // of the light arriving there from inside: a sensor at x facing
        // the centre, the estimator of `sky_irradiance` (cosine-weighted
        // directions, times π). By symmetry about the sun's axis that
        // irradiance depends only on c = cos(angle of x from the sun), and
        // dA = 2π·R_top²·dc, so the scattered flux is
        // 2π·R_top²·∫₋₁¹ E(c) dc. It is stratified in c (each path draws
        // its own c in its stratum, so each stratum's standard error holds
        // the variation across it).
        let a = Atmosphere {
            ozone_absorption: DVec3::ZERO,
            mie_extinction: Atmosphere::earth().mie_scattering,
            ground_albedo: DVec3::ONE,
            ..Atmosphere::earth()
        };
        let s = sun(DVec3::X);
        let medium = Medium::new(&a, &s);
        let top = a.top_radius;
        let incoming = PI * top * top;
        let direct = direct_flux(&a);
        let strata = 16;
        let paths = scaled(8000);
        let start = Instant::now();
        let (mut scattered, mut variance) = (DVec3::ZERO, DVec3::ZERO);
        for k in 0..strata {
            let lo = -1.0 + 2.0 * k as f64 / strata as f64;
            let width = 2.0 / strata as f64;
            let tally = estimate(
                &medium,
                settings(paths, 100 + k as u64, UNLIMITED),
                1,
                &|rng: &mut Rng| {
                    let c = lo + width * rng.uniform();
                    let x = top * DVec3::new(c, (1.0 - c * c).sqrt(), 0.0);
                    (x, cosine_direction(-x.normalize(), rng), PI)
                },
            );
            let (irradiance, error) = tally.mean_and_error();
            let area = TAU * top * top * width;
            scattered += area * irradiance;
            variance += (area * error) * (area * error);
        }
        let balance = (direct + scattered) / incoming;
        let error = variance.powf(0.5) / incoming;
        println!(
            "outgoing / incoming {balance} ± {error} (direct {}, in {:?})",
            direct / incoming,
            start.elapsed()
        );
        assert!(error.max_element() <= 3e-3, "{error}");
        assert!(((balance - 1.0).abs()).max_element() < 0.01, "{balance}");
        assert!(
            agrees(balance, error, DVec3::ONE, 4.0, 1e-4),
            "{balance} ± {error}"
        );
    }

    #[test]
    fn orders_fall_geometrically_and_the_tail_is_bounded() {
        // The first probe, where blue's orders fall slowest: each order is
        // at most half the one before (the ratio is about 0.35 in blue,
        // 0.12 in red), so the tail beyond order N is at most
        // by_order[N]·q/(1 − q) ≤ by_order[N]; the truncated estimate plus
        // that bound brackets the full one, and 50 orders equal unlimited
        // within their standard errors (different seeds).
        let a = probe_earth();
        let s = sun(dir(45.0, 0.0));
        let origin = DVec3::new(0.0, a.bottom_radius, 0.0);
        let v = dir(45.0, 180.0);
        let all = full_radiance(&a, &s, origin, v, settings(scaled(4000), 11, UNLIMITED));
        let fifty = full_radiance(&a, &s, origin, v, settings(scaled(4000), 12, 50));
        println!("orders {:?}", all.by_order);
        let combined =
            (all.std_error * all.std_error + fifty.std_error * fifty.std_error).powf(0.5);
        assert!(
            agrees(fifty.radiance, combined, all.radiance, 4.0, 0.0),
            "{} against {} ± {combined}",
            fifty.radiance,
            all.radiance
        );
        let q = 0.5;
        for k in 1..5 {
            let (this, next) = (all.by_order[k], all.by_order[k + 1]);
            assert!(
                (0..3).all(|c| next[c] <= q * this[c]),
                "order {} {this} then {next}",
                k + 1
            );
        }
        // Truncating the same paths (same seed) after N orders leaves out
        // exactly their tail, which the geometric bound covers.
        let n = 4;
        let truncated = full_radiance(&a, &s, origin, v, settings(scaled(4000), 11, n));
        let tail = all.radiance - truncated.radiance;
        let bound = all.by_order[n as usize - 1] * q / (1.0 - q);
        println!("tail beyond {n}: {tail} (bound {bound})");
        let kept: DVec3 = all.by_order[..n as usize].iter().copied().sum();
        assert!((truncated.radiance - kept).abs().max_element() < 1e-12);
        assert!(
            (0..3).all(|c| tail[c] >= 0.0 && tail[c] <= bound[c]),
            "{tail} {bound}"
        );
    }

    /// The probes: where, the sun, the view, and the ratios of full
    /// transport to single scattering its independent tracer found.
    fn probes() -> [(&'static str, f64, DVec3, DVec3, DVec3); 3] {
        [
            (
                "ground, sun 45° up, looking 45° up away from it",
                0.0,
                dir(45.0, 0.0),
                dir(45.0, 180.0),
                DVec3::new(1.31, 1.44, 1.77),
            ),
            (
                "ground, sun on the horizon, looking 10° up towards it",
                0.0,
                dir(0.0, 0.0),
                dir(10.0, 0.0),
                DVec3::new(1.07, 1.18, 1.53),
            ),
            (
                "10 km up, sun 10° up, looking 1° below the horizontal towards it",
                10_000.0,
                dir(10.0, 0.0),
                dir(-1.0, 0.0),
                DVec3::new(1.10, 1.17, 1.34),
            ),
        ]
    }

    #[test]
    fn earths_sky_has_the_multiple_scattering_an_independent_tracer_found() {
        let a = probe_earth();
        for (name, h, s, v, expected) in probes() {
            let origin = DVec3::new(0.0, a.bottom_radius + h, 0.0);
            let start = Instant::now();
            let e = full_radiance(
                &a,
                &sun(s),
                origin,
                v,
                settings(scaled(60_000), 21, UNLIMITED),
            );
            let ratio = e.radiance / e.single;
            let error = e.std_error / e.single;
            println!(
                "{name}: full/single {ratio} ± {error} in {:?}",
                start.elapsed()
            );
            // The figures are rounded to 0.01 and are themselves
            // estimates: 4 standard errors plus 1 %.
            assert!(
                (0..3)
                    .all(|c| (ratio[c] - expected[c]).abs() <= 4.0 * error[c] + 0.01 * expected[c]),
                "{name}: {ratio} ± {error} against {expected}"
            );
        }
    }

    #[test]
    fn a_seed_gives_the_same_estimate() {
        let a = probe_earth();
        let s = sun(dir(5.0, 0.0));
        let origin = DVec3::new(0.0, a.bottom_radius + 500.0, 0.0);
        let v = dir(3.0, 40.0);
        let run = |seed| full_radiance(&a, &s, origin, v, settings(300, seed, UNLIMITED));
        let (x, y, z) = (run(4), run(4), run(5));
        assert_eq!(x, y);
        assert_ne!(x.multiple, z.multiple);
    }

    /// Not a check: prints the probes' ratios (and more) with `PATHS`
    /// paths, their run time, and the pieces a ray is cut into.
    #[test]
    #[ignore]
    fn explore_probes() {
        let a = probe_earth();
        let paths: u32 = std::env::var("PATHS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(20000);
        let mut cases: Vec<_> = probes().to_vec();
        cases.extend([
            (
                "10 km up, sun 10° up, looking 1° below the horizontal across",
                10_000.0,
                dir(10.0, 0.0),
                dir(-1.0, 90.0),
                DVec3::ZERO,
            ),
            (
                "10 km up, sun 10° up, looking 1° below the horizontal away",
                10_000.0,
                dir(10.0, 0.0),
                dir(-1.0, 180.0),
                DVec3::ZERO,
            ),
            (
                "ground, sun 5° below the horizon, looking 30° up towards it",
                0.0,
                dir(-5.0, 0.0),
                dir(30.0, 0.0),
                DVec3::ZERO,
            ),
            (
                "ground, sun 5° below the horizon, looking at the zenith",
                0.0,
                dir(-5.0, 0.0),
                dir(90.0, 0.0),
                DVec3::ZERO,
            ),
        ]);
        for (name, h, s, v, expected) in cases {
            let origin = DVec3::new(0.0, a.bottom_radius + h, 0.0);
            let start = Instant::now();
            let single = quadrature::radiance(&a, &sun(s), origin, v);
            let single_time = start.elapsed();
            let start = Instant::now();
            let e = full_radiance(&a, &sun(s), origin, v, settings(paths, 1, UNLIMITED));
            let elapsed = start.elapsed();
            assert_eq!(single, e.single);
            let ratio = e.radiance / e.single;
            println!(
                "{name}: {ratio:.4} ± {:.4} (issue {expected}) single {:.4e} {:.4e} {:.4e} \
                 in {elapsed:?} (single {single_time:?})",
                e.std_error / e.single,
                e.single.x,
                e.single.y,
                e.single.z,
            );
        }
        let (a, s) = (Atmosphere::earth(), sun(DVec3::Y));
        let medium = Medium::new(&a, &s);
        let mut rng = Rng::new(0, 0, 0);
        for h in [0.0, 2_000.0, 10_000.0, 30_000.0] {
            let p = DVec3::new(0.0, a.bottom_radius + h, 0.0);
            let (mut pieces, mut rays) = (0, 0);
            for _ in 0..10_000 {
                let d = around(DVec3::Y, 2.0 * rng.uniform() - 1.0, TAU * rng.uniform());
                if let Some((t0, t1, _)) = medium.segment(p, d) {
                    pieces += medium.track(p, d, t0, t1).pieces();
                    rays += 1;
                }
            }
            println!("{h} m: {:.1} pieces a ray", pieces as f64 / rays as f64);
        }
    }
}
