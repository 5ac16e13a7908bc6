//! Where the shadow map looks from: an orthographic view along the
//! shadow-casting light, fitted to the casters that can shadow what the
//! camera sees.
//!
//! The map covers, across the light, the intersection of three boxes in
//! the light's frame: the camera's frustum (cut at the far side of the
//! farthest object in view), the objects in view (the receivers) and the
//! casters. Nothing outside the first two is ever looked up, and nothing
//! outside the last is ever in shadow, so every texel the lookup can reach
//! is spent where a shadow can fall. Along the light it spans from the
//! caster nearest the light to the farthest receiver, so no caster is
//! clipped (a caster behind the camera still shadows what is in view).
//! For the sun, whose shadows also fall on the planet's ground, the map
//! covers the casters whole, and ground beyond its far side compares as
//! its farthest depth (`shadow_map.glsl` clamps), so it is shadowed
//! exactly where a caster covers the texel.
//! Texels are not snapped to a world grid: each frame is fitted on its own
//! (a moving camera's shadows may shimmer by a texel).

use super::draw_list::Draw;
use super::geometry::SceneGeometry;
use super::sky_resources::ray_basis;
use crate::scene::{Light, Scene, ShadowLight, Shape};
use glam::{DMat4, DVec3, DVec4};

/// The shadow map's view for one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowView {
    /// Camera-relative position (as every position the GPU sees) to the
    /// light's clip space: x, y in [-1, 1] across the map, z in [0, 1]
    /// from the caster nearest the light.
    pub view_projection: DMat4,
    /// The world-space width of one texel (the larger of its two sides).
    pub texel: f64,
    /// Whether the light is the atmosphere's sun (else a scene light).
    pub sun: bool,
    /// The draws drawn into the map: every opaque draw, in view or not,
    /// whose objects cast shadows.
    pub casters: Vec<Draw>,
}

/// The unit direction `light` travels in `scene`.
pub fn light_direction(scene: &Scene, light: ShadowLight) -> Option<DVec3> {
    match light {
        ShadowLight::Light(i) => match scene.lights.get(i)? {
            Light::Directional { direction, .. } => Some(direction.as_dvec3().normalize()),
            Light::Point { .. } => None,
        },
        ShadowLight::Sun => Some(-scene.sky.as_ref()?.sun.direction.normalize()),
    }
}

/// Whether any of `objects` (a draw's) may shadow something in view
/// (`in_view`): false only for a flat caster (a plane, which cannot shadow
/// itself) with every vertex of every other object in view on its lit
/// side, where nothing lies behind it. The sun's planet ground may lie
/// behind any caster, so under the sun every caster may shadow. Drawing
/// such a plane into the map (a ground plane under the objects, say)
/// would fill every texel for nothing.
pub fn may_shadow(
    scene: &Scene,
    geometry: &SceneGeometry,
    in_view: &[usize],
    objects: &[usize],
) -> bool {
    let Some(light) = scene.shadow_light else {
        return false;
    };
    let Some(direction) = light_direction(scene, light) else {
        return false;
    };
    if light == ShadowLight::Sun {
        return true;
    }
    objects.iter().any(|&o| {
        let object = &scene.objects[o];
        if !matches!(object.shape, Shape::Plane { .. }) {
            return true;
        }
        let normal = (object.transform.normal_matrix() * glam::Vec3::Y)
            .as_dvec3()
            .normalize();
        // The side the light comes from.
        let lit_side = if normal.dot(direction) < 0.0 {
            normal
        } else {
            -normal
        };
        let origin = object.transform.translate;
        // A vertex this far behind the plane (relative to the scene's
        // size) still counts as on it: objects resting on a plane touch it.
        let tolerance = 1e-6 * f64::from(geometry.bounds[o].1);
        in_view.iter().filter(|&&r| r != o).any(|&r| {
            let model = scene.objects[r].transform.matrix_f64();
            geometry.meshes[r].vertices.iter().any(|v| {
                let p = model.transform_point3(glam::Vec3::from(v.position).as_dvec3());
                (p - origin).dot(lit_side) < -tolerance
            })
        })
    })
}

/// An axis-aligned box in the light's frame (x, y across, z along).
#[derive(Clone, Copy, Debug)]
struct LightBox {
    min: DVec3,
    max: DVec3,
}

impl LightBox {
    const EMPTY: LightBox = LightBox {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    fn add(&mut self, p: DVec3, radius: f64) {
        self.min = self.min.min(p - radius);
        self.max = self.max.max(p + radius);
    }

    fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y
    }
}

