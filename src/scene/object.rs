//! Scene [`Object`]s: an analytic [`Shape`] or a loaded mesh, how finely to tessellate it, a
//! material and a [`Transform`].

use std::sync::Arc;

use glam::{DMat4, DQuat, DVec3, Mat3, Mat4, Quat, Vec3};

use crate::mesh::{
    CylinderSurface, FlagSurface, Mesh, ParametricSurface, PlaneSurface, SphereSurface,
    TorusSurface,
};

/// One object to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Name, for messages and debugging.
    pub name: String,
    /// The surface.
    pub shape: Shape,
    /// `(u_segments, v_segments)`, each in `3..=4096`; for an auto object
    /// the grid a numeric `tessellation` knob scales instead.
    pub tessellation: (u32, u32),
    /// `tessellation = "auto"`: the grid is chosen by screen-space error
    /// when the mesh is built (`Scene::object_tessellation`), not
    /// `tessellation`. Only for parametric shapes.
    pub auto_tessellation: bool,
    /// Index into `Scene::materials`.
    pub material: usize,
    /// Object-to-world transform.
    pub transform: Transform,
    /// Draw both sides of the object's faces whatever its material says
    /// (as [`crate::scene::Material::two_sided`]).
    pub two_sided: bool,
    /// Drawn into the shadow map (when a light casts shadows); opaque
    /// objects only.
    pub casts_shadows: bool,
}

impl Object {
    /// Whether the object's faces are drawn from both sides: its own
    /// `two_sided` or its material's (`material`, its entry in
    /// `Scene::materials`).
    pub fn is_two_sided(&self, material: &crate::scene::Material) -> bool {
        self.two_sided || material.two_sided
    }
}

/// Object-to-world transform: scale, then rotate, then translate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Translation (f64, like every world position: see `Camera::view`).
    pub translate: DVec3,
    /// Rotation axis; unit length after loading.
    pub rotate_axis: Vec3,
    /// Rotation angle in degrees, counter-clockwise looking down the axis
    /// towards the origin (right-hand rule).
    pub rotate_degrees: f32,
    /// Per-axis scale; every component > 0 after loading.
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            translate: DVec3::ZERO,
            rotate_axis: Vec3::Y,
            rotate_degrees: 0.0,
            scale: Vec3::ONE,
        }
    }
}

impl Transform {
    /// The rotation as a quaternion. A zero axis (only possible when the
    /// struct is built by hand) means no rotation rather than NaN.
    pub fn rotation(&self) -> Quat {
        match self.rotate_axis.try_normalize() {
            Some(axis) => Quat::from_axis_angle(axis, self.rotate_degrees.to_radians()),
            None => Quat::IDENTITY,
        }
    }

    /// `T * R * S` in f64.
    pub fn matrix_f64(&self) -> DMat4 {
        let rotation = match self.rotate_axis.as_dvec3().try_normalize() {
            Some(axis) => DQuat::from_axis_angle(axis, f64::from(self.rotate_degrees).to_radians()),
            None => DQuat::IDENTITY,
        };
        DMat4::from_scale_rotation_translation(self.scale.as_dvec3(), rotation, self.translate)
    }

    /// `T * R * S` rounded to f32 (exact only near the origin).
    pub fn matrix(&self) -> Mat4 {
        self.matrix_f64().as_mat4()
    }

    /// `T' * R * S` with `T'` the translation relative to `origin` (the
    /// camera), composed in f64 and only then rounded to f32: what the GPU
    /// transforms vertices with, so a scene far from the world origin keeps
    /// its detail near the camera.
    pub fn matrix_relative_to(&self, origin: DVec3) -> Mat4 {
        Transform {
            translate: self.translate - origin,
            ..*self
        }
        .matrix_f64()
        .as_mat4()
    }

    /// Inverse transpose of the upper 3x3 of [`Transform::matrix`], for
    /// transforming normals.
    pub fn normal_matrix(&self) -> Mat3 {
        // (R S)^-T = R^-T S^-T = R S^-1 because R is orthonormal and S
        // diagonal; this avoids a general 3x3 inverse and its round-off.
        Mat3::from_quat(self.rotation()) * Mat3::from_diagonal(self.scale.recip())
    }

    /// Largest absolute scale component: how much the transform can stretch
    /// a distance, used to scale bounding-sphere radii.
    pub fn max_scale(&self) -> f32 {
        self.scale.abs().max_element()
    }
}

/// An analytic surface with its dimensions (all lengths > 0 after loading).
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Sphere centred at the origin.
    Sphere {
        /// Radius.
        radius: f32,
    },
    /// Torus around the `Y` axis, centred at the origin.
    Torus {
        /// Distance from the centre to the middle of the tube.
        major_radius: f32,
        /// Tube radius (may exceed `major_radius`: a spindle torus).
        minor_radius: f32,
    },
    /// Rectangle in the `XZ` plane, centred at the origin, normal `+Y`.
    Plane {
        /// Extent along `X`.
        width: f32,
        /// Extent along `Z`.
        depth: f32,
    },
    /// Open cylinder around the `Y` axis, centred at the origin.
    Cylinder {
        /// Radius.
        radius: f32,
        /// Height along `Y`.
        height: f32,
    },
    /// Waving flag `r(u, v) = [u W, v H, D sin(K u + alpha)]`, hanging from
    /// a pole along the `Y` axis and extending along `+X`.
    Flag {
        /// `W`, extent along `X`.
        width: f32,
        /// `H`, extent along `Y`.
        height: f32,
        /// `D`, wave amplitude along `Z`.
        amplitude: f32,
        /// `K`, radians of wave over the whole width.
        frequency: f32,
        /// `alpha`, radians.
        phase: f32,
    },
    /// A triangle mesh loaded from a model file (one object or group of an
    /// OBJ), already smoothed and given tangent frames; shared, so that a
    /// scene clone does not copy it.
    Mesh {
        /// The mesh in object space.
        mesh: Arc<Mesh>,
    },
}

impl Shape {
    /// The parametric surface to tessellate; `None` for a loaded mesh.
    pub fn surface(&self) -> Option<Box<dyn ParametricSurface>> {
        let f = f64::from;
        Some(match *self {
            Shape::Mesh { .. } => return None,
            Shape::Sphere { radius } => Box::new(SphereSurface { radius: f(radius) }),
            Shape::Torus {
                major_radius,
                minor_radius,
            } => Box::new(TorusSurface {
                major_radius: f(major_radius),
                minor_radius: f(minor_radius),
            }),
            Shape::Plane { width, depth } => Box::new(PlaneSurface {
                width: f(width),
                depth: f(depth),
            }),
            Shape::Cylinder { radius, height } => Box::new(CylinderSurface {
                radius: f(radius),
                height: f(height),
            }),
            Shape::Flag {
                width,
                height,
                amplitude,
                frequency,
                phase,
            } => Box::new(FlagSurface {
                width: f(width),
                height: f(height),
                amplitude: f(amplitude),
                frequency: f(frequency),
                phase: f(phase),
            }),
        })
    }

    /// The `type` name used in scene files.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Shape::Sphere { .. } => "sphere",
            Shape::Torus { .. } => "torus",
            Shape::Plane { .. } => "plane",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Flag { .. } => "flag",
            Shape::Mesh { .. } => "obj",
        }
    }
}
