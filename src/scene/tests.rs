//! Tests for scene loading, validation, the camera matrices, transforms and
//! per-object light culling.

use std::path::{Path, PathBuf};

use glam::{DVec3, DVec4, Mat3, Mat4, Quat, Vec3, Vec4};

use super::material_maps::MapKind;
use super::*;

/// The smallest valid scene, with room to append tables.
const MINIMAL: &str = "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n";

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_toml(text, "test.toml", Path::new("."))
}

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")
}

fn camera(near: f32, far: Option<f32>) -> Camera {
    Camera {
        eye: DVec3::new(0.0, 0.0, 0.0),
        look_at: DVec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        fov_y_degrees: 60.0,
        near,
        far,
    }
}

/// The projection written out from its definition, in f64.
fn expected_clip(cam: &Camera, aspect: f64, p: [f64; 3]) -> DVec4 {
    let f = 1.0 / (f64::from(cam.fov_y_degrees).to_radians() / 2.0).tan();
    let near = f64::from(cam.near);
    let (a, b) = match cam.far {
        Some(far) => {
            let far = f64::from(far);
            (-near / (far - near), near * far / (far - near))
        }
        None => (0.0, near),
    };
    let [x, y, z] = p;
    DVec4::new(f / aspect * x, -f * y, a * -z + b, -z)
}

#[test]
fn projection_matches_the_formula() {
    let aspect = 16.0 / 9.0;
    let points = [
        [0.0, 0.0, -0.1],
        [0.3, -0.2, -0.5],
        [-1.0, 2.0, -7.0],
        [5.0, 5.0, -99.0],
        [100.0, -40.0, -5.0e5],
        [1.0e3, 1.0e3, -9.0e7],
    ];
    for (near, far) in [
        (0.1, Some(100.0)),
        (0.1, Some(1.0e8)),
        (1.0, Some(2.0)),
        (0.1, None),
        (0.01, None),
    ] {
        let cam = camera(near, far);
        let m = cam.projection(aspect);
        assert!(m.is_finite());
        for p in points {
            let got = (m * Vec4::new(p[0] as f32, p[1] as f32, p[2] as f32, 1.0)).as_dvec4();
            let want = expected_clip(&cam, f64::from(aspect), p);
            for i in 0..4 {
                // f32 matrix entries and f32 inputs: relative tolerance.
                let tol = 1e-5 * (1.0 + want[i].abs().max(want.w.abs()));
                assert!(
                    (got[i] - want[i]).abs() <= tol,
                    "near {near} far {far:?} point {p:?} component {i}: {got} vs {want}"
                );
            }
        }
    }
}

#[test]
fn reversed_z_maps_near_to_one_and_far_to_zero() {
    for (near, far) in [(0.1_f32, 100.0_f32), (0.1, 1.0e8), (0.5, 3.0)] {
        let m = camera(near, Some(far)).projection(1.5);
        let depth = |z: f32| {
            let c = m * Vec4::new(0.0, 0.0, z, 1.0);
            f64::from(c.z) / f64::from(c.w)
        };
        assert!((depth(-near) - 1.0).abs() < 1e-6, "near {near} far {far}");
        assert!(
            depth(-far).abs() < 1e-6,
            "near {near} far {far}: {}",
            depth(-far)
        );
        // Monotonic: farther is smaller.
        assert!(depth(-near * 2.0) < depth(-near));
    }
    let m = camera(0.1, None).projection(1.0);
    let depth = |z: f32| {
        let c = m * Vec4::new(0.0, 0.0, z, 1.0);
        c.z / c.w
    };
    assert!((depth(-0.1) - 1.0).abs() < 1e-6);
    assert!((depth(-1.0e6) - 1.0e-7).abs() < 1e-12);
    assert!(depth(-1.0e30) >= 0.0 && depth(-1.0e30) < 1e-30);
}

