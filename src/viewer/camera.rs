//! The fly-through camera: position and orientation driven by keys and the
//! mouse, with a speed proportional to the height above the nearest
//! surface, so that the same keys work a metre above the ground and at the
//! Moon's distance from the Earth.
//!
//! Until the first input the camera is the scene's own, bit for bit, so
//! the first frame is exactly what `aerial render` draws. State is kept in
//! f64 (planet-scale positions) and handed to the renderer as the scene's
//! f32 [`Camera`].

use crate::render::SceneGeometry;
use crate::scene::{Camera, Scene};
use glam::{DQuat, DVec3};

/// Coordinates are bounded as in scene files, so that the printed camera
/// can be loaded again.
const MAX_COORDINATE: f64 = 0.9e9;
/// The view direction is never closer than this to the up direction
/// (radians), where the view matrix would degenerate.
const MIN_POLE_ANGLE: f64 = 1.0_f64 * std::f64::consts::PI / 180.0;
/// Field of view limits while zooming, degrees.
const FOV_RANGE: (f64, f64) = (0.01, 150.0);
/// Mouse look: radians per pixel of drag at a 45° field of view (scaled
/// with the field of view, so zoomed in the view turns as finely).
const RADIANS_PER_PIXEL: f64 = 0.0025;
/// Zoom: field of view factor per step (wheel notch or +/- press).
const ZOOM_STEP: f64 = 1.1;

/// What the camera measures its height against: the world boxes of the
/// scene's objects and, for a scene with an atmosphere, the planet.
#[derive(Clone, Debug, Default)]
pub struct Surroundings {
    /// World-space axis-aligned boxes (min, max), one per object.
    boxes: Vec<(DVec3, DVec3)>,
    /// Planet centre and ground radius.
    planet: Option<(DVec3, f64)>,
}

impl Surroundings {
    /// The surfaces of `scene`, whose meshes are `geometry`.
    pub fn of(scene: &Scene, geometry: &SceneGeometry) -> Surroundings {
        let boxes = scene
            .objects
            .iter()
            .zip(&geometry.meshes)
            .filter(|(_, mesh)| !mesh.vertices.is_empty())
            .map(|(object, mesh)| {
                let mut lo = DVec3::splat(f64::INFINITY);
                let mut hi = DVec3::splat(f64::NEG_INFINITY);
                for v in &mesh.vertices {
                    let p = DVec3::from(v.position.map(f64::from));
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                // The eight corners of the object-space box, moved: the
                // world box around them holds the moved mesh.
                let m = object.transform.matrix_f64();
                let mut wlo = DVec3::splat(f64::INFINITY);
                let mut whi = DVec3::splat(f64::NEG_INFINITY);
                for i in 0..8 {
                    let corner = DVec3::new(
                        if i & 1 == 0 { lo.x } else { hi.x },
                        if i & 2 == 0 { lo.y } else { hi.y },
                        if i & 4 == 0 { lo.z } else { hi.z },
                    );
                    let w = m.transform_point3(corner);
                    wlo = wlo.min(w);
                    whi = whi.max(w);
                }
                (wlo, whi)
            })
            .collect();
        let planet = scene
            .sky
            .as_ref()
            .map(|s| (s.atmosphere.center, s.atmosphere.bottom_radius));
        Surroundings { boxes, planet }
    }

    /// Distance from `p` to the nearest surface (0 inside an object's box
    /// or below the ground); `None` when the scene has no surface.
    pub fn height(&self, p: DVec3) -> Option<f64> {
        let boxes = self.boxes.iter().map(|(lo, hi)| {
            let outside = (*lo - p).max(p - *hi).max(DVec3::ZERO);
            outside.length()
        });
        let planet = self
            .planet
            .map(|(centre, radius)| (p.distance(centre) - radius).max(0.0));
        boxes.chain(planet).reduce(f64::min)
    }

    /// The local vertical at `p`: away from the planet's centre with one,
    /// `None` without (the camera's own up is used).
    pub fn vertical(&self, p: DVec3) -> Option<DVec3> {
        let (centre, _) = self.planet?;
        (p - centre).try_normalize()
    }
}

/// The camera the keys and mouse move.
#[derive(Clone, Debug)]
pub struct FlyCamera {
    home: Camera,
    /// False until the first input: `camera()` is then `home` exactly.
    moved: bool,
    eye: DVec3,
    /// Unit view direction.
    forward: DVec3,
    /// Unit up reference: yaw turns about it, and it is the camera's up.
    up: DVec3,
    fov_y: f64,
    /// How far ahead the look-at point is placed (its f32 rounding then
    /// bends the direction by a negligible angle).
    look_distance: f64,
}

impl FlyCamera {
    /// A camera starting at (and returning home to) `home`.
    pub fn new(home: Camera) -> FlyCamera {
        let mut camera = FlyCamera {
            home,
            moved: false,
            eye: DVec3::ZERO,
            forward: DVec3::NEG_Z,
            up: DVec3::Y,
            fov_y: 45.0,
            look_distance: 1.0,
        };
        camera.reset();
        camera
    }

