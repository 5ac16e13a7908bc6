//! Models whose assets are missing or broken are drawn with visible
//! fallbacks and warnings (default material, magenta/black checker, flat
//! normal), and `--strict` turns each warning into the error it was; a
//! model's scene is built from the model alone (`render MODEL.obj`,
//! `aerial scene`) and frames it at any size and offset.

use crate::common;

use aerial::scene::material_maps::MapKind;
use aerial::scene::{ModelSceneOptions, Scene, Texture};
use glam::Vec3;
use std::path::Path;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A unit quad facing +Z with UVs (two triangles), material `m`.
const QUAD: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
                    vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                    usemtl m\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";

/// The scene's one warning, as text (fails if it has another count).
fn only_warning(scene: &Scene) -> String {
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    scene.warnings[0].to_string()
}

fn scene_of(dir: &Path, extra: &str) -> Result<Scene, aerial::scene::SceneError> {
    let toml = format!(
        "ambient = [1, 1, 1]\n[output]\nwidth = 64\nheight = 64\ntexture_filter = \"nearest\"\n\
         [camera]\neye = [0, 0, 2.5]\nlook_at = [0, 0, 0]\n\
         [tone_map]\noperator = \"none\"\n\
         [[objects]]\nname = \"q\"\nshape = {{ type = \"obj\", path = \"m.obj\" }}\n{extra}"
    );
    Scene::from_toml(&toml, "t.toml", dir)
}

#[test]
fn a_missing_mtl_library_is_a_warning_naming_it_and_groups_get_the_default_material() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.obj", &format!("mtllib gone.mtl\n{QUAD}"));
    let scene = scene_of(dir.path(), "").unwrap();
    let warning = only_warning(&scene);
    let tried = dir.path().join("gone.mtl");
    assert!(
        warning.contains("\"gone.mtl\"") && warning.contains(&tried.display().to_string()),
        "{warning}"
    );
    assert!(warning.contains("default material"), "{warning}");
    let material = &scene.materials[scene.objects[0].material];
    assert_eq!(material.kd, Vec3::splat(0.8));
    assert!(material.map(MapKind::BaseColor).is_none());
    // --strict: the warning is the error.
    let error = scene.strict().unwrap_err().to_string();
    assert!(
        error.contains("objects[0].shape.path")
            && error.contains("cannot load its MTL library \"gone.mtl\""),
        "{error}"
    );
    // A statement that is not a number is left out, naming its line; the
    // rest of the library loads.
    write(dir.path(), "gone.mtl", "newmtl m\nNs shiny\nKd 0 0 1\n");
    let scene = scene_of(dir.path(), "").unwrap();
    let warning = only_warning(&scene);
    assert!(
        warning.contains("gone.mtl:2: Ns needs a number, got \"shiny\""),
        "{warning}"
    );
    let material = &scene.materials[scene.objects[0].material];
    assert_eq!(material.kd, Vec3::new(0.0, 0.0, 1.0));
    // A colour with one number is all three; one that is not numbers is
    // left out, with a warning naming the line.
    write(dir.path(), "gone.mtl", "newmtl m\nKd 0.25\nKs 0.1 x 0.2\n");
    let scene = scene_of(dir.path(), "").unwrap();
    let warning = only_warning(&scene);
    assert!(
        warning.contains("gone.mtl:3: Ks needs one or three numbers"),
        "{warning}"
    );
    let material = &scene.materials[scene.objects[0].material];
    assert_eq!((material.kd, material.ks), (Vec3::splat(0.25), Vec3::ZERO));
}