#[test]
fn projection_keeps_the_image_upright_in_vulkan_ndc() {
    let cam = Camera {
        eye: DVec3::new(0.0, 1.0, 5.0),
        look_at: DVec3::new(0.0, 1.0, 0.0),
        up: Vec3::Y,
        fov_y_degrees: 45.0,
        near: 0.1,
        far: Some(50.0),
    };
    let vp = cam.view_projection(2.0);
    // The matrix is camera-relative: it takes positions minus the eye.
    let ndc = |p: Vec3| vp.project_point3(p - cam.eye.as_vec3());
    assert!(ndc(cam.look_at.as_vec3()).truncate().length() < 1e-6);
    // Above the target is towards the top of the image: negative NDC y.
    assert!(ndc(Vec3::new(0.0, 2.0, 0.0)).y < 0.0);
    // Right (+X, seen from +Z) is positive NDC x.
    assert!(ndc(Vec3::new(1.0, 1.0, 0.0)).x > 0.0);
    // The edge of the vertical field of view lands on NDC y = -1.
    let half = (22.5_f32).to_radians().tan() * 5.0;
    assert!((ndc(Vec3::new(0.0, 1.0 + half, 0.0)).y + 1.0).abs() < 1e-5);
    assert_eq!(vp, cam.projection(2.0) * cam.view());
}

#[test]
fn invalid_aspect_does_not_poison_the_matrix() {
    for aspect in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert_eq!(
            camera(0.1, None).projection(aspect),
            camera(0.1, None).projection(1.0)
        );
    }
}

#[test]
fn view_is_a_right_handed_look_at() {
    let cam = Camera {
        eye: DVec3::new(3.0, 2.0, 1.0),
        look_at: DVec3::new(-1.0, 0.5, -2.0),
        up: Vec3::Y,
        fov_y_degrees: 45.0,
        near: 0.1,
        far: None,
    };
    let view = cam.view();
    // Camera-relative: the eye is the origin of its input.
    assert!(view.transform_point3(Vec3::ZERO).length() < 1e-5);
    let target = view.transform_point3((cam.look_at - cam.eye).as_vec3());
    let distance = cam.eye.distance(cam.look_at) as f32;
    assert!((target - Vec3::new(0.0, 0.0, -distance)).length() < 1e-5);
    let up = view.transform_vector3(Vec3::Y);
    assert!(up.y > 0.0 && up.x.abs() < 1e-6);
}

#[test]
fn transform_is_t_r_s_and_the_normal_matrix_its_inverse_transpose() {
    let t = Transform {
        translate: DVec3::new(1.0, -2.0, 3.0),
        rotate_axis: Vec3::new(1.0, 1.0, 0.0).normalize(),
        rotate_degrees: 37.0,
        scale: Vec3::new(2.0, 0.5, 3.0),
    };
    let expected = Mat4::from_translation(t.translate.as_vec3())
        * Mat4::from_quat(Quat::from_axis_angle(t.rotate_axis, 37.0_f32.to_radians()))
        * Mat4::from_scale(t.scale);
    assert!(t.matrix().abs_diff_eq(expected, 1e-5));
    let inverse_transpose = Mat3::from_mat4(t.matrix()).inverse().transpose();
    assert!(t.normal_matrix().abs_diff_eq(inverse_transpose, 1e-5));
    // A normal stays perpendicular to a transformed tangent.
    let (n, tangent) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 0.0, 1.0));
    let dot = (t.normal_matrix() * n).dot(t.matrix().transform_vector3(tangent));
    assert!(dot.abs() < 1e-5);
    assert_eq!(Transform::default().matrix(), Mat4::IDENTITY);
}

#[test]
fn default_scene_loads() {
    let scene = Scene::default_scene();
    assert_eq!(scene.objects.len(), 3);
    let points = scene
        .lights
        .iter()
        .filter(|l| matches!(l, Light::Point { .. }))
        .count();
    assert_eq!((points, scene.lights.len()), (2, 3));
    for i in 0..scene.objects.len() {
        assert!(scene.object_mesh(i).triangle_count() > 0);
        assert_eq!(scene.lights_reaching(i).len(), 3);
    }
}