    /// Back to the scene's camera, exactly.
    pub fn reset(&mut self) {
        let h = self.home;
        self.moved = false;
        self.eye = h.eye;
        let to = h.look_at - self.eye;
        self.look_distance = to.length();
        self.forward = to.normalize();
        self.up = h.up.as_dvec3().normalize();
        self.fov_y = f64::from(h.fov_y_degrees);
    }

    /// The camera to render with.
    pub fn camera(&self) -> Camera {
        if !self.moved {
            return self.home;
        }
        // Far enough ahead that the f32 look-at point keeps the direction
        // (relative to the eye's own rounding), near enough to stay within
        // the coordinate bounds of a scene file.
        let distance = self.look_distance.max(0.5 * self.eye.length()).min(1e8);
        Camera {
            eye: self.eye,
            look_at: (self.eye + self.forward * distance),
            up: self.up.as_vec3(),
            fov_y_degrees: self.fov_y as f32,
            ..self.home
        }
    }

    pub fn eye(&self) -> DVec3 {
        self.eye
    }

    pub fn forward(&self) -> DVec3 {
        self.forward
    }

    /// Whether the view differs from the scene's camera.
    pub fn moved(&self) -> bool {
        self.moved
    }

    /// Moves by `distance` along the unit direction made of `forward`,
    /// `right` and `up` (each -1, 0 or 1; up is the local vertical of
    /// `surroundings`, or the camera's up). On a planet the orientation is
    /// carried along, so level flight stays level around the globe.
    pub fn translate(
        &mut self,
        forward: f64,
        right: f64,
        up: f64,
        distance: f64,
        surroundings: &Surroundings,
    ) {
        let vertical = surroundings.vertical(self.eye).unwrap_or(self.up);
        let right_axis = self.forward.cross(self.up).normalize_or_zero();
        let direction =
            (self.forward * forward + right_axis * right + vertical * up).normalize_or_zero();
        if direction == DVec3::ZERO || distance <= 0.0 {
            return;
        }
        let before = self.eye;
        self.eye = (self.eye + direction * distance)
            .clamp(DVec3::splat(-MAX_COORDINATE), DVec3::splat(MAX_COORDINATE));
        if let (Some(a), Some(b)) = (
            surroundings.vertical(before),
            surroundings.vertical(self.eye),
        ) {
            let turn = DQuat::from_rotation_arc(a, b);
            self.forward = (turn * self.forward).normalize();
            self.up = (turn * self.up).normalize();
        }
        self.moved = true;
    }

