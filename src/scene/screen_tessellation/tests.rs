//! Tests of `tessellation = "auto"`: the chosen grids keep the error they
//! promise (measured on the triangles against the exact surfaces), follow
//! the error budget and the distance, and the scene file and knobs read
//! and refuse what they should.

use std::path::Path;

use glam::{DVec3, Vec3};

use super::*;
use crate::scene::Knob;

/// Output height of the test scenes, and their field of view (degrees).
const HEIGHT: u32 = 180;
const FOV_Y: f64 = 45.0;

/// A 320x180 scene with the camera at `(0, 0, distance)` looking at the
/// origin, and one object per `(shape, translate, extra)`: `shape` the
/// inline table, `extra` more object lines.
fn scene_with(distance: f64, objects: &[(&str, [f64; 3], &str)], output: &str) -> String {
    let mut text = format!(
        "[output]\nwidth = 320\nheight = {HEIGHT}\n{output}\n\
         [camera]\neye = [0.0, 0.0, {distance}]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = {FOV_Y}\n\
         [[materials]]\nname = \"m\"\nkd = [0.5, 0.5, 0.5]\n"
    );
    for (i, (shape, [x, y, z], extra)) in objects.iter().enumerate() {
        text += &format!(
            "[[objects]]\nname = \"o{i}\"\nmaterial = \"m\"\nshape = {shape}\n\
             translate = [{x}, {y}, {z}]\ntessellation = \"auto\"\n{extra}\n"
        );
    }
    text
}

fn parse(text: &str) -> Result<Scene, crate::scene::SceneError> {
    Scene::from_toml(text, "test.toml", Path::new("."))
}