impl ShadowView {
    /// The view for `scene`'s shadow light, or `None` when it casts none
    /// (no such light). `bounds` are the objects' world bounding spheres,
    /// `in_view` the objects on screen, `casters` the draws drawn into the
    /// map, `side` the map's width in texels.
    pub fn fit(
        scene: &Scene,
        bounds: &[(DVec3, f32)],
        in_view: &[usize],
        casters: Vec<Draw>,
        side: u32,
    ) -> Option<ShadowView> {
        let light = scene.shadow_light?;
        let direction = light_direction(scene, light)?;
        // The light's frame: z along the light, x and y across it.
        let helper = if direction.y.abs() < 0.9 {
            DVec3::Y
        } else {
            DVec3::X
        };
        let x_axis = helper.cross(direction).normalize();
        let y_axis = direction.cross(x_axis);
        let to_light = |p: DVec3| DVec3::new(p.dot(x_axis), p.dot(y_axis), p.dot(direction));

        let mut receivers = LightBox::EMPTY;
        let mut farthest = 0.0_f64;
        for &o in in_view {
            let (c, r) = bounds[o];
            receivers.add(to_light(c), f64::from(r));
            farthest = farthest.max(c.distance(scene.camera.eye) + f64::from(r));
        }
        let mut caster_box = LightBox::EMPTY;
        for d in &casters {
            for &o in d.objects() {
                let (c, r) = bounds[o];
                caster_box.add(to_light(c), f64::from(r));
            }
        }
        // Across the light: where a shadow can fall on screen. The sun
        // also shadows the planet's ground, which lies under every caster
        // and may be seen beyond the farthest object: its map covers the
        // casters.
        let frustum = frustum_box(scene, farthest, &to_light);
        let mut across = if light == ShadowLight::Sun {
            caster_box
        } else {
            LightBox {
                min: receivers.min.max(frustum.min).max(caster_box.min),
                max: receivers.max.min(frustum.max).min(caster_box.max),
            }
        };
        if across.is_empty() {
            // No caster over anything in view: any small map will do.
            across = if receivers.is_empty() {
                caster_box
            } else {
                receivers
            };
        }
        if across.is_empty() {
            return None;
        }
        // Along it: from the nearest caster to the farthest receiver, a
        // little beyond both so that nothing sits exactly on a plane.
        let near = caster_box.min.z.min(receivers.min.z);
        let far = caster_box.max.z.max(receivers.max.z);
        let depth_pad = 1e-3 * (far - near).max(1e-6);
        let (near, far) = (near - depth_pad, far + depth_pad);
        // A texel's margin around the box, so the filter's taps at its
        // edge read the map, not its border.
        let width = (across.max.x - across.min.x).max(across.max.y - across.min.y);
        let margin = 4.0 * width / f64::from(side);
        let (x0, x1) = (across.min.x - margin, across.max.x + margin);
        let (y0, y1) = (across.min.y - margin, across.max.y + margin);
        let world_to_light = DMat4::from_cols(
            x_axis.extend(0.0),
            y_axis.extend(0.0),
            direction.extend(0.0),
            DVec4::W,
        )
        .transpose();
        let ortho = DMat4::from_cols(
            DVec4::new(2.0 / (x1 - x0), 0.0, 0.0, 0.0),
            DVec4::new(0.0, 2.0 / (y1 - y0), 0.0, 0.0),
            DVec4::new(0.0, 0.0, 1.0 / (far - near), 0.0),
            DVec4::new(
                -(x1 + x0) / (x1 - x0),
                -(y1 + y0) / (y1 - y0),
                -near / (far - near),
                1.0,
            ),
        );
        let camera_relative = DMat4::from_translation(scene.camera.eye);
        Some(ShadowView {
            view_projection: ortho * world_to_light * camera_relative,
            texel: (x1 - x0).max(y1 - y0) / f64::from(side),
            sun: light == ShadowLight::Sun,
            casters,
        })
    }
}

/// The light-frame box around the camera's frustum from its near plane to
/// `reach` from the eye (at least the near plane).
fn frustum_box(scene: &Scene, reach: f64, to_light: &dyn Fn(DVec3) -> DVec3) -> LightBox {
    let camera = &scene.camera;
    let aspect = f64::from(scene.output.width) / f64::from(scene.output.height);
    let (forward, right, up) = ray_basis(camera, aspect);
    let near = f64::from(camera.near);
    let mut frustum = LightBox::EMPTY;
    // The corners' rays have length |corner| per unit of view depth, so
    // depth `reach` along them reaches at least `reach` from the eye.
    for depth in [near, reach.max(near)] {
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                let p = camera.eye + (forward + right * sx + up * sy) * depth;
                frustum.add(to_light(p), 0.0);
            }
        }
    }
    frustum
}
