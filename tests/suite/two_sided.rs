//! `two_sided`: an open sheet seen from behind is culled by default and
//! drawn, lit as its other side, with the option (on a material or an
//! object, forward and deferred, every shading model); `aerial render
//! MODEL.obj` turns it on for a model with open boundary edges only.

use crate::common;

use aerial::mesh::obj::{load_obj, DEFAULT_WELD_TOLERANCE};
use aerial::render::Pixels;
use aerial::scene::{model_scene_toml, ModelSceneOptions, Scene};
use std::path::Path;

/// A 2x2 plane (front +Y) at the origin seen straight from `eye_y` on the Y
/// axis, under one directional light travelling along `light_y` (Y), with
/// ambient 0.05 and kd 0.8 (ks 0): lit from its side, the centre is 0.68;
/// ambient only, 0.04.
fn sheet_scene(lighting: &str, shading: &str, eye_y: f32, light_y: f32, extra: &str) -> String {
    format!(
        r#"
ambient = [0.05, 0.05, 0.05]
[output]
width = 24
height = 24
hdr_format = "rgba32f"
lighting = "{lighting}"
[camera]
eye = [0.0, {eye_y}, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_y = 20.0
near = 0.1
far = 50.0
[tone_map]
operator = "none"
[[lights]]
type = "directional"
direction = [0.0, {light_y}, 0.0]
intensity = 1.0
[[materials]]
name = "m"
kd = [0.8, 0.8, 0.8]
shading = "{shading}"
{extra}
[[objects]]
name = "sheet"
material = "m"
shape = {{ type = "plane", width = 2.0, depth = 2.0 }}
tessellation = [4, 4]
"#
    )
}

fn centre(hdr: &Pixels<f32>) -> f32 {
    let p = common::pixel(hdr, 12, 12);
    (p[0] + p[1] + p[2]) / 3.0
}

fn render_hdr(toml: &str) -> Pixels<f32> {
    common::render(&common::scene(toml), true).hdr.unwrap()
}

#[test]
fn a_sheet_seen_from_behind_is_culled_unless_two_sided_and_lit_as_its_other_side() {
    for lighting in ["forward", "deferred"] {
        for shading in ["phong", "gouraud", "toon"] {
            let case = format!("{lighting}, {shading}");
            // From below, lit from below: culled without the option.
            let hidden = render_hdr(&sheet_scene(lighting, shading, -4.0, 1.0, ""));
            assert!(
                hidden.data.iter().all(|&c| c == 0.0),
                "{case}: the back of a one-sided sheet was drawn"
            );
            // With it, the back is lit by the light on its side...
            let two = "two_sided = true";
            let back_lit = centre(&render_hdr(&sheet_scene(lighting, shading, -4.0, 1.0, two)));
            assert!(back_lit > 0.3, "{case}: back lit from its side: {back_lit}");
            // ...and not by the light on the front: only ambient.
            let back_dark = centre(&render_hdr(&sheet_scene(
                lighting, shading, -4.0, -1.0, two,
            )));
            assert!(
                (back_dark - 0.04).abs() < 1e-3,
                "{case}: back lit from the other side: {back_dark}"
            );
            // The back seen and lit from below is the front seen and lit
            // from above.
            let front = centre(&render_hdr(&sheet_scene(lighting, shading, 4.0, -1.0, "")));
            assert!(
                (front - back_lit).abs() < 1e-3,
                "{case}: front {front}, back {back_lit}"
            );
            // The front of a two-sided sheet is drawn as a one-sided one's.
            let front_two = centre(&render_hdr(&sheet_scene(lighting, shading, 4.0, -1.0, two)));
            assert!(
                (front_two - front).abs() < 1e-6,
                "{case}: {front_two} {front}"
            );
        }
    }
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// One quad in the XZ plane, front +Y.
const QUAD: &str = "v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nf 1 2 3 4\n";

/// A closed cube whose faces have their own vertices (welded by position).
fn split_cube() -> String {
    let faces: [[[i32; 3]; 4]; 6] = [
        [[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]],
        [[1, -1, -1], [-1, -1, -1], [-1, 1, -1], [1, 1, -1]],
        [[1, -1, 1], [1, -1, -1], [1, 1, -1], [1, 1, 1]],
        [[-1, -1, -1], [-1, -1, 1], [-1, 1, 1], [-1, 1, -1]],
        [[-1, 1, 1], [1, 1, 1], [1, 1, -1], [-1, 1, -1]],
        [[-1, -1, -1], [1, -1, -1], [1, -1, 1], [-1, -1, 1]],
    ];
    let mut s = String::new();
    for (i, face) in faces.iter().enumerate() {
        for [x, y, z] in face {
            s += &format!("v {x} {y} {z}\n");
        }
        let b = 4 * i + 1;
        s += &format!("f {} {} {} {}\n", b, b + 1, b + 2, b + 3);
    }
    s
}

/// An open band: a ring of `n` quads around Y, 2n boundary edges.
fn band(n: usize) -> String {
    let mut s = String::new();
    for i in 0..n {
        let a = i as f64 / n as f64 * std::f64::consts::TAU;
        s += &format!(
            "v {} -0.5 {}\nv {} 0.5 {}\n",
            a.cos(),
            a.sin(),
            a.cos(),
            a.sin()
        );
    }
    for i in 0..n {
        let j = (i + 1) % n;
        s += &format!(
            "f {} {} {} {}\n",
            2 * i + 1,
            2 * j + 1,
            2 * j + 2,
            2 * i + 2
        );
    }
    s
}

#[test]
fn open_edges_are_counted_on_welded_positions() {
    let dir = tempfile::tempdir().unwrap();
    let count = |name: &str, text: &str| {
        load_obj(&write(dir.path(), name, text))
            .unwrap()
            .open_edges(DEFAULT_WELD_TOLERANCE)
    };
    assert_eq!(count("quad.obj", QUAD), 4);
    assert_eq!(count("band.obj", &band(12)), 24);
    assert_eq!(count("cube.obj", &split_cube()), 0);
    // The cube with one face left out has that face's rim open.
    let open_box: String = split_cube()
        .lines()
        .filter(|l| l.trim() != "f 1 2 3 4")
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!(count("box.obj", &open_box), 4);
}

#[test]
fn a_model_scene_is_two_sided_for_an_open_model_only() {
    let dir = tempfile::tempdir().unwrap();
    let options = ModelSceneOptions {
        width: 32,
        height: 24,
        ..ModelSceneOptions::default()
    };
    for (name, text, open) in [
        ("band.obj", band(16), true),
        ("quad.obj", QUAD.to_string(), true),
        ("cube.obj", split_cube(), false),
    ] {
        let path = write(dir.path(), name, &text);
        let toml = model_scene_toml(&path, &options).unwrap();
        assert_eq!(toml.contains("two_sided = true"), open, "{name}:\n{toml}");
        let scene = Scene::from_model(&path, &options).unwrap();
        assert!(scene.objects.iter().all(|o| o.two_sided == open), "{name}");
    }
}

#[test]
fn render_of_an_open_model_says_it_draws_both_sides() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text, open) in [
        ("band.obj", band(16), true),
        ("cube.obj", split_cube(), false),
    ] {
        let path = write(dir.path(), name, &text);
        let out = common::succeed(
            common::aerial()
                .args(["render", "--validate", "--width", "32", "--height", "24"])
                .arg(&path)
                .arg("--out")
                .arg(dir.path().join("o.png")),
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            stderr.contains("open boundary edges") && stderr.contains("two_sided"),
            open,
            "{name}: {stderr}"
        );
    }
}