fn load(text: &str) -> Scene {
    parse(text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// The largest distance from a point of object 0's triangles (a
/// barycentric grid on each) to its exact surface, measured by `exact`
/// (distance of an object-space point to the surface, in closed form).
fn max_chord_error(scene: &Scene, exact: impl Fn(DVec3) -> f64) -> f64 {
    let mesh = scene.object_mesh(0);
    let point = |i: u32| Vec3::from(mesh.vertices[i as usize].position).as_dvec3();
    const K: u32 = 6;
    let mut worst = 0.0f64;
    for t in mesh.indices.chunks_exact(3) {
        let (a, b, c) = (point(t[0]), point(t[1]), point(t[2]));
        for i in 0..=K {
            for j in 0..=K - i {
                let (s, r) = (f64::from(i) / f64::from(K), f64::from(j) / f64::from(K));
                worst = worst.max(exact(a + s * (b - a) + r * (c - a)));
            }
        }
    }
    worst
}

/// The world error the rule allows for an object whose bounding sphere's
/// nearest point is `surface_distance` from the camera (near plane 0.1).
fn allowed_error(max_pixel_error: f64, surface_distance: f64) -> f64 {
    let pixels_per_unit = f64::from(HEIGHT) / 2.0 / (FOV_Y.to_radians() / 2.0).tan();
    max_pixel_error * surface_distance.max(0.1) / pixels_per_unit
}

/// The shapes of test (a): the inline table, the radius of a sphere around
/// the origin that holds it, and the distance of a point to the surface.
type Exact = fn(DVec3) -> f64;
fn curved_shapes() -> [(&'static str, f64, Exact); 3] {
    [
        ("{ type = \"sphere\", radius = 1.0 }", 1.0, |p| {
            (p.length() - 1.0).abs()
        }),
        (
            "{ type = \"cylinder\", radius = 1.0, height = 2.0 }",
            2f64.sqrt(),
            |p| (p.x.hypot(p.z) - 1.0).abs(),
        ),
        (
            "{ type = \"torus\", major_radius = 1.0, minor_radius = 0.4 }",
            1.4,
            |p| ((p.x.hypot(p.z) - 1.0).hypot(p.y) - 0.4).abs(),
        ),
    ]
}

#[test]
fn chosen_grids_keep_the_true_chord_error_within_the_budget() {
    for (shape, radius, exact) in curved_shapes() {
        for distance in [2.5, 6.0, 20.0, 80.0] {
            for max_pixel_error in [0.5, 0.25] {
                let mpe = format!("max_pixel_error = {max_pixel_error}");
                let scene = load(&scene_with(distance, &[(shape, [0.0; 3], "")], &mpe));
                let grid = scene.object_tessellation(0);
                let error = max_chord_error(&scene, exact);
                let allowed = allowed_error(max_pixel_error, distance - radius);
                assert!(
                    error <= allowed,
                    "{shape} at {distance}, {max_pixel_error} px: grid {grid:?} strays {error:e}, \
                     more than {allowed:e}"
                );
                // Not the ceiling taken for safety: the bound is within a
                // modest factor of what the triangles really do.
                assert!(
                    error > allowed / 40.0,
                    "{shape}: {grid:?} {error:e} {allowed:e}"
                );
            }
        }
    }
}

#[test]
fn halving_the_pixel_error_multiplies_each_count_by_about_root_two() {
    for (shape, _, _) in curved_shapes() {
        let text = scene_with(10.0, &[(shape, [0.0; 3], "")], "");
        let surface = load(&text).objects[0].shape.surface().unwrap();
        let bounds = surface_bounds(surface.as_ref());
        let (u1, v1) = required_segments(&bounds, 1e-3);
        let (u2, v2) = required_segments(&bounds, 0.5e-3);
        for (a, b) in [(u1, u2), (v1, v2)] {
            // A cylinder is straight along v: no segments needed there.
            let ratio = if a == 0.0 { 2f64.sqrt() } else { b / a };
            assert!((ratio - 2f64.sqrt()).abs() < 1e-9, "{shape}: {a} -> {b}");
        }
        assert!(u1 > 1.0, "{shape}: {u1}");
        // Through the scene: never fewer, and more triangles in all.
        let half = load(&scene_with(
            10.0,
            &[(shape, [0.0; 3], "")],
            "max_pixel_error = 0.25",
        ));
        let full = load(&text);
        let (a, b) = (full.object_tessellation(0), half.object_tessellation(0));
        assert!(
            b.0 >= a.0 && b.1 >= a.1 && b.0 * b.1 > a.0 * a.1,
            "{a:?} {b:?}"
        );
    }
}

#[test]
fn the_ladder_rounds_up_to_shared_counts() {
    let ladder: Vec<u32> = [0.0, 3.0, 3.5, 4.0, 5.0, 7.0, 9.0, 13.0, 17.0, 100.0]
        .iter()
        .map(|&n| ladder_up(n))
        .collect();
    assert_eq!(ladder, [3, 3, 4, 4, 6, 8, 12, 16, 24, 128]);
    assert_eq!(ladder_up(3073.0), 4096);
    assert_eq!(ladder_up(1e9), 4096);
    assert_eq!(ladder_up(f64::INFINITY), 4096);
    assert_eq!(ladder_up(f64::NAN), 4096);
}

#[test]
fn bounds_are_estimated_not_per_shape() {
    // The sphere's second fundamental form in closed form (u and v over
    // [0, 1] for 2 pi of longitude and pi of latitude): L <= 4 pi^2 R (at
    // the equator), M = 0, N = pi^2 R. The estimate is at least L and N and
    // at most the margin above; M is zero up to the differences'
    // round-off, although |r_uv| itself reaches 2 pi^2 R (tangential).
    let r = 2.0;
    let b = surface_bounds(&crate::mesh::SphereSurface { radius: r });
    let pi2 = std::f64::consts::PI.powi(2);
    for (estimate, exact) in [(b.m_uu, 4.0 * pi2 * r), (b.m_vv, pi2 * r)] {
        assert!(
            estimate >= exact && estimate <= 1.3 * exact,
            "{estimate} {exact}"
        );
    }
    assert!(b.m_uv < 1e-4 * b.m_uu, "{b:?}");
    assert!(
        b.centre.length() < 1e-9 && b.radius >= r && b.radius < 1.01 * r,
        "{b:?}"
    );
    // A plane is flat: the minimum grid whatever the budget.
    let plane = surface_bounds(&crate::mesh::PlaneSurface {
        width: 10.0,
        depth: 10.0,
    });
    assert_eq!(
        segments_for_error(&plane, 1e-9),
        (MIN_SEGMENTS, MIN_SEGMENTS)
    );
    // A flag is curved along u only.
    let flag = crate::mesh::FlagSurface {
        width: 2.0,
        height: 1.0,
        amplitude: 0.2,
        frequency: 9.0,
        phase: 0.3,
    };
    let (u, v) = segments_for_error(&surface_bounds(&flag), 1e-3);
    assert!(u > 12 && v == MIN_SEGMENTS, "{u} {v}");
}

#[test]
fn a_far_object_gets_fewer_triangles_than_a_near_one() {
    let sphere = "{ type = \"sphere\", radius = 1.0 }";
    // Camera at z = 10: one sphere 3 away, one 90 away (behind the origin).
    let scene = load(&scene_with(
        10.0,
        &[
            (sphere, [0.0, 0.0, 7.0], ""),
            (sphere, [0.0, 0.0, -80.0], ""),
        ],
        "",
    ));
    let (near, far) = (scene.object_mesh(0), scene.object_mesh(1));
    assert!(
        far.triangle_count() * 4 < near.triangle_count(),
        "near {} far {}",
        near.triangle_count(),
        far.triangle_count()
    );
    assert_eq!(scene.mesh_sources(), [0, 1]);
    assert_eq!(
        scene.triangle_count(),
        (near.triangle_count() + far.triangle_count()) as u64
    );
}

#[test]
fn objects_at_similar_distances_share_one_mesh() {
    let sphere = "{ type = \"sphere\", radius = 0.5 }";
    let objects: Vec<_> = (0..5)
        .map(|i| (sphere, [f64::from(i) * 1.5 - 3.0, 0.0, 0.0], ""))
        .collect();
    let scene = load(&scene_with(30.0, &objects, ""));
    assert_eq!(scene.mesh_sources(), [0, 0, 0, 0, 0]);
    let summary = scene.tessellation_summary().unwrap();
    assert!(
        summary.contains("5 objects") && summary.contains("x5"),
        "{summary}"
    );
}

#[test]
fn scale_counts_like_size() {
    // A unit sphere scaled by 3 needs the grid of a radius-3 sphere.
    let scaled = load(&scene_with(
        20.0,
        &[(
            "{ type = \"sphere\", radius = 1.0 }",
            [0.0; 3],
            "scale = [3, 3, 3]",
        )],
        "",
    ));
    let big = load(&scene_with(
        20.0,
        &[("{ type = \"sphere\", radius = 3.0 }", [0.0; 3], "")],
        "",
    ));
    assert_eq!(scaled.object_tessellation(0), big.object_tessellation(0));
    let small = load(&scene_with(
        20.0,
        &[("{ type = \"sphere\", radius = 1.0 }", [0.0; 3], "")],
        "",
    ));
    assert!(small.object_tessellation(0).0 < big.object_tessellation(0).0);
}

#[test]
fn fixed_grids_are_untouched() {
    let text = scene_with(
        5.0,
        &[("{ type = \"sphere\", radius = 1.0 }", [0.0; 3], "")],
        "",
    )
    .replace("tessellation = \"auto\"", "tessellation = [40, 8]");
    let scene = load(&text);
    assert!(!scene.objects[0].auto_tessellation);
    assert_eq!(scene.object_tessellation(0), (40, 8));
    assert_eq!(scene.tessellation_summary(), None);
}

#[test]
fn bad_values_are_errors_naming_the_field() {
    let sphere = "{ type = \"sphere\", radius = 1.0 }";
    let base = scene_with(5.0, &[(sphere, [0.0; 3], "")], "");
    let cases = [
        (
            base.replace("\"auto\"", "\"autox\""),
            "objects[0].tessellation",
            "\"autox\"",
        ),
        (
            base.replace("\"auto\"", "[8]"),
            "objects[0].tessellation",
            "[u, v]",
        ),
        (
            base.replace("\"auto\"", "[8, 2.5]"),
            "objects[0].tessellation",
            "v segments",
        ),
        (
            base.replace("\"auto\"", "[-8, 8]"),
            "objects[0].tessellation",
            "got -8",
        ),
        (
            base.replace("\"auto\"", "true"),
            "objects[0].tessellation",
            "got true",
        ),
    ];
    for (text, field, reason) in cases {
        let e = parse(&text).unwrap_err().to_string();
        assert!(
            e.contains("test.toml") && e.contains(field) && e.contains(reason),
            "{e}"
        );
    }
    for (value, reason) in [
        ("0", "greater than 0"),
        ("-1", "greater than 0"),
        ("nan", "NaN"),
        ("inf", "inf"),
        ("1e-300", "1e-300"),
    ] {
        let text = scene_with(5.0, &[], &format!("max_pixel_error = {value}"));
        let e = parse(&text).unwrap_err().to_string();
        assert!(
            e.contains("test.toml") && e.contains("output.max_pixel_error") && e.contains(reason),
            "{value}: {e}"
        );
    }
    // A string is a type error, which names the key.
    let e = parse(&scene_with(5.0, &[], "max_pixel_error = \"half\""))
        .unwrap_err()
        .to_string();
    assert!(e.contains("max_pixel_error") && e.contains("string"), "{e}");
}

#[test]
fn an_obj_model_refuses_auto_too() {
    let text = "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
                [[objects]]\nname = \"m\"\nshape = { type = \"obj\", path = \"x.obj\" }\n\
                tessellation = \"auto\"\n";
    let e = parse(text).unwrap_err().to_string();
    assert!(
        e.contains("objects[0].tessellation") && e.contains("obj model"),
        "{e}"
    );
}

#[test]
fn knobs_set_auto_and_the_pixel_error() {
    let sphere = "{ type = \"sphere\", radius = 1.0 }";
    let fixed = scene_with(8.0, &[(sphere, [0.0; 3], "")], "")
        .replace("tessellation = \"auto\"", "tessellation = [64, 32]");
    let mut scene = load(&fixed);
    let tessellation = Knob::find("tessellation").unwrap();
    let fixed_read = (tessellation.read)(&scene);
    tessellation.set(&mut scene, "auto").unwrap();
    assert!(scene.objects[0].auto_tessellation);
    let chosen = scene.object_tessellation(0);
    assert_ne!(chosen, (64, 32));
    let read = (tessellation.read)(&scene);
    assert!(read.starts_with("auto") && read != fixed_read, "{read}");

    let error = Knob::find("max_pixel_error").unwrap();
    error.set(&mut scene, "0.125").unwrap();
    assert_eq!((error.read)(&scene), "0.125");
    let finer = scene.object_tessellation(0);
    assert!(
        finer.0 > chosen.0 && finer.1 > chosen.1,
        "{chosen:?} {finer:?}"
    );
    for bad in ["0", "-1", "nan", "inf", "half", ""] {
        let e = error.set(&mut scene, bad).unwrap_err().to_string();
        assert!(e.contains("max_pixel_error") && e.contains(bad), "{e}");
    }
    let e = tessellation
        .set(&mut scene, "automatic")
        .unwrap_err()
        .to_string();
    assert!(e.contains("tessellation") && e.contains("auto"), "{e}");

    // A factor makes the grid fixed again: the default grid times it, as
    // for a scene that never was auto.
    tessellation.set(&mut scene, "0.5").unwrap();
    assert!(!scene.objects[0].auto_tessellation);
    assert_eq!(scene.object_tessellation(0), (32, 16));
}

#[test]
fn the_size_knob_changes_the_choice() {
    // Twice the pixels: each world length covers twice the pixels, so
    // twice the segments before rounding.
    let sphere = "{ type = \"sphere\", radius = 1.0 }";
    let mut scene = load(&scene_with(8.0, &[(sphere, [0.0; 3], "")], ""));
    let before = scene.object_tessellation(0);
    Knob::find("size")
        .unwrap()
        .set(&mut scene, "1280x720")
        .unwrap();
    let after = scene.object_tessellation(0);
    assert!(
        after.0 > before.0 && after.1 > before.1,
        "{before:?} {after:?}"
    );
}

#[test]
fn a_budget_beyond_the_largest_grid_is_warned_about() {
    let (shape, _, _) = curved_shapes()[0];
    let scene = |mpe: &str| load(&scene_with(6.0, &[(shape, [0.0; 3], "")], mpe));
    assert_eq!(scene("max_pixel_error = 0.5").tessellation_ceiling(), None);
    let tiny = scene("max_pixel_error = 1e-7");
    assert_eq!(tiny.object_tessellation(0).0, MAX_SEGMENTS);
    let warning = tiny.tessellation_ceiling().expect("a warning");
    assert!(
        warning.contains("1 object") && warning.contains(&MAX_SEGMENTS.to_string()),
        "{warning}"
    );
}