#[test]
fn a_missing_texture_becomes_a_magenta_checker_and_a_missing_normal_map_the_flat_normal() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.obj", &format!("mtllib m.mtl\n{QUAD}"));
    write(
        dir.path(),
        "m.mtl",
        "newmtl m\nKd 1 1 1\nmap_Kd textures\\gone.png\nnorm gone_normals.png\n",
    );
    let scene = scene_of(dir.path(), "").unwrap();
    let text: Vec<String> = scene.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(text.len(), 2, "{text:?}");
    assert!(
        text[0].contains("material \"m\"")
            && text[0].contains("map_Kd")
            && text[0].contains("textures/gone.png")
            && text[0].contains("magenta/black checker"),
        "{}",
        text[0]
    );
    assert!(
        text[1].contains("normal map")
            && text[1].contains("gone_normals.png")
            && text[1].contains("(0, 0, 1)"),
        "{}",
        text[1]
    );
    let material = &scene.materials[scene.objects[0].material];
    assert_eq!(
        material.map(MapKind::BaseColor).map(|m| &m.texture),
        Some(&Texture::Placeholder)
    );
    assert_eq!(material.map(MapKind::Normal), None);

    // The checker is in the image: magenta and black texels, nothing else
    // (full ambient light, kd 1, no tone curve).
    let run = common::render(&scene, false);
    let (mut magenta, mut black) = (0, 0);
    for y in 20..44 {
        for x in 20..44 {
            let [r, g, b, _] = common::pixel(&run.output, x, y);
            assert!(
                g <= 8 && r.abs_diff(b) <= 8,
                "({x}, {y}) is {:?}, not part of the checker",
                [r, g, b]
            );
            if r > 200 {
                magenta += 1;
            } else if r < 8 {
                black += 1;
            }
        }
    }
    assert!(
        magenta > 100 && black > 100,
        "{magenta} magenta, {black} black"
    );

    // An undecodable file is the same warning with the decoder's reason.
    write(dir.path(), "m.mtl", "newmtl m\nmap_Kd bad.png\n");
    write(dir.path(), "bad.png", "this is not an image");
    let scene = scene_of(dir.path(), "").unwrap();
    let text = only_warning(&scene);
    assert!(
        text.contains("bad.png") && text.contains("neither a PNG nor a JPEG"),
        "{text}"
    );
    assert_eq!(
        scene.materials[scene.objects[0].material]
            .map(MapKind::BaseColor)
            .map(|m| &m.texture),
        Some(&Texture::Placeholder)
    );
}

#[test]
fn an_overriding_scene_material_never_opens_the_mtl_textures() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.obj", &format!("mtllib m.mtl\n{QUAD}"));
    write(dir.path(), "m.mtl", "newmtl m\nmap_Kd gone.png\n");
    let scene = scene_of(
        dir.path(),
        "material = \"grey\"\n[[materials]]\nname = \"grey\"\nkd = [0.5, 0.5, 0.5]\n",
    )
    .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.materials.len(), 1);
}

#[test]
fn utf16_files_are_read_and_an_empty_newmtl_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let utf8 = format!("mtllib m.mtl\n{QUAD}");
    write(
        dir.path(),
        "m.mtl",
        "newmtl\nKd 0 1 0\nnewmtl m\nKd 0.2 0.4 0.6\n",
    );
    let plain = {
        write(dir.path(), "m.obj", &utf8);
        scene_of(dir.path(), "").unwrap()
    };
    let w = plain
        .warnings
        .iter()
        .map(|w| w.to_string())
        .collect::<Vec<_>>();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("m.mtl:1: newmtl without a name"), "{}", w[0]);
    assert_eq!(
        plain.materials[plain.objects[0].material].kd,
        Vec3::new(0.2, 0.4, 0.6)
    );
    for big_endian in [false, true] {
        let mut bytes: Vec<u8> = if big_endian {
            vec![0xFE, 0xFF]
        } else {
            vec![0xFF, 0xFE]
        };
        for unit in utf8.encode_utf16() {
            bytes.extend(if big_endian {
                unit.to_be_bytes()
            } else {
                unit.to_le_bytes()
            });
        }
        std::fs::write(dir.path().join("m.obj"), &bytes).unwrap();
        let scene = scene_of(dir.path(), "").unwrap();
        assert_eq!(scene.objects, plain.objects);
        assert_eq!(scene.materials, plain.materials);
    }
    // An odd number of bytes after the mark cannot be UTF-16.
    std::fs::write(dir.path().join("m.obj"), [0xFF, 0xFE, b'v']).unwrap();
    let error = scene_of(dir.path(), "").unwrap_err().to_string();
    assert!(
        error.contains("UTF-16 encoded") && error.contains("convert to UTF-8"),
        "{error}"
    );
}

