//! Every scene in `tests/bad_scenes/` must fail to load with a message that
//! names the file, the offending field and the reason.
//!
//! Each bad scene starts with a `# expect: TEXT` line; the error's `Display`
//! must contain TEXT. Keeping the expectation inside the file means a new
//! case is just a new file.

use std::path::{Path, PathBuf};

use aerial::scene::{Scene, SceneError};

fn bad_scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_scenes")
}

/// `(path, expected text)` for every bad scene, sorted by name.
fn bad_scenes() -> Vec<(PathBuf, String)> {
    let entries = std::fs::read_dir(bad_scenes_dir()).expect("tests/bad_scenes exists");
    let mut scenes: Vec<_> = entries
        .map(|entry| entry.expect("readable directory entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "toml"))
        .map(|path| {
            let text = std::fs::read_to_string(&path).expect("readable bad scene");
            let expect = text
                .lines()
                .next()
                .and_then(|line| line.strip_prefix("# expect: "))
                .unwrap_or_else(|| panic!("{} lacks a '# expect: ' first line", path.display()))
                .to_owned();
            (path, expect)
        })
        .collect();
    scenes.sort();
    scenes
}

/// Cases whose error comes from the TOML parser rather than validation.
const PARSE_CASES: &[&str] = &[
    "unknown_field",
    "unknown_top_level_field",
    "unknown_shape_type",
    "unknown_shading_model",
    "wrong_type",
    "syntax_error",
    "missing_camera",
];

#[test]
fn every_bad_scene_fails_with_the_expected_message() {
    let scenes = bad_scenes();
    for (path, expect) in &scenes {
        let name = path.file_stem().map(|s| s.to_string_lossy().into_owned());
        let name = name.as_deref().unwrap_or_default();
        let err = match Scene::load(path) {
            Ok(_) => panic!("{name}: loaded, but should fail with '{expect}'"),
            Err(err) => err,
        };
        let message = err.to_string();
        assert!(
            message.starts_with(&format!("{}: ", path.display())),
            "{name}: message does not start with the file: {message}"
        );
        assert!(
            message.contains(expect.as_str()),
            "{name}: expected '{expect}' in: {message}"
        );
        if PARSE_CASES.contains(&name) {
            assert!(matches!(err, SceneError::Parse { .. }), "{name}: {err:?}");
            assert!(
                message.contains("line "),
                "{name}: no line number: {message}"
            );
        } else {
            let SceneError::Invalid { field, .. } = &err else {
                panic!("{name}: expected a validation error, got {err:?}");
            };
            // The expectation starts with the field path.
            assert!(
                expect.starts_with(&format!("{field}: ")),
                "{name}: field {field} vs expectation {expect}"
            );
        }
    }
}

#[test]
fn every_validation_rule_has_a_bad_scene() {
    let names: Vec<String> = bad_scenes()
        .iter()
        .filter_map(|(path, _)| path.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    for required in [
        "nan_number",
        "inf_number",
        "width_zero",
        "height_too_large",
        "fov_zero",
        "fov_180",
        "near_zero",
        "far_not_beyond_near",
        "eye_equals_look_at",
        "up_parallel_to_view",
        "light_direction_zero",
        "rotate_axis_zero",
        "negative_light_color",
        "negative_intensity",
        "negative_attenuation",
        "attenuation_all_zero",
        "negative_shininess",
        "opacity_above_one",
        "opacity_negative",
        "unknown_material",
        "duplicate_material",
        "missing_texture",
        "sphere_radius_zero",
        "plane_width_negative",
        "torus_minor_zero",
        "tessellation_too_low",
        "tessellation_too_high",
        "scale_zero_component",
        "exposure_zero",
        "unknown_field",
        "syntax_error",
    ] {
        assert!(
            names.iter().any(|n| n == required),
            "tests/bad_scenes/{required}.toml is missing"
        );
    }
    for parse_case in PARSE_CASES {
        assert!(
            names.iter().any(|n| n == parse_case),
            "{parse_case}.toml is missing"
        );
    }
}

#[test]
fn a_missing_texture_names_the_resolved_path() {
    let path = bad_scenes_dir().join("missing_texture.toml");
    let message = Scene::load(&path)
        .map(|_| ())
        .expect_err("must fail")
        .to_string();
    assert!(message.contains("no_such_texture.png"), "{message}");
}

#[test]
fn allowed_edge_cases_load() {
    // Limits that are inclusive or explicitly allowed must not be rejected.
    let text = "ambient = [0.0, 0.0, 0.0]\nlight_cutoff = 0.0\n\
        [output]\nwidth = 16384\nheight = 1\n\
        [camera]\neye = [0.0, 1.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 179.0\n\
        [[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = 0.0\nattenuation = [0.0, 0.0, 1.0]\n\
        [[materials]]\nname = \"m\"\nkd = [0.0, 0.0, 0.0]\nopacity = 0.0\nshininess = 0.001\n\
        [[materials]]\nname = \"n\"\nkd = [5.0, 5.0, 5.0]\nopacity = 1.0\n\
        [[objects]]\nname = \"spindle\"\nmaterial = \"m\"\ntessellation = [3, 4096]\n\
        shape = { type = \"torus\", major_radius = 0.5, minor_radius = 2.0 }\n\
        [[objects]]\nname = \"still flag\"\nmaterial = \"n\"\n\
        shape = { type = \"flag\", width = 1, height = 1, amplitude = 0, frequency = 0, phase = -3 }\n";
    let scene = Scene::from_toml(text, "edge.toml", Path::new("."))
        .unwrap_or_else(|e| panic!("edge cases rejected: {e}"));
    assert_eq!(scene.objects.len(), 2);
    // An empty object list is a valid (if dull) scene.
    let empty = "[camera]\neye = [0.0, 0.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\n";
    let scene = Scene::from_toml(empty, "empty.toml", Path::new("."))
        .unwrap_or_else(|e| panic!("empty scene rejected: {e}"));
    assert!(scene.objects.is_empty());
}
