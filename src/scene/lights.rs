//! Light sources and the attenuation model used for per-object culling.

use glam::{DVec3, Vec3};

/// A light source. Colours are linear RGB, already multiplied by the
/// intensity given in the scene file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A point light whose contribution is scaled by
    /// `1 / (c + l d + q d^2)` at distance `d`.
    Point {
        /// World-space position (f64, like every world position).
        position: DVec3,
        /// Colour times intensity, every component >= 0.
        color: Vec3,
        /// `(c, l, q)`: constant, linear and quadratic attenuation, each >= 0
        /// and not all zero.
        attenuation: Vec3,
    },
    /// A light at infinity.
    Directional {
        /// Unit vector in the direction the light travels (from the light
        /// towards the scene).
        direction: Vec3,
        /// Colour times intensity, every component >= 0.
        color: Vec3,
    },
}

/// How far a light reaches at a given cutoff: the distances where its
/// strength ([`Light::strength_at`]) is at least the cutoff.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightRange {
    /// Every distance (directional lights, a zero cutoff, no fall-off).
    Everywhere,
    /// Distances up to this one (>= 0).
    Within(f32),
    /// No distance: the light is below the cutoff even at its position.
    Nowhere,
}

impl Light {
    /// Where this light's strength is at least `cutoff`.
    ///
    /// With peak colour `P` and `K = P / cutoff`, a point light reaches `d`
    /// when `c + l d + q d^2 <= K`; the positive root is computed as
    /// `2 (K - c) / (l + sqrt(l^2 + 4 q (K - c)))`, which stays accurate
    /// when `q` is tiny (no cancellation) and is `(K - c) / l` at `q = 0`.
    pub fn range(&self, cutoff: f32) -> LightRange {
        let Light::Point { attenuation, .. } = *self else {
            return LightRange::Everywhere;
        };
        if cutoff <= 0.0 {
            return LightRange::Everywhere;
        }
        let peak = f64::from(self.color().max_element());
        let k = peak / f64::from(cutoff);
        let (c, l, q) = (
            f64::from(attenuation.x),
            f64::from(attenuation.y),
            f64::from(attenuation.z),
        );
        if c > k || peak == 0.0 {
            return LightRange::Nowhere;
        }
        if l == 0.0 && q == 0.0 {
            return LightRange::Everywhere;
        }
        let slack = k - c;
        let d = 2.0 * slack / (l + (l * l + 4.0 * q * slack).sqrt());
        if d.is_finite() && d < f64::from(f32::MAX) {
            LightRange::Within(d as f32)
        } else {
            LightRange::Everywhere
        }
    }

    /// The light's colour (times intensity).
    pub fn color(&self) -> Vec3 {
        match *self {
            Light::Point { color, .. } | Light::Directional { color, .. } => color,
        }
    }

    /// The attenuation factor at `distance` from the light:
    /// `1 / (c + l d + q d^2)` for a point light (infinite when the
    /// denominator is zero, i.e. `c = 0` at the light itself) and 1 for a
    /// directional light.
    pub fn attenuation_at(&self, distance: f32) -> f32 {
        match *self {
            Light::Point { attenuation, .. } => {
                let d = distance.max(0.0);
                let denominator = attenuation.x + attenuation.y * d + attenuation.z * d * d;
                if denominator > 0.0 {
                    1.0 / denominator
                } else {
                    f32::INFINITY
                }
            }
            Light::Directional { .. } => 1.0,
        }
    }

    /// The light's window at `cutoff`: what the renderer subtracts from
    /// [`Light::attenuation_at`] before clamping at 0, `cutoff / peak` with
    /// `peak` the largest colour component (0 for a zero cutoff, a black
    /// light or a directional light).
    ///
    /// A point light's colour at distance `d` is
    /// `color * max(1 / (c + l d + q d^2) - cutoff / peak, 0)`: its strongest
    /// component reaches exactly 0 where [`Light::strength_at`] falls to
    /// the cutoff, at the end of [`Light::range`], and stays 0 beyond. So
    /// culling lights outside their range, per object (forward lighting)
    /// or per screen tile (deferred), leaves every pixel as it would be
    /// without culling, whatever the granularity; the cost is that every
    /// point light is `cutoff / peak` of its colour dimmer everywhere.
    pub fn window(&self, cutoff: f32) -> f32 {
        let peak = self.color().max_element();
        match self {
            Light::Point { .. } if cutoff > 0.0 && peak > 0.0 => cutoff / peak,
            _ => 0.0,
        }
    }

    /// Largest colour component of the light as seen at `distance`: the
    /// quantity compared with `Scene::light_cutoff` when culling (before
    /// the window, [`Light::window`]).
    pub fn strength_at(&self, distance: f32) -> f32 {
        let peak = self.color().max_element();
        if peak == 0.0 {
            // Avoids 0 * inf = NaN for a black light with c = 0.
            0.0
        } else {
            peak * self.attenuation_at(distance)
        }
    }
}