/// The back of an OBJ sheet is drawn with `two_sided` on the object (its
/// default material being the model's), lit as its other side.
#[test]
fn an_object_two_sided_draws_the_back_of_an_obj_sheet() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "quad.obj", QUAD);
    let toml = |two_sided: &str| {
        sheet_scene("deferred", "phong", -4.0, 1.0, "").replace(
            "shape = { type = \"plane\", width = 2.0, depth = 2.0 }\ntessellation = [4, 4]",
            &format!("shape = {{ type = \"obj\", path = \"quad.obj\" }}\n{two_sided}"),
        )
    };
    let render = |text: &str| {
        let scene = Scene::from_toml(text, "test", dir.path()).unwrap();
        common::render(&scene, true).hdr.unwrap()
    };
    assert!(render(&toml("")).data.iter().all(|&c| c == 0.0));
    let lit = centre(&render(&toml("two_sided = true")));
    assert!(lit > 0.3, "{lit}");
}

/// A value that is not a boolean is a parse error at its line, showing it;
/// a misspelt name is an unknown field whose message lists `two_sided`.
#[test]
fn two_sided_must_be_a_boolean() {
    for (material, object, expect) in [
        ("two_sided = 1", "", "expected a boolean"),
        ("two_sided = \"yes\"", "", "expected a boolean"),
        ("", "two_sided = \"true\"", "expected a boolean"),
        ("twosided = true", "", "two_sided"),
        ("", "two_side = true", "two_sided"),
    ] {
        let text = sheet_scene("forward", "phong", 4.0, -1.0, material).replace(
            "tessellation = [4, 4]",
            &format!("tessellation = [4, 4]\n{object}"),
        );
        let error = Scene::from_toml(&text, "test", Path::new("."))
            .unwrap_err()
            .to_string();
        let line = if material.is_empty() {
            object
        } else {
            material
        };
        assert!(
            error.contains(expect) && error.contains("line ") && error.contains(line),
            "{line}: {error}"
        );
    }
}
