//! Every scene in `tests/bad_scenes/` must fail to load with a message that
//! names the file, the offending field and the reason.
//!
//! Each bad scene starts with a `# expect: TEXT` line; the error's `Display`
//! must contain TEXT. Keeping the expectation inside the file means a new
//! case is just a new file.

use crate::common;
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

/// Runs `aerial` with `args`: its exit code and standard error.
fn exit_and_stderr(args: &[&std::ffi::OsStr]) -> (Option<i32>, String) {
    let out = common::aerial().args(args).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Messages say what is really wrong, where: a folder, FIFO or device
/// given as a map is "not a regular file" of its kind (not "not found"),
/// a pipe is a pipe, an oversized memory budget is "too large", a
/// non-UTF-8 scene gives the byte offset and line, an endless input stops
/// at a bound, a coordinate overflow is blamed on the model file, and OBJ
/// statements the parser would refuse carry their line.
#[test]
#[cfg(target_os = "linux")]
fn messages_name_the_real_problem_and_where() {
    use std::ffi::OsStr;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let os = |s: &str| OsStr::new(s).to_owned();
    let scene_with = |name: &str, map: &str| {
        let path = d.join(name);
        std::fs::write(
            &path,
            format!(
                "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
                 [[materials]]\nname = \"m\"\nkd = [1, 1, 1]\nnormal_map = \"{map}\"\n\
                 [[objects]]\nname = \"s\"\nmaterial = \"m\"\nshape = {{ type = \"sphere\", radius = 1 }}\n"
            ),
        )
        .unwrap();
        path
    };
    std::fs::create_dir(d.join("folder.png")).unwrap();
    let fifo = d.join("fifo.png");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo(3) with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let out = d.join("o.png");
    for (map, expected) in [
        ("folder.png", "not a regular file (a folder)"),
        ("fifo.png", "not a regular file (a FIFO (named pipe))"),
        ("/dev/null", "not a regular file (a device)"),
        ("gone.png", "file not found"),
    ] {
        let scene = scene_with("s.toml", map);
        let (code, err) = exit_and_stderr(&[
            &os("render"),
            scene.as_os_str(),
            &os("--out"),
            out.as_os_str(),
        ]);
        assert_eq!(code, Some(2), "{map}: {err}");
        assert!(
            err.contains("materials[0].normal_map") && err.contains(expected),
            "{map}: {err}"
        );
    }

    // An oversized budget is too large, not too small.
    let out_big = std::process::Command::new(env!("CARGO_BIN_EXE_aerial"))
        .args(["mesh", "whatever.obj"])
        .env("AERIAL_MEMORY_BUDGET", "99999999999999999999999")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out_big.stderr);
    assert!(
        err.contains("AERIAL_MEMORY_BUDGET") && err.contains("too large"),
        "{err}"
    );

    // Not UTF-8: the byte offset and line.
    let latin1 = d.join("latin1.toml");
    std::fs::write(&latin1, b"# ok\n# caf\xe9\n[camera]\n").unwrap();
    let (code, err) = exit_and_stderr(&[
        &os("render"),
        latin1.as_os_str(),
        &os("--out"),
        out.as_os_str(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("byte 0xe9 at byte offset 10 (line 2)"),
        "{err}"
    );

    // An endless input stops at the bound.
    let started = std::time::Instant::now();
    let (code, err) = exit_and_stderr(&[
        &os("render"),
        &os("/dev/zero"),
        &os("--out"),
        out.as_os_str(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("/dev/zero") && err.contains("reading stopped"),
        "{err}"
    );
    assert!(started.elapsed() < std::time::Duration::from_secs(60));

    // A scene read from a pipe is read once (process substitution).
    let piped = d.join("piped");
    let c = std::ffi::CString::new(piped.to_str().unwrap()).unwrap();
    // SAFETY: as above.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let text =
        "[output]\nwidth = 16\nheight = 16\n[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
    let writer = {
        let piped = piped.clone();
        std::thread::spawn(move || std::fs::write(piped, text).unwrap())
    };
    let (code, err) = exit_and_stderr(&[
        &os("render"),
        piped.as_os_str(),
        &os("--out"),
        out.as_os_str(),
    ]);
    writer.join().unwrap();
    assert_eq!(code, Some(0), "{err}");
    assert!(out.exists());

    // An output that is a pipe says so.
    let (code, err) = exit_and_stderr(&[&os("render"), &os("--out"), fifo.as_os_str()]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("a FIFO (named pipe)"), "{err}");

    // Overflowing coordinates are the model file's fault.
    std::fs::write(
        d.join("big.obj"),
        "v 3e38 0 0\nv -3e38 0 0\nv 0 3e38 0\nf 1 2 3\n",
    )
    .unwrap();
    let big = d.join("big.toml");
    std::fs::write(
        &big,
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
         [[objects]]\nname = \"b\"\nshape = { type = \"obj\", path = \"big.obj\" }\n",
    )
    .unwrap();
    let e = Scene::load(&big).unwrap_err().to_string();
    assert!(
        e.contains("objects[0].shape.path") && e.contains("big.obj"),
        "{e}"
    );
    assert!(!e.contains("smoothing"), "{e}");

    // OBJ statements the parser refuses carry their line.
    for (body, expected) in [
        (
            "v 0 0 0 1 1 1 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "m.obj:1: vertex needs 3 numbers",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0\nf 1/1 2/1 3/1\n",
            "m.obj:4: texture coordinate",
        ),
        (
            "v 0 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "m.obj:1: vertex weight w is 0",
        ),
    ] {
        let model = d.join("m.obj");
        std::fs::write(&model, body).unwrap();
        let (code, err) = exit_and_stderr(&[&os("mesh"), model.as_os_str()]);
        assert_eq!(code, Some(2), "{err}");
        assert!(err.contains(expected), "{err}");
    }
}
