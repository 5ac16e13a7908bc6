//! The reference's shadows against a closed form: a sphere of radius `r`
//! centred at height `h` over the plane `y = 0`, under a directional light
//! at angle θ from the vertical, shadows the plane inside an ellipse with
//! semi-axes `r` across the light and `r / cos θ` along its horizontal
//! direction, centred where the line through the sphere's centre along
//! the light meets the plane.

use super::shadows::{casters, Occluders};
use super::*;
use std::path::Path;

fn scene(toml: &str) -> Scene {
    Scene::from_toml(toml, "test.toml", Path::new(".")).unwrap()
}

/// A sphere (radius `r`, centre `(0, h, 0)`, `sphere` and `material`
/// appended to its object and material) over a plane (object 1) wide
/// enough for its shadow, lit by a shadow-casting directional light at
/// `theta` degrees from the vertical, travelling towards `+X`, and a
/// second light at `-theta`, towards `-X`, that casts none. `ks = 0`.
fn sphere_over_plane(r: f64, h: f64, theta: f64, sphere: &str, material: &str) -> String {
    let (sin, cos) = theta.to_radians().sin_cos();
    let size = 4.0 * (h * sin / cos + 2.0 * r / cos);
    format!(
        r#"
ambient = [0.1, 0.1, 0.1]
[output]
width = 64
height = 48
[camera]
eye = [0.0, {eye:?}, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
[[lights]]
type = "directional"
direction = [{sin:?}, {ncos:?}, 0.0]
color = [0.5, 0.75, 1.0]
shadows = true
[[lights]]
type = "directional"
direction = [{nsin:?}, {ncos:?}, 0.0]
color = [0.25, 0.25, 0.25]
[[materials]]
name = "ball"
kd = [0.5, 0.5, 0.5]
{material}
[[materials]]
name = "ground"
kd = [0.8, 0.6, 0.4]
[[objects]]
name = "sphere"
material = "ball"
shape = {{ type = "sphere", radius = {r:?} }}
translate = [0.0, {h:?}, 0.0]
{sphere}
[[objects]]
name = "ground"
material = "ground"
shape = {{ type = "plane", width = {size:?}, depth = {size:?} }}
"#,
        eye = 4.0 * h,
        ncos = -cos,
        nsin = -sin,
    )
}

/// The closed-form shadow of the sphere of [`sphere_over_plane`] under
/// the scene's light 0 (its direction as the scene stores it).
struct Ellipse {
    centre: DVec3,
    /// Unit horizontal direction of the light's travel, and across it.
    along: DVec3,
    across: DVec3,
    /// Semi-axes along and across.
    a: f64,
    b: f64,
}

impl Ellipse {
    fn of(scene: &Scene, r: f64, h: f64) -> Ellipse {
        let Light::Directional { direction, .. } = scene.lights[0] else {
            panic!("light 0 is directional");
        };
        let travel = direction.as_dvec3().normalize();
        let cos = -travel.y;
        let along = (travel * DVec3::new(1.0, 0.0, 1.0))
            .try_normalize()
            .unwrap_or(DVec3::X);
        Ellipse {
            centre: DVec3::new(0.0, h, 0.0) + travel * (h / cos),
            along,
            across: DVec3::Y.cross(along),
            a: r / cos,
            b: r,
        }
    }

    /// The point at `rho` times the ellipse's radius in direction `phi`.
    fn point(&self, rho: f64, phi: f64) -> DVec3 {
        let (s, c) = phi.sin_cos();
        self.centre + self.along * (rho * self.a * c) + self.across * (rho * self.b * s)
    }

    /// The ellipse's radius through `p` (1 on the outline).
    fn rho(&self, p: DVec3) -> f64 {
        let rel = p - self.centre;
        (rel.dot(self.along) / self.a).hypot(rel.dot(self.across) / self.b)
    }
}

/// Light 0's visibility on the plane (object 1) at `p`.
fn visibility(scene: &Scene, p: DVec3) -> f64 {
    let Light::Directional { direction, .. } = scene.lights[0] else {
        panic!("light 0 is directional");
    };
    let to_light = (-direction.as_dvec3()).normalize();
    Occluders::new(casters(scene)).visibility(1, p, to_light)
}

/// `(r, h, theta)`: from straight down to a low light, at two scales.
const CASES: [(f64, f64, f64); 5] = [
    (1.0, 3.0, 0.0),
    (1.0, 3.0, 30.0),
    (0.5, 2.0, 60.0),
    (0.25, 0.5, 75.0),
    (200.0, 1000.0, 45.0),
];

#[test]
fn the_sphere_shadows_exactly_the_closed_form_ellipse() {
    for (r, h, theta) in CASES {
        let scene = scene(&sphere_over_plane(r, h, theta, "", ""));
        let ellipse = Ellipse::of(&scene, r, h);
        for k in 0..16 {
            let phi = f64::from(k) * std::f64::consts::TAU / 16.0;
            for (rho, want) in [(0.0, 0.0), (0.5, 0.0), (0.98, 0.0), (1.02, 1.0), (2.0, 1.0)] {
                let p = ellipse.point(rho, phi);
                assert_eq!(
                    visibility(&scene, p),
                    want,
                    "r {r} h {h} theta {theta}: rho {rho} phi {phi} at {p}"
                );
            }
        }
    }
}

#[test]
fn a_lone_plane_is_fully_lit() {
    for (r, h, theta) in CASES.into_iter().chain([(1.0, 3.0, 89.0)]) {
        let mut scene = scene(&sphere_over_plane(r, h, theta, "", ""));
        scene.objects.remove(0);
        let Shape::Plane { width, .. } = scene.objects[0].shape else {
            panic!("object 0 is the plane");
        };
        let half = f64::from(width) * 0.5;
        let to_light = match scene.lights[0] {
            Light::Directional { direction, .. } => (-direction.as_dvec3()).normalize(),
            Light::Point { .. } => unreachable!(),
        };
        let occluders = Occluders::new(casters(&scene));
        for i in 0..=10 {
            for j in 0..=10 {
                let (x, z) = (f64::from(i) / 5.0 - 1.0, f64::from(j) / 5.0 - 1.0);
                let p = DVec3::new(x * half, 0.0, z * half);
                assert_eq!(occluders.visibility(0, p, to_light), 1.0, "{theta}: {p}");
            }
        }
    }
}

#[test]
fn casts_shadows_false_removes_the_shadow() {
    let (r, h, theta) = (1.0, 3.0, 30.0);
    let scene = scene(&sphere_over_plane(r, h, theta, "casts_shadows = false", ""));
    let ellipse = Ellipse::of(&scene, r, h);
    for rho in [0.0, 0.5, 0.98] {
        assert_eq!(visibility(&scene, ellipse.point(rho, 1.0)), 1.0, "{rho}");
    }
    // Only the plane is left to cast.
    assert_eq!(casters(&scene).len(), 1);
}

#[test]
fn a_transparent_sphere_casts_no_shadow() {
    let (r, h, theta) = (1.0, 3.0, 30.0);
    let scene = scene(&sphere_over_plane(r, h, theta, "", "opacity = 0.99"));
    let ellipse = Ellipse::of(&scene, r, h);
    for rho in [0.0, 0.5, 0.98] {
        assert_eq!(visibility(&scene, ellipse.point(rho, 1.0)), 1.0, "{rho}");
    }
}

#[test]
fn a_plane_blocks_light_from_either_side() {
    // A 2 x 2 plane at height 1 over the ground, facing up and (turned
    // half a turn about X) facing down, under a light straight down.
    for turn in ["", "rotate = { axis = [1.0, 0.0, 0.0], degrees = 180.0 }"] {
        let mut text = sphere_over_plane(1.0, 3.0, 0.0, "", "");
        text = text.replace(
            "shape = { type = \"sphere\", radius = 1.0 }\ntranslate = [0.0, 3.0, 0.0]",
            &format!(
                "shape = {{ type = \"plane\", width = 2.0, depth = 2.0 }}\n\
                 translate = [0.0, 1.0, 0.0]\n{turn}"
            ),
        );
        let scene = scene(&text);
        assert!(matches!(scene.objects[0].shape, Shape::Plane { .. }));
        assert_eq!(
            visibility(&scene, DVec3::new(0.9, 0.0, -0.9)),
            0.0,
            "{turn}"
        );
        assert_eq!(visibility(&scene, DVec3::new(1.1, 0.0, 0.0)), 1.0, "{turn}");
    }
}

#[test]
fn the_shadow_removes_exactly_the_lights_term_from_the_image() {
    // Seen from straight above: on the plane, inside the ellipse, shadows
    // take away light 0's term kd cos(theta) Le and nothing else (light 1
    // casts no shadow, and its would-be shadow lies on the other side);
    // outside it, and on the sphere, nothing changes.
    let (r, h, theta) = (1.0, 3.0, 45.0);
    let text = sphere_over_plane(r, h, theta, "", "");
    let shadowed = scene(&text);
    let unshadowed = scene(&text.replace("shadows = true", ""));
    assert_eq!(shadowed.shadow_light, Some(ShadowLight::Light(0)));
    assert_eq!(unshadowed.shadow_light, None);
    let with = render_on_cpu(&shadowed).unwrap();
    let without = render_on_cpu(&unshadowed).unwrap();
    let ellipse = Ellipse::of(&shadowed, r, h);
    let cos = theta.to_radians().cos();
    let term = DVec3::new(0.8, 0.6, 0.4) * DVec3::new(0.5, 0.75, 1.0) * cos;
    let reference = CpuScene::new(&shadowed).unwrap();
    let (mut inside, mut outside) = (0, 0);
    for y in 0..48 {
        for x in 0..64 {
            let i = ((y * 64 + x) * 4) as usize;
            let diff = DVec3::from_array(std::array::from_fn(|c| {
                f64::from(without.data[i + c]) - f64::from(with.data[i + c])
            }));
            let Some(hit) = reference.trace(reference.ray(x, y)) else {
                assert_eq!(diff, DVec3::ZERO, "({x}, {y})");
                continue;
            };
            let rho = ellipse.rho(hit.point);
            if hit.object == 1 && rho < 0.98 {
                assert!(
                    (diff - term).abs().max_element() < 1e-6,
                    "({x}, {y}): {diff}"
                );
                inside += 1;
            } else if hit.object == 0 || rho > 1.02 {
                assert_eq!(diff, DVec3::ZERO, "({x}, {y})");
                outside += 1;
            }
        }
    }
    assert!(inside > 50 && outside > 1000, "{inside} {outside}");
}

#[test]
fn the_sun_casts_shadows_when_it_is_the_shadow_light() {
    let text = sphere_over_plane(1.0, 3.0, 30.0, "", "").replace("shadows = true", "")
        + "[sun]\ndirection = [0.5, 0.5, -0.7]\nshadows = true\n[atmosphere]\n";
    let reference = CpuScene::new(&scene(&text)).unwrap();
    assert!(reference.sun_shadowed);
    assert_eq!(reference.casters.len(), 2);
    let lights = &reference.objects[1].lights;
    assert!(lights.iter().all(|l| matches!(
        l,
        CpuLight::Directional {
            shadowed: false,
            ..
        }
    )));
    // Without a shadow light nothing is gathered (and the reference of a
    // scene does not depend on its objects' casts_shadows).
    let plain = CpuScene::new(&scene(&text.replace("shadows = true", ""))).unwrap();
    assert!(!plain.sun_shadowed && plain.casters.is_empty());
}
