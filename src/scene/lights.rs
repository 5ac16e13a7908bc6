//! Light sources and the attenuation model used for per-object culling.

use glam::Vec3;

/// A light source. Colours are linear RGB, already multiplied by the
/// intensity given in the scene file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A point light whose contribution is scaled by
    /// `1 / (c + l d + q d^2)` at distance `d`.
    Point {
        /// World-space position.
        position: Vec3,
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

impl Light {
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

    /// Largest colour component of the light as seen at `distance`: the
    /// quantity compared with `Scene::light_cutoff` when culling.
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
