//! The analytic surfaces the scene format offers: sphere, torus, plane, open
//! cylinder and waving flag, each a [`ParametricSurface`] with exact first
//! derivatives.
//!
//! Every closed surface is parameterised so that `du x dv` points outward,
//! the plane so that it points to `+Y` and the flag so that it points to
//! `+Z` (tilted by the wave); the tessellator relies on this for its
//! counter-clockwise front faces. The seam of the closed surfaces (`u = 0`
//! and `u = 1`) is placed on the `-Z` side, away from a camera on `+Z`.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::surface::{derived_normal, ParametricSurface};

/// Azimuth for the closed surfaces: `u = 0` and `u = 1` both map to `-Z`.
fn azimuth(u: f64) -> f64 {
    TAU * u - PI
}

/// Sphere of the given radius centred at the origin.
///
/// `u` runs around the `Y` axis, `v` from the south pole (`v = 0`, `-Y`) to
/// the north pole (`v = 1`, `+Y`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereSurface {
    /// Radius, > 0.
    pub radius: f64,
}

impl ParametricSurface for SphereSurface {
    fn position(&self, u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        let theta = PI * v;
        self.radius
            * DVec3::new(
                theta.sin() * phi.sin(),
                -theta.cos(),
                theta.sin() * phi.cos(),
            )
    }

    fn du(&self, u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        let ring = self.radius * (PI * v).sin();
        TAU * ring * DVec3::new(phi.cos(), 0.0, -phi.sin())
    }

    fn dv(&self, u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        let theta = PI * v;
        PI * self.radius
            * DVec3::new(
                theta.cos() * phi.sin(),
                theta.sin(),
                theta.cos() * phi.cos(),
            )
    }

    /// Exactly radial, including at the poles where `du` vanishes.
    fn normal(&self, u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        let theta = PI * v;
        DVec3::new(
            theta.sin() * phi.sin(),
            -theta.cos(),
            theta.sin() * phi.cos(),
        )
    }

    /// The direction of `du`, which stays well defined at the poles even
    /// though `du` itself is zero there.
    fn tangent(&self, u: f64, _v: f64) -> DVec3 {
        let phi = azimuth(u);
        DVec3::new(phi.cos(), 0.0, -phi.sin())
    }
}

/// Torus around the `Y` axis, centred at the origin.
///
/// `u` runs around the `Y` axis (the major circle), `v` around the tube,
/// starting at the outer equator and going up first. A minor radius at or
/// above the major radius gives a self-intersecting (horn or spindle) torus;
/// that is allowed, and the normal then follows `du x dv`, which flips on the
/// inner part, so that normals and winding always agree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorusSurface {
    /// Distance from the centre to the middle of the tube, > 0.
    pub major_radius: f64,
    /// Radius of the tube, > 0.
    pub minor_radius: f64,
}

impl TorusSurface {
    /// Outward normal of the tube, independent of the orientation flip.
    fn tube_normal(u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        let theta = TAU * v;
        DVec3::new(
            theta.cos() * phi.sin(),
            theta.sin(),
            theta.cos() * phi.cos(),
        )
    }

    /// Distance of the point from the `Y` axis, signed: negative on the part
    /// of a spindle torus that has passed through the axis.
    fn ring(&self, v: f64) -> f64 {
        self.major_radius + self.minor_radius * (TAU * v).cos()
    }
}

impl ParametricSurface for TorusSurface {
    fn position(&self, u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        let ring = self.ring(v);
        DVec3::new(
            ring * phi.sin(),
            self.minor_radius * (TAU * v).sin(),
            ring * phi.cos(),
        )
    }

    fn du(&self, u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        TAU * self.ring(v) * DVec3::new(phi.cos(), 0.0, -phi.sin())
    }

    fn dv(&self, u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        let theta = TAU * v;
        TAU * self.minor_radius
            * DVec3::new(
                -theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            )
    }

