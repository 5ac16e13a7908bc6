//! The pinhole [`Camera`] and its view and reversed-Z projection matrices.

use glam::{DMat4, DVec3, DVec4, Mat4, Vec3};

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position in world space (f64: scenes far from the origin keep their
    /// metre-scale detail; see [`Camera::view`]).
    pub eye: DVec3,
    /// Point the camera looks at; differs from `eye`.
    pub look_at: DVec3,
    /// Approximate up direction; not parallel to `look_at - eye`.
    pub up: Vec3,
    /// Vertical field of view in degrees, in `(0, 180)`.
    pub fov_y_degrees: f32,
    /// Distance to the near plane, > 0.
    pub near: f32,
    /// Distance to the far plane (> `near`), or `None` for an infinite far
    /// plane.
    pub far: Option<f32>,
}

impl Camera {
    /// Camera-relative world to view: right-handed, the camera looks down
    /// `-Z` with `+Y` up in view space. Its input is a world position minus
    /// [`Camera::eye`] (computed in f64), so the matrix is a pure rotation
    /// and the GPU never sees a world coordinate: a scene 1e9 m from the
    /// origin renders like one at the origin.
    pub fn view(&self) -> Mat4 {
        self.view_f64().as_mat4()
    }

    /// [`Camera::view`] in f64.
    pub fn view_f64(&self) -> DMat4 {
        // In f64: the view direction is normalised from a difference that
        // may be tiny (or large) for f32, which would give NaN there.
        DMat4::look_at_rh(DVec3::ZERO, self.look_at - self.eye, self.up.as_dvec3())
    }

    /// A world position relative to the camera (`p - eye`, in f64), the
    /// space every GPU position is in.
    pub fn relative(&self, p: DVec3) -> DVec3 {
        p - self.eye
    }

    /// View-to-clip matrix for Vulkan with reversed Z.
    ///
    /// With `f = 1 / tan(fov_y / 2)`: `x_c = f / aspect * x_v`,
    /// `y_c = -f * y_v` (Vulkan's NDC `y` points down, so the flip keeps the
    /// image upright), `w_c = -z_v` and `z_c = A * (-z_v) + B`, where
    /// `A = -near / (far - near)`, `B = near * far / (far - near)` for a
    /// finite far plane and `A = 0`, `B = near` for an infinite one. NDC
    /// depth is therefore 1 at the near plane and falls towards 0 at the far
    /// plane (or infinity), which spreads float precision evenly over depth.
    ///
    /// An `aspect` that is not a positive finite number is treated as 1 so
    /// that the matrix stays finite; `Scene` output sizes are validated, so
    /// this only guards direct callers.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        self.projection_f64(aspect).as_mat4()
    }

    /// [`Camera::projection`] in f64.
    pub fn projection_f64(&self, aspect: f32) -> DMat4 {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            f64::from(aspect)
        } else {
            1.0
        };
        // f64 because A and B are differences of nearly equal quantities
        // when far/near is large (1e9 and more).
        let f = 1.0 / (f64::from(self.fov_y_degrees).to_radians() * 0.5).tan();
        let near = f64::from(self.near);
        let (a, b) = match self.far {
            Some(far) => {
                let far = f64::from(far);
                (-near / (far - near), near * far / (far - near))
            }
            None => (0.0, near),
        };
        // Columns: z_c = A * (-z_v) + B * w_v means column 2 holds -A in the
        // z row and column 3 holds B; w_c = -z_v puts -1 in column 2's w row.
        DMat4::from_cols(
            DVec4::new(f / aspect, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -f, 0.0, 0.0),
            DVec4::new(0.0, 0.0, -a, -1.0),
            DVec4::new(0.0, 0.0, b, 0.0),
        )
    }

    /// `projection(aspect) * view()`: camera-relative world (`p - eye`) to
    /// clip space, composed in f64 and rounded once.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.view_projection_f64(aspect).as_mat4()
    }

    /// [`Camera::view_projection`] in f64.
    pub fn view_projection_f64(&self, aspect: f32) -> DMat4 {
        self.projection_f64(aspect) * self.view_f64()
    }

    /// Unit vector from `eye` towards `look_at`.
    pub fn forward(&self) -> Vec3 {
        (self.look_at - self.eye).normalize_or_zero().as_vec3()
    }
}