#[test]
fn every_example_scene_loads() {
    let mut names = Vec::new();
    let entries = std::fs::read_dir(assets().join("scenes")).expect("assets/scenes exists");
    for entry in entries {
        let path = entry.expect("readable entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            // A scene with an atmosphere may be sky only.
            assert!(
                !scene.objects.is_empty() || scene.sky.is_some(),
                "{}",
                path.display()
            );
            for material in &scene.materials {
                for (_, map) in material.maps.iter() {
                    let file = map.path().expect("a file, not the placeholder");
                    assert!(file.is_file(), "{}", file.display());
                }
            }
            names.push(path.file_stem().map(|s| s.to_string_lossy().into_owned()));
        }
    }
    for expected in [
        "default",
        "shading_models",
        "many_lights",
        "flag",
        "transparency",
    ] {
        assert!(
            names.iter().flatten().any(|n| n == expected),
            "{expected}.toml missing"
        );
    }
}

#[test]
fn example_scenes_show_their_features() {
    let load = |name: &str| {
        Scene::load(&assets().join("scenes").join(name)).unwrap_or_else(|e| panic!("{e}"))
    };
    let shading = load("shading_models.toml");
    let models: std::collections::HashSet<_> = shading
        .objects
        .iter()
        .map(|o| shading.materials[o.material].shading)
        .collect();
    assert_eq!(models.len(), 3);

    let many = load("many_lights.toml");
    let points = many
        .lights
        .iter()
        .filter(|l| matches!(l, Light::Point { .. }))
        .count();
    assert!(points >= 12, "{points} point lights");
    let reached: Vec<usize> = (0..many.objects.len())
        .map(|i| many.lights_reaching(i).len())
        .collect();
    assert!(reached.iter().all(|&n| n > 0), "{reached:?}");
    assert!(
        reached.iter().any(|&n| n < many.lights.len()),
        "no light is culled for any object: {reached:?}"
    );

    let flag = load("flag.toml");
    assert!(flag
        .objects
        .iter()
        .any(|o| matches!(o.shape, Shape::Flag { .. })));
    assert!(flag
        .materials
        .iter()
        .any(|m| m.map(MapKind::BaseColor).is_some()));

    let glass = load("transparency.toml");
    let see_through = glass
        .objects
        .iter()
        .filter(|o| (0.3..=0.6).contains(&glass.materials[o.material].opacity))
        .count();
    let opaque = glass
        .objects
        .iter()
        .filter(|o| glass.materials[o.material].opacity == 1.0)
        .count();
    assert!(see_through >= 2 && opaque >= 1);
}

#[test]
fn minimal_scene_gets_the_documented_defaults() {
    let scene = parse(MINIMAL).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        scene.output,
        Output {
            width: 640,
            height: 360,
            hdr_format: HdrFormat::Rgba16F,
            texture_filter: crate::scene::TextureFilter::Trilinear,
            lighting: crate::scene::Lighting::Forward,
            depth_prepass: crate::scene::DepthPrepass::Auto,
            debug_view: None,
            static_lights: true,
            max_pixel_error: 0.5,
            shadow_map: 2048,
            shadow_filter: crate::scene::ShadowFilter::Pcf3,
            shadow_cascades: crate::scene::ShadowCascades::Auto,
        }
    );
    assert_eq!(scene.camera.up, Vec3::Y);
    assert_eq!(
        (
            scene.camera.fov_y_degrees,
            scene.camera.near,
            scene.camera.far
        ),
        (45.0, 0.1, None)
    );
    assert_eq!(
        scene.tone_map,
        ToneMap {
            operator: ToneMapOperator::Reinhard,
            exposure: Exposure::Fixed(1.0),
            bloom: None,
        }
    );
    assert_eq!(scene.ambient, Vec3::ZERO);
    assert_eq!(scene.light_cutoff, 1e-3);
    assert!(scene.lights.is_empty() && scene.materials.is_empty() && scene.objects.is_empty());
}