    fn normal(&self, u: f64, v: f64) -> DVec3 {
        let ring = self.ring(v);
        // du x dv = 4 pi^2 r ring * tube_normal, so its direction is the tube
        // normal times the sign of `ring`. Where `ring` is (nearly) zero the
        // surface pinches to a point on the axis and the generic fallback
        // picks the limit from one side.
        if ring.abs() > 1e-9 * (self.major_radius + self.minor_radius) {
            ring.signum() * Self::tube_normal(u, v)
        } else {
            derived_normal(self, u, v)
        }
    }
}

/// Rectangle in the `XZ` plane, centred at the origin, normal `+Y`.
///
/// `u` runs along `+X`, `v` along `-Z` (so that `du x dv` is `+Y`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneSurface {
    /// Extent along `X`, > 0.
    pub width: f64,
    /// Extent along `Z`, > 0.
    pub depth: f64,
}

impl ParametricSurface for PlaneSurface {
    fn position(&self, u: f64, v: f64) -> DVec3 {
        DVec3::new((u - 0.5) * self.width, 0.0, (0.5 - v) * self.depth)
    }

    fn du(&self, _u: f64, _v: f64) -> DVec3 {
        DVec3::new(self.width, 0.0, 0.0)
    }

    fn dv(&self, _u: f64, _v: f64) -> DVec3 {
        DVec3::new(0.0, 0.0, -self.depth)
    }
}

/// Open cylinder (no caps) around the `Y` axis, centred at the origin.
///
/// `u` runs around the axis, `v` from the bottom (`y = -height / 2`) to the
/// top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CylinderSurface {
    /// Radius, > 0.
    pub radius: f64,
    /// Height along `Y`, > 0.
    pub height: f64,
}

impl ParametricSurface for CylinderSurface {
    fn position(&self, u: f64, v: f64) -> DVec3 {
        let phi = azimuth(u);
        DVec3::new(
            self.radius * phi.sin(),
            (v - 0.5) * self.height,
            self.radius * phi.cos(),
        )
    }

    fn du(&self, u: f64, _v: f64) -> DVec3 {
        let phi = azimuth(u);
        TAU * self.radius * DVec3::new(phi.cos(), 0.0, -phi.sin())
    }

    fn dv(&self, _u: f64, _v: f64) -> DVec3 {
        DVec3::new(0.0, self.height, 0.0)
    }
}

/// The waving flag `r(u, v) = [u W, v H, D sin(K u + alpha)]`.
///
/// The pole is the `x = 0` edge, the flag extends along `+X` and `+Y` from
/// the origin and waves in `Z`. `K` is in radians over the whole width, so
/// the flag shows `K / 2 pi` waves. The normal is proportional to
/// `[-K D cos(K u + alpha), 0, W]`, i.e. it faces `+Z` where the cloth is
/// flat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlagSurface {
    /// Extent along `X` (`W`), > 0.
    pub width: f64,
    /// Extent along `Y` (`H`), > 0.
    pub height: f64,
    /// Wave amplitude along `Z` (`D`).
    pub amplitude: f64,
    /// Angular frequency over `u` (`K`), radians per flag width.
    pub frequency: f64,
    /// Phase (`alpha`), radians.
    pub phase: f64,
}

impl ParametricSurface for FlagSurface {
    fn position(&self, u: f64, v: f64) -> DVec3 {
        DVec3::new(
            u * self.width,
            v * self.height,
            self.amplitude * (self.frequency * u + self.phase).sin(),
        )
    }

    fn du(&self, u: f64, _v: f64) -> DVec3 {
        DVec3::new(
            self.width,
            0.0,
            self.amplitude * self.frequency * (self.frequency * u + self.phase).cos(),
        )
    }

    fn dv(&self, _u: f64, _v: f64) -> DVec3 {
        DVec3::new(0.0, self.height, 0.0)
    }
}