    /// Turns the view as a mouse drag of (dx, dy) pixels: right and down
    /// turn right and down.
    pub fn look(&mut self, dx: f64, dy: f64) {
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        let scale = RADIANS_PER_PIXEL * self.fov_y / 45.0;
        let yaw = DQuat::from_axis_angle(self.up, -dx * scale);
        let mut forward = yaw * self.forward;
        let right = forward.cross(self.up).normalize();
        // Pitch, kept away from straight up and down.
        let angle = forward.angle_between(self.up);
        let pitched =
            (angle + dy * scale).clamp(MIN_POLE_ANGLE, std::f64::consts::PI - MIN_POLE_ANGLE);
        forward = DQuat::from_axis_angle(right, angle - pitched) * forward;
        self.forward = forward.normalize();
        self.moved = true;
    }

    /// Narrows (positive steps) or widens the field of view.
    pub fn zoom(&mut self, steps: f64) {
        if steps == 0.0 {
            return;
        }
        self.fov_y = (self.fov_y / ZOOM_STEP.powf(steps)).clamp(FOV_RANGE.0, FOV_RANGE.1);
        self.moved = true;
    }

    /// Metres a second the camera flies at `height` above the nearest
    /// surface: the height itself (one height a second), never below the
    /// near plane distance, so it slows down as it comes close.
    pub fn speed(&self, height: Option<f64>) -> f64 {
        let floor = f64::from(self.home.near).max(1e-3);
        height.unwrap_or(self.look_distance).max(floor)
    }