#[test]
fn full_scene_parses_every_field() {
    let text = format!(
        "{MINIMAL}far = 50\nup = [0, 2, 0]\n\
         [output]\nwidth = 320\nheight = 200\nhdr_format = \"rgba32f\"\n\
         [tone_map]\noperator = \"aces\"\nexposure = 2\n\
         [[lights]]\ntype = \"point\"\nposition = [1, 2, 3]\ncolor = [1, 0.5, 0]\nintensity = 4\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0, -2, 0]\n\
         [[materials]]\nname = \"m\"\nkd = [0.5, 0.5, 0.5]\nshading = \"toon\"\nopacity = 0.5\n\
         [[objects]]\nname = \"f\"\nmaterial = \"m\"\n\
         shape = {{ type = \"flag\", width = 2, height = 1, amplitude = 0.1, frequency = 6 }}\n\
         tessellation = [40, 8]\ntranslate = [1, 0, 0]\nscale = [2, 2, 2]\n\
         rotate = {{ axis = [0, 0, 3], degrees = 90 }}\n"
    );
    let scene = parse(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.output.hdr_format, HdrFormat::Rgba32F);
    assert_eq!(scene.output.aspect(), 1.6);
    assert_eq!(scene.tone_map.operator, ToneMapOperator::Aces);
    assert_eq!(scene.camera.far, Some(50.0));
    assert_eq!(scene.camera.up, Vec3::Y, "up is normalised");
    assert_eq!(
        scene.lights[0],
        Light::Point {
            position: DVec3::new(1.0, 2.0, 3.0),
            color: Vec3::new(4.0, 2.0, 0.0),
            attenuation: Vec3::from(DEFAULT_ATTENUATION),
        }
    );
    assert_eq!(
        scene.lights[1],
        Light::Directional {
            direction: -Vec3::Y,
            color: Vec3::ONE
        }
    );
    let m = &scene.materials[0];
    assert_eq!((m.ka, m.ks, m.shininess), (m.kd, Vec3::ZERO, 32.0));
    assert_eq!(
        (m.shading, m.opacity, m.is_transparent()),
        (ShadingModel::Toon, 0.5, true)
    );
    let o = &scene.objects[0];
    assert_eq!(o.tessellation, (40, 8));
    assert_eq!(o.transform.rotate_axis, Vec3::Z);
    assert_eq!(o.transform.rotate_degrees, 90.0);
    assert_eq!(
        o.shape,
        Shape::Flag {
            width: 2.0,
            height: 1.0,
            amplitude: 0.1,
            frequency: 6.0,
            phase: 0.0
        }
    );
    assert_eq!(o.shape.kind_name(), "flag");
    let mesh = scene.object_mesh(0);
    assert_eq!(mesh.vertices.len(), 41 * 9);
    assert_eq!(scene.object_mesh(1), crate::mesh::Mesh::default());
}

#[test]
fn invalid_values_name_file_field_and_reason() {
    let err = parse(&format!(
        "{MINIMAL}[[materials]]\nname = \"m\"\nkd = [1, 1, 1]\n\
         [[objects]]\nname = \"a\"\nmaterial = \"m\"\nshape = {{ type = \"sphere\", radius = 1 }}\n\
         [[objects]]\nname = \"b\"\nmaterial = \"m\"\nshape = {{ type = \"sphere\", radius = 1 }}\n\
         [[objects]]\nname = \"c\"\nmaterial = \"m\"\nshape = {{ type = \"sphere\", radius = 1 }}\n\
         rotate = {{ axis = [0, 0, 0], degrees = 10 }}\n"
    ))
    .expect_err("zero axis");
    assert_eq!(
        err.to_string(),
        "test.toml: objects[2].rotate.axis: axis has zero length"
    );
    assert_eq!(err.field(), Some("objects[2].rotate.axis"));
}

#[test]
fn unknown_fields_and_syntax_errors_are_parse_errors() {
    let err = parse(&format!("{MINIMAL}fov = 45\n")).expect_err("unknown field");
    let text = err.to_string();
    assert!(matches!(err, SceneError::Parse { .. }), "{text}");
    assert!(text.starts_with("test.toml: "), "{text}");
    assert!(
        text.contains("unknown field `fov`") && text.contains("line 4"),
        "{text}"
    );

    let err = parse("[camera\n").expect_err("syntax");
    assert!(matches!(err, SceneError::Parse { .. }), "{err}");

    let err = parse(&format!(
        "{MINIMAL}[[lights]]\ntype = \"point\"\nposition = [0, 0, 0]\ncolour = [1, 1, 1]\n"
    ))
    .expect_err("unknown light field");
    assert!(err.to_string().contains("unknown field `colour`"), "{err}");
}