#[test]
fn the_command_line_warns_once_and_refuses_under_strict() {
    let dir = tempfile::tempdir().unwrap();
    let model = write(dir.path(), "m.obj", &format!("mtllib m.mtl\n{QUAD}"));
    write(dir.path(), "m.mtl", "newmtl m\nmap_Kd gone.png\n");
    let out = dir.path().join("m.png");
    let run = common::aerial()
        .arg("render")
        .arg(&model)
        .args(["--width", "48", "--height", "32", "--validate"])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert_eq!(stderr.matches("warning: ").count(), 1, "{stderr}");
    assert!(stderr.contains("gone.png"), "{stderr}");
    assert!(out.is_file());

    let strict = common::aerial()
        .arg("render")
        .arg(&model)
        .args(["--strict", "--out"])
        .arg(dir.path().join("strict.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&strict.stderr);
    assert_eq!(strict.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("error:")
            && stderr.contains("map_Kd file not found")
            && stderr.contains("gone.png"),
        "{stderr}"
    );
    assert!(!dir.path().join("strict.png").exists());

    // `aerial mesh` never opens textures: no warning at all.
    let mesh = common::aerial()
        .arg("mesh")
        .arg(&model)
        .arg("--strict")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&mesh.stderr);
    assert!(mesh.status.success(), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    // ...but a missing library is a warning there too, an error under --strict.
    std::fs::remove_file(dir.path().join("m.mtl")).unwrap();
    let mesh = common::aerial().arg("mesh").arg(&model).output().unwrap();
    let stderr = String::from_utf8_lossy(&mesh.stderr);
    assert!(mesh.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: ") && stderr.contains("m.mtl"),
        "{stderr}"
    );
    let mesh = common::aerial()
        .arg("mesh")
        .arg(&model)
        .arg("--strict")
        .output()
        .unwrap();
    assert_eq!(mesh.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&mesh.stderr);
    assert!(
        stderr.contains("cannot load its MTL library \"m.mtl\""),
        "{stderr}"
    );
}

/// A closed box (12 triangles) `size` across centred at `centre`.
fn box_obj(centre: Vec3, size: f32) -> String {
    let mut text = String::new();
    for i in 0..8 {
        let corner = Vec3::new(
            if i & 1 == 0 { -0.5 } else { 0.5 },
            if i & 2 == 0 { -0.5 } else { 0.5 },
            if i & 4 == 0 { -0.5 } else { 0.5 },
        ) * size
            + centre;
        text.push_str(&format!("v {} {} {}\n", corner.x, corner.y, corner.z));
    }
    for f in [
        "1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6",
    ] {
        text.push_str(&format!("f {f}\n"));
    }
    text
}

#[test]
fn a_model_scene_frames_any_size_and_offset_alike() {
    let dir = tempfile::tempdir().unwrap();
    let options = ModelSceneOptions {
        width: 80,
        height: 60,
        ground: true,
        ..ModelSceneOptions::default()
    };
    let mut coverages = Vec::new();
    for (size, centre) in [
        (1.0, Vec3::ZERO),
        (1e-3, Vec3::ZERO),
        (1e6, Vec3::ZERO),
        (1.0, Vec3::splat(1e6)),
        (1e3, Vec3::new(1e6, -2e6, 5e5)),
    ] {
        let model = write(dir.path(), "box.obj", &box_obj(centre, size));
        let scene = Scene::from_model(&model, &options).unwrap();
        // The camera is at the same place relative to the model, up to the
        // spacing of 32-bit floats at the model's offset.
        let spacing = centre.abs().max_element() * f32::EPSILON / size;
        let offset = (scene.camera.eye - scene.camera.look_at).as_vec3() / size;
        assert!((scene.camera.look_at.as_vec3() - centre).length() / size <= 1e-3 + spacing);
        assert!(
            offset.is_finite() && (offset.length() - 2.813).abs() < 0.01 + 2.0 * spacing,
            "{offset}"
        );
        let run = common::render(&scene, false);
        // The box and the ground: every pixel not black.
        let lit = run
            .output
            .data
            .chunks_exact(4)
            .filter(|c| c[..3].iter().map(|&v| u32::from(v)).sum::<u32>() > 0)
            .count();
        assert!(lit > 80 * 60 / 10, "{lit} pixels lit");
        coverages.push(lit);
    }
    let (lo, hi) = (
        *coverages.iter().min().unwrap(),
        *coverages.iter().max().unwrap(),
    );
    assert!(
        hi - lo <= hi / 20,
        "coverage differs with scale/offset: {coverages:?}"
    );
}

#[test]
fn the_written_scene_parses_back_to_the_same_scene() {
    let dir = tempfile::tempdir().unwrap();
    let model = write(
        dir.path(),
        "box.obj",
        &box_obj(Vec3::new(3.0, 1.0, -2.0), 0.7),
    );
    let options = ModelSceneOptions {
        width: 200,
        height: 100,
        ground: true,
        grey: true,
        smoothing: Some(aerial::mesh::smoothing::Smoothing::Face),
    };
    let built = Scene::from_model(&model, &options).unwrap();
    assert_eq!(built.objects.len(), 2);
    let out = dir.path().join("sub");
    std::fs::create_dir(&out).unwrap();
    let toml = out.join("scene.toml");
    let status = common::aerial()
        .arg("scene")
        .arg(&model)
        .args([
            "--width",
            "200",
            "--height",
            "100",
            "--ground",
            "--material",
            "grey",
        ])
        .args(["--smoothing", "face", "--out"])
        .arg(&toml)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let mut loaded = Scene::load(&toml).unwrap();
    // The written scene is one more input of itself; everything else,
    // the model's files included, is the same.
    assert_eq!(loaded.files.first(), Some(&toml));
    loaded.files.remove(0);
    assert_eq!(loaded, built);
}

#[test]
fn bench_counts_asset_warnings_in_its_json_and_strict_refuses_them() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.obj", &format!("mtllib m.mtl\n{QUAD}"));
    write(dir.path(), "m.mtl", "newmtl m\nmap_Kd gone.png\n");
    let scene = write(
        dir.path(),
        "s.toml",
        "[camera]\neye = [0, 0, 3]\nlook_at = [0, 0, 0]\n\
         [[objects]]\nname = \"q\"\nshape = { type = \"obj\", path = \"m.obj\" }\n",
    );
    let bench = |extra: &[&str]| {
        common::aerial()
            .arg("bench")
            .arg(&scene)
            .args([
                "--frames", "1", "--warmup", "0", "--width", "32", "--height", "18",
            ])
            .arg("--validate")
            .args(extra)
            .output()
            .unwrap()
    };
    let json = dir.path().join("bench.json");
    let out = bench(&["--json", json.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert_eq!(stderr.matches("warning: ").count(), 1, "{stderr}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["scenes"][0]["asset_warnings"], 1);

    let out = bench(&["--strict"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("map_Kd file not found"), "{stderr}");
}

#[test]
fn model_options_with_a_scene_file_are_refused() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    for flag in [
        &["--ground"][..],
        &["--material", "grey"],
        &["--smoothing", "face"],
    ] {
        let out = common::aerial()
            .arg("render")
            .arg(&scene)
            .args(flag)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(&format!("{}: only for a model file", flag[0])),
            "{stderr}"
        );
    }
}

/// MTL values are held to a scene material's bounds, each value out of
/// them a warning naming the library, the material's line and the value,
/// with the fallback taken (an error under `--strict`); duplicate
/// `newmtl`s say which definition is used.
#[test]
fn mtl_values_out_of_bounds_are_warnings_with_their_fallback() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.obj", &format!("mtllib m.mtl\n{QUAD}"));
    let cases: &[(&str, &str, &str)] = &[
        (
            "Kd 3.4e38 0.5 0.5",
            "Kd component 0 must be at most 1e6, got 3.4e38",
            "clamped",
        ),
        (
            "Ks -1 0 0",
            "Ks component 0 must be finite and at least 0",
            "Ks 0 is used",
        ),
        (
            "Ka 0 inf 0",
            "Ka component 1 must be finite and at least 0",
            "used instead",
        ),
        ("d -5", "d must be from 0 to 1, got -5", "drawn opaque"),
        ("d 1.5", "d must be from 0 to 1, got 1.5", "drawn opaque"),
        ("Ns -3", "Ns must be finite and at least 0", "Ns 32"),
        ("Ns 1e30", "Ns must be at most 1e6", "clamped"),
    ];
    for (statement, problem, fallback) in cases {
        write(
            dir.path(),
            "m.mtl",
            &format!("# values\nnewmtl m\n{statement}\n"),
        );
        let scene = scene_of(dir.path(), "").unwrap();
        assert_eq!(scene.warnings.len(), 1, "{statement}: {:?}", scene.warnings);
        let w = scene.warnings[0].to_string();
        assert!(w.contains("m.mtl:2: material \"m\""), "{statement}: {w}");
        assert!(
            w.contains(problem) && w.contains(fallback),
            "{statement}: {w}"
        );
        let m = &scene.materials[scene.objects[0].material];
        assert!(m.kd.is_finite() && m.kd.max_element() <= 1e6, "{statement}");
        assert!(m.ka.is_finite() && m.ks.min_element() >= 0.0, "{statement}");
        assert!((0.0..=1.0).contains(&m.opacity), "{statement}");
        assert!(m.shininess >= 1.0 && m.shininess <= 1e6, "{statement}");
        let e = scene.strict().unwrap_err().to_string();
        assert!(
            e.contains("objects[0].shape.path") && e.contains(problem),
            "{e}"
        );
    }
    // d -5 is drawn (opaque), not invisible.
    write(dir.path(), "m.mtl", "newmtl m\nKd 1 0 0\nd -5\n");
    let scene = scene_of(dir.path(), "").unwrap();
    let run = common::render(&scene, false);
    let centre = common::pixel(&run.output, 32, 32);
    assert!(centre[0] > 200 && centre[1] < 30, "{centre:?}");
    // In-range values give no warning; Ns 0 ("no highlight") becomes 1.
    write(
        dir.path(),
        "m.mtl",
        "newmtl m\nKd 1e6 0 0\nKs 0 0 0\nNs 0\nd 0\n",
    );
    let scene = scene_of(dir.path(), "").unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.materials[scene.objects[0].material].shininess, 1.0);
    // The later of two definitions is used, and the warning says so.
    write(
        dir.path(),
        "m.mtl",
        "newmtl m\nKd 1 0 0\n\nnewmtl m\nKd 0 1 0\n",
    );
    let scene = scene_of(dir.path(), "").unwrap();
    let w = only_warning(&scene);
    assert!(
        w.contains("m.mtl:4: material \"m\" is defined again (first at line 1)")
            && w.contains("the later definition is used"),
        "{w}"
    );
    assert_eq!(
        scene.materials[scene.objects[0].material].kd,
        Vec3::new(0.0, 1.0, 0.0)
    );
}
