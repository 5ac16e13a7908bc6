//! The value checks every table of a scene file shares (`file.rs` for the
//! scene, `sky.rs` for `[sun]` and `[atmosphere]`): one copy of each, so a
//! number, vector, length or direction is refused with the same words
//! wherever it is written.
//!
//! Numbers arrive as f64 (see `file.rs`). Checks that hand the value to
//! the GPU narrow it to f32 and say so when it does not fit; the sky keeps
//! f64 and uses the checks that do not narrow.

use std::path::Path;

use glam::{DVec3, Vec3};

use super::SceneError;

/// Largest accepted coordinate magnitude (positions, translations): large
/// enough for planet-scale scenes (the Moon is 3.8e8 m away), small enough
/// that sums, differences and squares of coordinates stay finite in
/// 32-bit floats. Precision at this scale is the scene's business: a
/// 32-bit float places objects 1e9 away to within about 64 units.
pub const MAX_COORDINATE: f64 = 1e9;
/// Accepted range of every length (shape sizes, `near`) and scale factor.
pub const MIN_LENGTH: f64 = 1e-6;
/// See [`MIN_LENGTH`].
pub const MAX_LENGTH: f64 = 1e9;
/// Largest accepted colour, reflectance or light colour times intensity
/// per channel, and attenuation term: keeps every lighting sum finite in
/// 32-bit floats.
pub const MAX_COLOUR: f64 = 1e6;

pub(super) type Result<T> = std::result::Result<T, SceneError>;

/// Validation context: where messages say the error is, and where textures
/// are looked up.
pub(super) struct Check<'a> {
    pub(super) file: &'a str,
    pub(super) base_dir: &'a Path,
}

/// `x` (finite) as an f32, or why it cannot be one.
fn narrow(x: f64) -> std::result::Result<f32, String> {
    if x.abs() > f64::from(f32::MAX) {
        return Err(format!(
            "is {x:e}, out of range (32-bit floats reach about 3.4e38)"
        ));
    }
    if x != 0.0 && x.abs() < f64::from(f32::MIN_POSITIVE) {
        return Err(format!(
            "is {x:e}, too close to 0 for a 32-bit float (the smallest is about 1.2e-38)"
        ));
    }
    Ok(x as f32)
}