#[test]
fn missing_file_is_an_io_error() {
    let err = Scene::load(Path::new("/nonexistent/scene.toml")).expect_err("missing");
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(
        err.to_string().starts_with("/nonexistent/scene.toml: "),
        "{err}"
    );
    // The OS reason is in the message, once (not also as a chained source).
    assert!(err.to_string().contains("os error"), "{err}");
    assert!(std::error::Error::source(&err).is_none());
}

#[test]
fn textures_resolve_relative_to_the_scene_folder() {
    let text = format!(
        "{MINIMAL}[[materials]]\nname = \"m\"\nkd = [1, 1, 1]\ntexture = \"../textures/checker.png\"\n"
    );
    let base = assets().join("scenes");
    let scene = Scene::from_toml(&text, "t.toml", &base).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        scene.materials[0]
            .map(MapKind::BaseColor)
            .and_then(|t| t.path()),
        Some(base.join("../textures/checker.png").as_path())
    );
    // The same text from another folder points at a file that is not there.
    let err = Scene::from_toml(&text, "t.toml", &assets()).expect_err("missing texture");
    let message = err.to_string();
    assert!(
        message.contains("materials[0].texture: file not found"),
        "{message}"
    );
    assert!(message.contains("checker.png"), "{message}");
}

/// Every map kind's scene-file field that names a missing file is an
/// error naming the material, the field and the file (the loader walks the
/// map table, so a new kind is covered without a test of its own).
#[test]
fn every_map_field_naming_a_missing_file_is_an_error_naming_it() {
    for info in crate::scene::material_maps::MAP_KINDS {
        let text = format!(
            "{MINIMAL}[[materials]]\nname = \"m\"\nkd = [1, 1, 1]\n{} = \"no_such_map.png\"\n",
            info.field
        );
        let err = Scene::from_toml(&text, "t.toml", &assets()).expect_err(info.field);
        let message = err.to_string();
        assert!(
            message.contains(&format!("materials[0].{}: file not found", info.field)),
            "{message}"
        );
        assert!(message.contains("no_such_map.png"), "{message}");
    }
}

