//! Ray–surface intersections and shading of the CPU reference, against
//! closed forms worked out by hand.

use super::*;
use std::path::Path;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
}

fn close_vec(a: DVec3, b: DVec3) -> bool {
    close(a.x, b.x) && close(a.y, b.y) && close(a.z, b.z)
}

fn scene(toml: &str) -> Scene {
    Scene::from_toml(toml, "test", Path::new(env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// A camera on +Z looking at the origin, one white directional light from
/// above, one object given as TOML `[[objects]]` body text.
fn one_object(object: &str, material: &str) -> String {
    format!(
        r#"
ambient = [0.1, 0.1, 0.1]
[output]
width = 5
height = 5
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.0]
[[materials]]
name = "m"
kd = [0.5, 0.5, 0.5]
{material}
[[objects]]
name = "thing"
material = "m"
{object}
"#
    )
}

#[test]
fn sphere_hit_distance_matches_the_closed_form() {
    let sphere = Surface::Sphere { radius: 2.0 };
    // Head on: the front is at z = 2, 3 units from the origin.
    let hit = sphere
        .intersect(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z, 0.0, f64::INFINITY)
        .unwrap();
    assert!(close(hit.t, 3.0), "{hit:?}");
    assert!(close_vec(hit.normal, DVec3::new(0.0, 0.0, 2.0)));
    // Off axis at height 1: the chord starts at z = sqrt(4 - 1).
    let hit = sphere
        .intersect(DVec3::new(0.0, 1.0, 5.0), -DVec3::Z, 0.0, f64::INFINITY)
        .unwrap();
    assert!(close(hit.t, 5.0 - 3f64.sqrt()), "{hit:?}");
    // An unnormalized direction scales t by 1 / |d|.
    let hit = sphere
        .intersect(
            DVec3::new(0.0, 0.0, 5.0),
            -2.0 * DVec3::Z,
            0.0,
            f64::INFINITY,
        )
        .unwrap();
    assert!(close(hit.t, 1.5));
    // A miss, and a far camera (cancellation-prone) small sphere.
    assert!(sphere
        .intersect(DVec3::new(0.0, 2.5, 5.0), -DVec3::Z, 0.0, f64::INFINITY)
        .is_none());
    let tiny = Surface::Sphere { radius: 1e-3 };
    let hit = tiny
        .intersect(DVec3::new(0.0, 0.0, 1e4), -DVec3::Z, 0.0, f64::INFINITY)
        .unwrap();
    assert!((hit.t - (1e4 - 1e-3)).abs() < 1e-9, "{hit:?}");
}

#[test]
fn back_faces_and_clipped_hits_are_skipped() {
    let sphere = Surface::Sphere { radius: 1.0 };
    // From the centre, the only hit faces along the ray: culled.
    assert!(sphere
        .intersect(DVec3::ZERO, DVec3::X, 0.0, f64::INFINITY)
        .is_none());
    // The front face beyond t_max, or before t_min (the near plane cuts it
    // off): the back face behind it is not shown instead.
    let o = DVec3::new(0.0, 0.0, 5.0);
    assert!(sphere.intersect(o, -DVec3::Z, 0.0, 3.9).is_none());
    assert!(sphere.intersect(o, -DVec3::Z, 4.1, 100.0).is_none());
    assert!(sphere.intersect(o, -DVec3::Z, 3.9, 4.1).is_some());

    // The plane's front is +Y: seen from below it is culled.
    let plane = Surface::Plane {
        width: 4.0,
        depth: 2.0,
    };
    assert!(plane
        .intersect(DVec3::new(0.0, -3.0, 0.0), DVec3::Y, 0.0, f64::INFINITY)
        .is_none());
    let hit = plane
        .intersect(DVec3::new(0.0, 3.0, 0.0), -DVec3::Y, 0.0, f64::INFINITY)
        .unwrap();
    assert!(close(hit.t, 3.0) && hit.normal == DVec3::Y);
    // Parallel to the plane: no hit, no division by zero.
    assert!(plane
        .intersect(DVec3::new(-5.0, 0.0, 0.0), DVec3::X, 0.0, f64::INFINITY)
        .is_none());

    // Looking down into the open cylinder: the inside of the far wall is a
    // back face, the bottom is open, so nothing is hit.
    let cylinder = Surface::Cylinder {
        radius: 1.0,
        height: 2.0,
    };
    let down = DVec3::new(0.3, -1.0, 0.0);
    assert!(cylinder
        .intersect(DVec3::new(0.0, 3.0, 0.0), down, 0.0, f64::INFINITY)
        .is_none());
    // From the side, the near wall at z = 1 with the outward normal.
    let hit = cylinder
        .intersect(DVec3::new(0.0, 0.5, 5.0), -DVec3::Z, 0.0, f64::INFINITY)
        .unwrap();
    assert!(
        close(hit.t, 4.0) && close_vec(hit.normal, DVec3::Z),
        "{hit:?}"
    );
    // Above the rim: misses the wall.
    assert!(cylinder
        .intersect(DVec3::new(0.0, 1.5, 5.0), -DVec3::Z, 0.0, f64::INFINITY)
        .is_none());
    // Along the axis: parallel, no hit.
    assert!(cylinder
        .intersect(DVec3::new(0.0, 5.0, 0.0), -DVec3::Y, 0.0, f64::INFINITY)
        .is_none());
}

#[test]
fn plane_rectangle_bounds() {
    let plane = Surface::Plane {
        width: 4.0,
        depth: 2.0,
    };
    let hit = |x: f64, z: f64| {
        plane
            .intersect(DVec3::new(x, 1.0, z), -DVec3::Y, 0.0, f64::INFINITY)
            .is_some()
    };
    // |x| <= width / 2 = 2, |z| <= depth / 2 = 1, edges included.
    assert!(hit(0.0, 0.0) && hit(1.99, 0.99) && hit(-2.0, -1.0));
    assert!(!hit(2.01, 0.0) && !hit(-2.01, 0.0));
    assert!(!hit(0.0, 1.01) && !hit(0.0, -1.01));
}

#[test]
fn transformed_sphere_hits_and_normals_match_the_ellipsoid() {
    // The unit sphere scaled (2, 1, 1), turned 90 degrees about Z (x -> y),
    // moved by (0.25, 0, 0): the ellipsoid (x - 0.25)^2 + y^2 / 4 + z^2 = 1,
    // whose outward normal is the gradient (x - 0.3, y / 4, z).
    let toml = one_object(
        r#"shape = { type = "sphere", radius = 1.0 }
scale = [2.0, 1.0, 1.0]
rotate = { axis = [0.0, 0.0, 1.0], degrees = 90.0 }
translate = [0.25, 0.0, 0.0]"#,
        "",
    );
    let reference = CpuScene::new(&scene(&toml)).unwrap();
    let eye = DVec3::new(0.0, 0.0, 5.0);
    let c = DVec3::new(0.25, 0.0, 0.0);
    let mut checked = 0;
    for dir in [
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(0.05, 0.3, -1.0),
        DVec3::new(-0.1, -0.25, -1.0),
        DVec3::new(0.2, 0.1, -1.0),
    ] {
        let dir = dir.normalize();
        let (o, d) = (eye - c, dir);
        let q = DVec3::new(1.0, 0.25, 1.0);
        let a = (d * d).dot(q);
        let b = (o * d).dot(q);
        let cc = (o * o).dot(q) - 1.0;
        let t = (-b - (b * b - a * cc).sqrt()) / a;
        let p = eye + dir * t;
        let n = ((p - c) * q).normalize();
        let hit = reference.trace(dir).unwrap();
        assert!((hit.t - t).abs() < 1e-12, "{dir}: {} vs {t}", hit.t);
        assert!((hit.point - p).length() < 1e-12);
        assert!(
            (hit.normal - n).length() < 1e-12,
            "{dir}: {} vs {n}",
            hit.normal
        );
        checked += 1;
    }
    assert_eq!(checked, 4);
}

#[test]
fn pixel_rays_follow_the_gpu_camera() {
    let toml = one_object(r#"shape = { type = "sphere", radius = 1.0 }"#, "")
        .replace("width = 5", "width = 10")
        .replace("height = 5", "height = 4");
    let reference = CpuScene::new(&scene(&toml)).unwrap();
    // Pixel (0, 0) is the top left: -X and +Y in view space (the camera
    // looks down -Z), at the centre of the pixel, aspect 10/4.
    let tan = (22.5f64).to_radians().tan();
    let expected = DVec3::new(-0.9 * tan * 2.5, 0.75 * tan, -1.0).normalize();
    assert!((reference.ray(0, 0) - expected).length() < 1e-12);
    let expected = DVec3::new(0.9 * tan * 2.5, -0.75 * tan, -1.0).normalize();
    assert!((reference.ray(9, 3) - expected).length() < 1e-12);
}

#[test]
fn shading_is_the_gpu_formula() {
    // A plane at the origin seen from (0, 3, 3); the centre pixel of a 5x5
    // image looks exactly at the origin. Light straight down: cos = 1,
    // H halfway between +Y and the view direction, N.H = cos(22.5 deg).
    let toml = one_object(
        r#"shape = { type = "plane", width = 1.0, depth = 1.0 }"#,
        "ka = [0.2, 0.4, 0.6]\nks = [0.5, 0.25, 0.125]\nshininess = 10.0",
    )
    .replace("eye = [0.0, 0.0, 5.0]", "eye = [0.0, 3.0, 3.0]");
    let image = render_on_cpu(&scene(&toml)).unwrap();
    let px = |x: u32, y: u32| {
        let i = ((y * image.width + x) * 4) as usize;
        DVec3::new(
            f64::from(image.data[i]),
            f64::from(image.data[i + 1]),
            f64::from(image.data[i + 2]),
        )
    };
    let spec = (22.5f64).to_radians().cos().powf(10.0);
    let expected =
        DVec3::new(0.2, 0.4, 0.6) * 0.1 + DVec3::splat(0.5) + DVec3::new(0.5, 0.25, 0.125) * spec;
    assert!(
        (px(2, 2) - expected).length() < 1e-6,
        "{} vs {expected}",
        px(2, 2)
    );
    assert_eq!(image.data[(12 * 4) + 3], 1.0);
    // The corner misses the small plane: transparent black.
    assert_eq!(&image.data[..4], &[0.0; 4]);

    // A point light 2 above the origin with attenuation (1, 0.5, 0.25):
    // 1 / (1 + 1 + 1) = 1/3 of its colour, less the window of the default
    // cutoff (0.001 / peak colour 1, as the GPU gets it in f32).
    let point = toml.replace(
        "type = \"directional\"\ndirection = [0.0, -1.0, 0.0]",
        "type = \"point\"\nposition = [0.0, 2.0, 0.0]\nattenuation = [1.0, 0.5, 0.25]",
    );
    let image = render_on_cpu(&scene(&point)).unwrap();
    let i = 12 * 4;
    let got = f64::from(image.data[i]);
    let window = f64::from(0.001f32);
    let want = 0.2 * 0.1 + (0.5 + 0.5 * spec) * (1.0 / 3.0 - window);
    assert!((got - want).abs() < 1e-6, "{got} vs {want}");
}

#[test]
fn culled_lights_are_left_out_as_on_the_gpu() {
    // A dim point light far away: above the cutoff it lights the plane,
    // below it the GPU leaves it out, and so does the reference.
    let base = one_object(
        r#"shape = { type = "plane", width = 1.0, depth = 1.0 }"#,
        "",
    )
    .replace("eye = [0.0, 0.0, 5.0]", "eye = [0.0, 3.0, 3.0]")
    .replace(
        "type = \"directional\"\ndirection = [0.0, -1.0, 0.0]",
        "type = \"point\"\nposition = [0.0, 50.0, 0.0]\nattenuation = [1.0, 0.0, 0.0]\nintensity = 0.01",
    );
    let centre = |cutoff: &str| {
        let toml = format!("light_cutoff = {cutoff}\n{base}");
        render_on_cpu(&scene(&toml)).unwrap().data[12 * 4]
    };
    let lit = centre("0.001");
    let culled = centre("0.1");
    // Ambient only: ka (= kd = 0.5) times La = 0.1.
    assert!((f64::from(culled) - 0.05).abs() < 1e-7, "{culled}");
    // Lit: attenuation 1 less the window 0.001 / 0.01 = 0.1.
    let window = f64::from(0.001f32 / 0.01f32);
    let want = 0.05 + 0.5 * 0.01 * (1.0 - window);
    assert!((f64::from(lit) - want).abs() < 1e-6, "{lit} vs {want}");
}

#[test]
fn unsupported_features_name_object_material_and_feature() {
    let error = |object: &str, material: &str| {
        render_on_cpu(&scene(&one_object(object, material)))
            .unwrap_err()
            .to_string()
    };
    let sphere = r#"shape = { type = "sphere", radius = 1.0 }"#;
    let sphere_two_sided = format!("{sphere}\ntwo_sided = true");
    for (object, material, words) in [
        (
            r#"shape = { type = "torus", major_radius = 1.0, minor_radius = 0.2 }"#,
            "",
            &["'thing'", "torus"][..],
        ),
        (
            r#"shape = { type = "flag", width = 1.0, height = 1.0, amplitude = 0.1, frequency = 3.0 }"#,
            "",
            &["'thing'", "flag"][..],
        ),
        (
            sphere,
            "opacity = 0.5",
            &["'thing'", "'m'", "transparency (opacity 0.5)"][..],
        ),
        (
            sphere,
            "shading = \"gouraud\"",
            &["'thing'", "'m'", "gouraud"][..],
        ),
        (
            sphere,
            "shading = \"toon\"",
            &["'thing'", "'m'", "toon"][..],
        ),
        (
            sphere,
            "texture = \"assets/textures/checker.png\"",
            &["'thing'", "'m'", "texture"][..],
        ),
        (
            sphere,
            "two_sided = true",
            &["'thing'", "'m'", "two-sided faces (two_sided)"][..],
        ),
        (
            sphere_two_sided.as_str(),
            "",
            &["'thing'", "'m'", "two-sided faces (two_sided)"][..],
        ),
    ] {
        let text = error(object, material);
        for word in words {
            assert!(text.contains(word), "'{word}' missing from: {text}");
        }
        assert!(text.contains("no CPU reference"), "{text}");
    }

    // A hand-built scene with a dangling material index: an error, not a
    // panic.
    let mut bad = scene(&one_object(sphere, ""));
    bad.objects[0].material = 7;
    let text = render_on_cpu(&bad).unwrap_err().to_string();
    assert!(
        text.contains("'thing'") && text.contains("material index 7"),
        "{text}"
    );
}

#[test]
fn sphere_roots_are_ordered_and_stable() {
    // From (0, 0, 5) along -Z through the unit sphere: 4 and 6.
    assert_eq!(
        sphere_roots(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z, 1.0),
        Some([4.0, 6.0])
    );
    assert_eq!(
        sphere_roots(DVec3::new(0.0, 2.0, 5.0), -DVec3::Z, 1.0),
        None
    );
    assert_eq!(sphere_roots(DVec3::ONE, DVec3::ZERO, 1.0), None);
    // Grazing: a double root.
    assert_eq!(
        sphere_roots(DVec3::new(0.0, 1.0, 5.0), -DVec3::Z, 1.0),
        Some([5.0, 5.0])
    );
    // A 1e-3 sphere 1e4 away keeps its chord, 2e-3 long, to 1e-11 (the
    // textbook |o|^2 - r^2 = 1e8 - 1e-6 would leave it about 1% off).
    let [near, far] = sphere_roots(DVec3::new(0.0, 0.0, 1e4), -DVec3::Z, 1e-3).unwrap();
    assert!((far - near - 2e-3).abs() < 1e-11, "{near} {far}");
}