    /// The `[camera]` table of a scene file that renders this view.
    pub fn toml(&self) -> String {
        let c = self.camera();
        let v = |v: glam::DVec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
        let mut text = format!(
            "[camera]\neye = {}\nlook_at = {}\nup = {}\nfov_y = {}\nnear = {}\n",
            v(c.eye),
            v(c.look_at),
            v(c.up.as_dvec3()),
            c.fov_y_degrees,
            c.near
        );
        if let Some(far) = c.far {
            text.push_str(&format!("far = {far}\n"));
        }
        text
    }
}

/// The sun direction turned by `radians` along its arc over `vertical`
/// (the local vertical): positive angles lower it, negative raise it,
/// through the zenith when it is overhead.
pub fn turn_sun(direction: DVec3, vertical: DVec3, radians: f64) -> DVec3 {
    let axis = vertical
        .cross(direction)
        .try_normalize()
        .unwrap_or_else(|| vertical.any_orthonormal_vector());
    (DQuat::from_axis_angle(axis, radians) * direction).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn home() -> Camera {
        Camera {
            eye: glam::DVec3::new(0.0, 2.0, 0.0),
            look_at: glam::DVec3::new(0.0, 2.0, -10.0),
            up: Vec3::Y,
            fov_y_degrees: 45.0,
            near: 0.1,
            far: None,
        }
    }

    fn ground() -> Surroundings {
        Surroundings {
            boxes: vec![(DVec3::new(-50.0, 0.0, -50.0), DVec3::new(50.0, 0.0, 50.0))],
            planet: None,
        }
    }

    #[test]
    fn before_any_input_the_camera_is_the_scenes_exactly() {
        let mut c = FlyCamera::new(home());
        assert_eq!(c.camera(), home());
        c.look(3.0, 0.0);
        assert_ne!(c.camera(), home());
        c.reset();
        assert_eq!(c.camera(), home());
    }

    #[test]
    fn moving_forward_goes_along_the_view_direction_at_height_speed() {
        let mut c = FlyCamera::new(home());
        let s = ground();
        let h = s.height(c.eye());
        assert_eq!(h, Some(2.0));
        assert_eq!(c.speed(h), 2.0);
        c.translate(1.0, 0.0, 0.0, 0.5, &s);
        assert!((c.eye() - DVec3::new(0.0, 2.0, -0.5)).length() < 1e-12);
        c.translate(0.0, 1.0, 0.0, 1.0, &s);
        assert!((c.eye() - DVec3::new(1.0, 2.0, -0.5)).length() < 1e-12);
        c.translate(0.0, 0.0, -1.0, 1.5, &s);
        assert!((c.eye() - DVec3::new(1.0, 0.5, -0.5)).length() < 1e-12);
        // Diagonal moves are not faster.
        let before = c.eye();
        c.translate(1.0, 1.0, 0.0, 1.0, &s);
        assert!((c.eye().distance(before) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn speed_scales_with_height_from_a_metre_to_the_moon() {
        let planet = Surroundings {
            boxes: vec![],
            planet: Some((DVec3::new(0.0, -6.36e6, 0.0), 6.36e6)),
        };
        let c = FlyCamera::new(home());
        let near_ground = c.speed(planet.height(DVec3::new(0.0, 1.0, 0.0)));
        let moon = c.speed(planet.height(DVec3::new(0.0, 3.844e8, 0.0)));
        assert!((near_ground - 1.0).abs() < 1e-6, "{near_ground}");
        assert!((moon / 3.844e8 - 1.0).abs() < 1e-6, "{moon}");
        // On the ground, the near plane sets the slowest speed.
        assert!((c.speed(Some(0.0)) - 0.1).abs() < 1e-7);
    }

    #[test]
    fn looking_turns_and_never_reaches_the_pole() {
        let mut c = FlyCamera::new(home());
        c.look(100.0, 0.0);
        let f = c.forward();
        assert!(
            f.x > 0.0 && f.y.abs() < 1e-12,
            "dragging right turns right: {f}"
        );
        c.look(0.0, 1e6);
        let angle = c.forward().angle_between(DVec3::Y).to_degrees();
        assert!((angle - 179.0).abs() < 1e-9, "{angle}");
        let cam = c.camera();
        assert!(
            (cam.look_at - cam.eye)
                .normalize()
                .cross(cam.up.as_dvec3())
                .length()
                > 0.01
        );
    }

    #[test]
    fn level_flight_around_a_planet_stays_level() {
        let radius = 6.36e6;
        let planet = Surroundings {
            boxes: vec![],
            planet: Some((DVec3::new(0.0, -radius, 0.0), radius)),
        };
        let mut c = FlyCamera::new(Camera {
            eye: glam::DVec3::new(0.0, 1000.0, 0.0),
            look_at: glam::DVec3::new(0.0, 1000.0, -1.0),
            ..home()
        });
        // A quarter of the way round, in steps.
        for _ in 0..1000 {
            let h = planet.height(c.eye()).unwrap();
            c.translate(
                1.0,
                0.0,
                0.0,
                (radius + h) * std::f64::consts::FRAC_PI_2 / 1000.0,
                &planet,
            );
        }
        let vertical = planet.vertical(c.eye()).unwrap();
        assert!(c.forward().dot(vertical).abs() < 0.01, "{}", c.forward());
    }

    #[test]
    fn the_printed_camera_reloads_to_the_same_values() {
        let mut c = FlyCamera::new(home());
        c.translate(1.0, 0.3, 0.0, 0.123_456_7, &ground());
        c.look(17.0, -3.0);
        c.zoom(1.0);
        let text = format!("{}[[materials]]\nname = \"m\"\nkd = [1, 1, 1]\n", c.toml());
        let scene = Scene::from_toml(&text, "printed", std::path::Path::new(".")).unwrap();
        assert_eq!(scene.camera, c.camera());
    }

    #[test]
    fn the_sun_turns_along_its_arc() {
        let up = DVec3::Y;
        let sun = DVec3::new(1.0, 1.0, 0.0).normalize();
        let lower = turn_sun(sun, up, 10f64.to_radians());
        assert!(lower.y < sun.y && lower.z.abs() < 1e-12);
        assert!((sun.angle_between(lower).to_degrees() - 10.0).abs() < 1e-9);
        let overhead = turn_sun(up, up, 0.5);
        assert!((overhead.length() - 1.0).abs() < 1e-12 && overhead.y < 1.0);
    }
}