/// A scene with one unit sphere, stretched to radius 2 along Y and moved to
/// x = 10, lit by the given lights.
fn culling_scene(lights: Vec<Light>, cutoff: f32) -> Scene {
    let mut scene = parse(&format!(
        "{MINIMAL}[[materials]]\nname = \"m\"\nkd = [1, 1, 1]\n\
         [[objects]]\nname = \"ball\"\nmaterial = \"m\"\n\
         shape = {{ type = \"sphere\", radius = 1 }}\ntessellation = [64, 32]\n\
         translate = [10, 0, 0]\nscale = [1, 2, 1]\n"
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    scene.lights = lights;
    scene.light_cutoff = cutoff;
    scene
}

fn point(x: f32, brightness: f32, attenuation: [f32; 3]) -> Light {
    Light::Point {
        position: DVec3::new(f64::from(x), 0.0, 0.0),
        color: Vec3::new(0.1, brightness, 0.2),
        attenuation: Vec3::from(attenuation),
    }
}

#[test]
fn lights_reaching_follows_the_attenuation_threshold() {
    // The ball is centred at x = 10 with bounding radius 2 (scale y = 2), so
    // a light at x is d = |x - 10| - 2 from its bounding sphere.
    let quadratic = [1.0, 0.0, 1.0];
    let lights = vec![
        point(10.0, 1.0, quadratic),           // inside: d = 0, factor 1
        point(41.0, 1.0, quadratic),           // d = 29: 1/842 = 1.19e-3 >= 1e-3
        point(45.0, 1.0, quadratic),           // d = 33: 1/1090 = 9.2e-4 < 1e-3
        point(-50.0, 10.0, quadratic),         // d = 58: 10/3365 = 2.97e-3
        point(-50.0, 1.0, [0.0, 0.0, 0.0001]), // d = 58: 1/0.3364 ~ 2.97
        point(-50.0, 1.0, [0.0, 2.0, 0.0]),    // d = 58: 1/116 = 8.6e-3
        point(1000.0, 1.0, [1.0, 1.0, 0.0]),   // d = 988: 1/989 = 1.01e-3
        point(1010.0, 1.0, [1.0, 1.0, 0.0]),   // d = 998: 1/999 = 1.001e-3
        point(1020.0, 1.0, [1.0, 1.0, 0.0]),   // d = 1008: < 1e-3
        Light::Directional {
            direction: -Vec3::Y,
            color: Vec3::splat(1e-9),
        },
    ];
    let scene = culling_scene(lights.clone(), 1e-3);
    let (centre, radius) = scene.object_bounds(0).expect("object 0");
    assert!((centre - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-4);
    assert!((radius - 2.0).abs() < 1e-4);
    assert_eq!(scene.lights_reaching(0), vec![0, 1, 3, 4, 5, 6, 7, 9]);
    // A cutoff of zero keeps everything; a huge one only directional lights
    // and the light inside the ball with c = 0 (infinite).
    assert_eq!(
        culling_scene(lights.clone(), 0.0).lights_reaching(0).len(),
        10
    );
    let mut inside = lights;
    inside.push(point(10.0, 1.0, [0.0, 0.0, 1.0]));
    assert_eq!(culling_scene(inside, 1e30).lights_reaching(0), vec![9, 10]);
    assert!(scene.lights_reaching(1).is_empty());
}

#[test]
fn lights_reaching_uses_the_rotated_and_translated_bounds() {
    // A long flag rotated by 90 degrees about Y extends along -Z from its
    // pole at the origin; a light near its far end must reach it.
    let mut scene = parse(&format!(
        "light_cutoff = 0.01\n{MINIMAL}[[materials]]\nname = \"m\"\nkd = [1, 1, 1]\n\
         [[objects]]\nname = \"flag\"\nmaterial = \"m\"\n\
         shape = {{ type = \"flag\", width = 100, height = 1, amplitude = 0, frequency = 0 }}\n\
         rotate = {{ axis = [0, 1, 0], degrees = 90 }}\n"
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    scene.lights = vec![
        point(0.0, 1.0, [1.0, 0.0, 1.0]),
        Light::Point {
            position: DVec3::new(0.0, 0.0, -100.0),
            color: Vec3::ONE,
            attenuation: Vec3::new(1.0, 0.0, 1.0),
        },
        Light::Point {
            position: DVec3::new(0.0, 0.0, 100.0),
            color: Vec3::ONE,
            attenuation: Vec3::new(1.0, 0.0, 1.0),
        },
    ];
    assert_eq!(scene.lights_reaching(0), vec![0, 1]);
}

#[test]
fn attenuation_and_strength() {
    let light = point(0.0, 2.0, [1.0, 0.5, 0.25]);
    assert_eq!(light.attenuation_at(2.0), 1.0 / 3.0);
    assert_eq!(light.attenuation_at(-5.0), 1.0);
    assert_eq!(light.strength_at(2.0), 2.0 / 3.0);
    let black = Light::Point {
        position: DVec3::ZERO,
        color: Vec3::ZERO,
        attenuation: Vec3::new(0.0, 0.0, 1.0),
    };
    assert_eq!(black.strength_at(0.0), 0.0);
    assert_eq!(black.attenuation_at(0.0), f32::INFINITY);
}

#[test]
fn windowed_attenuation_reaches_zero_at_the_culling_range() {
    let light = Light::Point {
        position: DVec3::ZERO,
        color: Vec3::new(2.0, 1.0, 0.0),
        attenuation: Vec3::new(1.0, 0.5, 0.25),
    };
    let cutoff = 0.01;
    let window = light.window(cutoff);
    assert_eq!(window, cutoff / 2.0);
    let LightRange::Within(range) = light.range(cutoff) else {
        panic!("a point light with fall-off has a finite range");
    };
    // Windowed attenuation, as the shaders and the CPU reference compute it.
    let windowed = |d: f32| (light.attenuation_at(d) - window).max(0.0);
    assert!(windowed(range) < 1e-7, "{}", windowed(range));
    assert_eq!(windowed(range * 1.01), 0.0);
    assert_eq!(windowed(range * 10.0), 0.0);
    assert!(windowed(range * 0.99) > 0.0);
    // No cutoff, no window; directional lights have none.
    assert_eq!(light.window(0.0), 0.0);
    let sun = Light::Directional {
        direction: -Vec3::Y,
        color: Vec3::ONE,
    };
    assert_eq!(sun.window(cutoff), 0.0);
}

/// `"seed"`, the old name of the linear table mapping, is still read, as
/// `linear`, with a warning naming the field (an error under `--strict`),
/// in scene files and through the knob.
#[test]
fn the_old_name_of_the_linear_mapping_is_read_with_a_warning() {
    let toml = |mapping: &str| {
        format!(
            "[camera]\neye = [0, 1, 0]\nlook_at = [0, 1, 1]\n[sun]\ndirection = [0, 1, 0]\n\
             [atmosphere]\nod_table_mapping = \"{mapping}\"\n"
        )
    };
    let old = Scene::from_toml(&toml("seed"), "t.toml", Path::new(".")).unwrap();
    assert_eq!(
        old.sky.as_ref().unwrap().table_mapping,
        TableMapping::Linear
    );
    assert_eq!(old.warnings.len(), 1);
    let w = old.warnings[0].to_string();
    assert!(
        w.contains("atmosphere.od_table_mapping") && w.contains("\"linear\""),
        "{w}"
    );
    assert!(old.strict().is_err());
    let new = Scene::from_toml(&toml("linear"), "t.toml", Path::new(".")).unwrap();
    assert_eq!(
        new.sky.as_ref().unwrap().table_mapping,
        TableMapping::Linear
    );
    assert!(new.warnings.is_empty());
    let mut knobbed = Scene::from_toml(&toml("horizon"), "t.toml", Path::new(".")).unwrap();
    crate::scene::Knob::find("od_table_mapping")
        .unwrap()
        .set(&mut knobbed, "seed")
        .unwrap();
    assert_eq!(
        knobbed.sky.as_ref().unwrap().table_mapping,
        TableMapping::Linear
    );
    assert_eq!(knobbed.warnings.len(), 1);
}

/// The models are read after the file is parsed, but an object after an
/// `obj` object can still name one of the model's materials
/// (`object/material`), and an unknown name is refused with every material
/// known at that object, the model's included.
#[test]
fn an_object_after_a_model_can_name_the_model_s_material() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("tri.obj"),
        "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("tri.mtl"), "newmtl red\nKd 0.8 0.1 0.1\n").unwrap();
    let scene = |material: &str| {
        Scene::from_toml(
            &format!(
                "{MINIMAL}[[materials]]\nname = \"grey\"\nkd = [0.5, 0.5, 0.5]\n\
                 [[objects]]\nname = \"model\"\nshape = {{ type = \"obj\", path = \"tri.obj\" }}\n\
                 [[objects]]\nname = \"ball\"\nmaterial = \"{material}\"\n\
                 shape = {{ type = \"sphere\", radius = 1.0 }}\n\
                 [[objects]]\nname = \"again\"\nmaterial = \"{material}\"\n\
                 shape = {{ type = \"obj\", path = \"tri.obj\" }}\n"
            ),
            "t.toml",
            dir.path(),
        )
    };
    let s = scene("model/red").unwrap();
    let red = s.materials.iter().position(|m| m.name == "model/red");
    assert_eq!(red, Some(1), "{:?}", s.materials);
    assert_eq!(s.objects.len(), 3);
    assert!(s.objects[1..].iter().all(|o| o.material == 1));
    let e = scene("model/blue").unwrap_err().to_string();
    assert_eq!(
        e,
        "t.toml: objects[1].material: unknown material \"model/blue\" \
         (defined: \"grey\", \"model/red\")"
    );
}

/// `[output] static_lights` takes a boolean; another type is refused with
/// the file, the line and the field's text, and a missing one is on.
#[test]
fn static_lights_takes_a_boolean() {
    assert!(parse(MINIMAL).unwrap().output.static_lights);
    let off = format!("[output]\nstatic_lights = false\n{MINIMAL}");
    assert!(!parse(&off).unwrap().output.static_lights);
    for value in ["\"yes\"", "1", "[true]"] {
        let text = format!("[output]\nstatic_lights = {value}\n{MINIMAL}");
        let e = parse(&text).unwrap_err().to_string();
        assert!(
            e.contains("test.toml") && e.contains("line 2") && e.contains("static_lights"),
            "{value}: {e}"
        );
    }
}