impl Check<'_> {
    pub(super) fn invalid(
        &self,
        field: impl Into<String>,
        reason: impl Into<String>,
    ) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_owned(),
            field: field.into(),
            reason: reason.into(),
        }
    }

    /// `x`, if it is a finite number.
    pub(super) fn number(&self, field: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(field, format!("must be a finite number, got {x}")))
        }
    }

    /// `x` narrowed to f32: finite, and neither too large for f32 nor so
    /// small that it would become 0 or lose precision (subnormal).
    pub(super) fn finite(&self, field: &str, x: f64) -> Result<f32> {
        let x = self.number(field, x)?;
        narrow(x).map_err(|reason| self.invalid(field, reason))
    }

    /// Component `i` of the vector at `field`, if it is a finite number.
    fn component(&self, field: &str, i: usize, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(
                field,
                format!("component {i} must be a finite number, got {x}"),
            ))
        }
    }

    /// `v`, if every component is a finite number.
    pub(super) fn vector(&self, field: &str, v: [f64; 3]) -> Result<DVec3> {
        for (i, x) in v.iter().enumerate() {
            self.component(field, i, *x)?;
        }
        Ok(DVec3::from(v))
    }

    /// `v` narrowed to f32, component by component (see [`Check::finite`]).
    pub(super) fn vec3(&self, field: &str, v: [f64; 3]) -> Result<Vec3> {
        let mut out = [0f32; 3];
        for (i, x) in v.iter().enumerate() {
            let x = self.component(field, i, *x)?;
            out[i] = narrow(x)
                .map_err(|reason| self.invalid(field, format!("component {i} {reason}")))?;
        }
        Ok(Vec3::from(out))
    }

    /// A position: every component within `MAX_COORDINATE`.
    pub(super) fn coordinates(&self, field: &str, v: [f64; 3]) -> Result<DVec3> {
        self.vec3(field, v)?;
        let c = DVec3::from_array(v);
        if let Some(i) = v.iter().position(|x| x.abs() > MAX_COORDINATE) {
            return Err(self.invalid(
                field,
                format!(
                    "component {i} must be between -{MAX_COORDINATE:e} and {MAX_COORDINATE:e}, \
                     got {:e} (the renderer's limit for world positions)",
                    v[i]
                ),
            ));
        }
        Ok(c)
    }

    /// A colour or other per-channel factor: finite, >= 0 and at most
    /// `MAX_COLOUR` (> 1 is fine, the pipeline is HDR).
    pub(super) fn colour(&self, field: &str, v: [f64; 3]) -> Result<Vec3> {
        let c = self.vec3(field, v)?;
        if let Some(i) = v.iter().position(|&x| x < 0.0) {
            return Err(self.invalid(
                field,
                format!("component {i} must not be negative, got {}", v[i]),
            ));
        }
        if let Some(i) = v.iter().position(|&x| x > MAX_COLOUR) {
            return Err(self.invalid(
                field,
                format!(
                    "component {i} must be at most {MAX_COLOUR:e}, got {:e}",
                    v[i]
                ),
            ));
        }
        Ok(c)
    }

    /// A vector of coefficients kept in f64: every component finite and
    /// within `0..=max` (bounded like colours, so products with path
    /// lengths of 1e9 m stay finite).
    pub(super) fn components_up_to(&self, field: &str, v: [f64; 3], max: f64) -> Result<DVec3> {
        let d = self.vector(field, v)?;
        for (i, x) in v.iter().enumerate() {
            if *x < 0.0 || *x > max {
                return Err(self.invalid(
                    field,
                    format!("component {i} must be between 0 and {max:e}, got {x:e}"),
                ));
            }
        }
        Ok(d)
    }

    pub(super) fn positive(&self, field: &str, x: f64) -> Result<f32> {
        if x.is_finite() && x <= 0.0 {
            return Err(self.invalid(field, format!("must be greater than 0, got {x}")));
        }
        self.finite(field, x)
    }

    /// A length or scale factor: within `MIN_LENGTH..=MAX_LENGTH`.
    pub(super) fn length(&self, field: &str, x: f64) -> Result<f32> {
        if !x.is_finite() || x <= 0.0 {
            return self.positive(field, x);
        }
        if !(MIN_LENGTH..=MAX_LENGTH).contains(&x) {
            return Err(self.invalid(
                field,
                format!("must be between {MIN_LENGTH:e} and {MAX_LENGTH:e}, got {x:e}"),
            ));
        }
        self.finite(field, x)
    }

    pub(super) fn non_negative(&self, field: &str, x: f64) -> Result<f32> {
        let v = self.finite(field, x)?;
        if x >= 0.0 {
            Ok(v)
        } else {
            Err(self.invalid(field, format!("must not be negative, got {x}")))
        }
    }

    /// A finite number for which `ok` holds, kept in f64, or an error
    /// saying what it `must` be.
    pub(super) fn within(
        &self,
        field: &str,
        x: f64,
        ok: &dyn Fn(f64) -> bool,
        must: &str,
    ) -> Result<f64> {
        let x = self.number(field, x)?;
        if ok(x) {
            Ok(x)
        } else {
            Err(self.invalid(field, format!("must be {must}, got {x:e}")))
        }
    }

    /// A direction or axis, returned normalised (in f64; the caller
    /// narrows it if the GPU wants it). Normalised after dividing by the
    /// largest component, so neither huge nor tiny components overflow or
    /// underflow on the way.
    pub(super) fn direction(&self, field: &str, v: [f64; 3], what: &str) -> Result<DVec3> {
        let v = self.vector(field, v)?;
        let largest = v.abs().max_element();
        if largest == 0.0 {
            return Err(self.invalid(field, format!("{what} has zero length")));
        }
        Ok((v / largest).normalize())
    }
}
