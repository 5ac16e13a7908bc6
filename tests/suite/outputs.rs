//! No command ever writes over one of its own inputs, and every image
//! output is named by its format.
//!
//! - An output that is the same file as any input of the command (the
//!   scene, an OBJ model, its MTL library, a texture, a normal or height
//!   map, a view script, a baseline, an image to compare), named directly,
//!   through a symbolic link, a hard link or another spelling of the path,
//!   is refused before any work: exit 2, a message saying it is an input,
//!   every input byte for byte unchanged and no file created.
//! - A PNG output not named `*.png` or an OpenEXR output not named `*.exr`
//!   (any case) is refused the same way.
//!
//! Commands that get as far as rendering run under `--validate`.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Output;

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")
}

/// A scene with a textured sphere and an OBJ model whose MTL library
/// names a normal map, written into `dir` with all its files.
const SCENE: &str = r#"
ambient = [0.2, 0.2, 0.2]
[output]
width = 32
height = 18
[camera]
eye = [0.0, 1.0, 6.0]
look_at = [0.0, 0.0, 0.0]
[[lights]]
type = "directional"
direction = [-1.0, -1.0, -0.5]
[[materials]]
name = "checked"
kd = [0.8, 0.8, 0.8]
texture = "tex.png"
[[objects]]
name = "ball"
material = "checked"
shape = { type = "sphere", radius = 1.0 }
tessellation = [8, 6]
translate = [-1.5, 0.0, 0.0]
[[objects]]
name = "ring"
shape = { type = "obj", path = "m.obj" }
translate = [1.5, 0.0, 0.0]
"#;

/// The scene and everything it reads, in a fresh folder.
struct Fixture {
    dir: tempfile::TempDir,
}

impl Fixture {
    fn new() -> Fixture {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("s.toml"), SCENE).unwrap();
        std::fs::copy(assets().join("textures/checker.png"), d.join("tex.png")).unwrap();
        std::fs::copy(assets().join("models/cut_torus.obj"), d.join("m.obj")).unwrap();
        // The OBJ names its library as cut_torus.mtl.
        std::fs::copy(
            assets().join("models/cut_torus.mtl"),
            d.join("cut_torus.mtl"),
        )
        .unwrap();
        std::fs::copy(assets().join("models/bumps.png"), d.join("bumps.png")).unwrap();
        Fixture { dir }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// Every file in the folder with its bytes.
    fn snapshot(&self) -> Vec<(String, Vec<u8>)> {
        let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(self.dir.path())
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let bytes = std::fs::read(e.path()).unwrap_or_default();
                (e.file_name().to_string_lossy().into_owned(), bytes)
            })
            .collect();
        v.sort();
        v
    }

    /// A symbolic link `name` to `target` (a name in the folder).
    fn symlink(&self, target: &str, name: &str) -> PathBuf {
        let link = self.path(name);
        std::os::unix::fs::symlink(self.path(target), &link).unwrap();
        link
    }

    /// A hard link `name` to `target`.
    fn hard_link(&self, target: &str, name: &str) -> PathBuf {
        let link = self.path(name);
        std::fs::hard_link(self.path(target), &link).unwrap();
        link
    }
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    common::aerial().args(args).output().unwrap()
}

/// Runs `args` and asserts it was refused with exit 2, a message holding
/// every needle, and the folder exactly as before.
fn assert_refused(fixture: &Fixture, args: &[&std::ffi::OsStr], needles: &[&str]) {
    let before = fixture.snapshot();
    let out = run(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}\nstderr:\n{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: expected {n:?} in:\n{err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        fixture.snapshot() == before,
        "{args:?} changed the folder; stderr:\n{err}"
    );
}

fn os(s: &str) -> &std::ffi::OsStr {
    std::ffi::OsStr::new(s)
}

const INPUT: &str = "an input of this command";

#[test]
fn render_refuses_to_write_over_any_file_its_scene_reads() {
    let f = Fixture::new();
    let scene = f.path("s.toml");
    // Every input, named directly, through another spelling, a symbolic
    // link and a hard link (the links are made once, before the runs).
    let mut outputs: Vec<(PathBuf, &str)> =
        ["s.toml", "tex.png", "m.obj", "cut_torus.mtl", "bumps.png"]
            .iter()
            .map(|n| (f.path(n), INPUT))
            .collect();
    outputs.push((f.path("sub/../tex.png"), "same file as the input"));
    std::fs::create_dir(f.path("sub")).unwrap();
    outputs.push((f.symlink("tex.png", "link.png"), "same file as the input"));
    outputs.push((
        f.symlink("s.toml", "scene-link.exr"),
        "same file as the input",
    ));
    outputs.push((
        f.hard_link("bumps.png", "hard.png"),
        "same file as the input",
    ));
    outputs.push((
        f.hard_link("cut_torus.mtl", "hard.exr"),
        "same file as the input",
    ));
    for (target, needle) in &outputs {
        assert_refused(
            &f,
            &[
                os("render"),
                scene.as_os_str(),
                os("--validate"),
                os("--out"),
                target.as_os_str(),
            ],
            &[needle, "--out"],
        );
        assert_refused(
            &f,
            &[
                os("render"),
                scene.as_os_str(),
                os("--validate"),
                os("--out"),
                f.path("fresh.png").as_os_str(),
                os("--hdr"),
                target.as_os_str(),
            ],
            &[needle, "--hdr"],
        );
    }
    // The scene's files are protected whatever the current folder: run
    // from the fixture's folder with relative names.
    let out = common::aerial()
        .current_dir(f.dir.path())
        .args(["render", "s.toml", "--validate", "--out", "./tex.png"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        std::fs::read(f.path("tex.png")).unwrap(),
        std::fs::read(assets().join("textures/checker.png")).unwrap()
    );
}

#[test]
fn the_other_commands_refuse_to_write_over_their_inputs() {
    let f = Fixture::new();
    let s = f.path("s.toml");
    // tonemap: the EXR it reads.
    let exr = f.path("x.exr");
    let pixels = aerial::render::Pixels {
        width: 2,
        height: 1,
        data: vec![0.5f32; 8],
    };
    aerial::image_io::write_exr(&exr, &pixels).unwrap();
    let exr_link = f.symlink("x.exr", "x-link.png");
    for out in [exr.as_path(), exr_link.as_path()] {
        assert_refused(
            &f,
            &[
                os("tonemap"),
                exr.as_os_str(),
                os("--validate"),
                os("--out"),
                out.as_os_str(),
            ],
            &["input"],
        );
    }
    // compare: either image, as the diff.
    let a = f.path("tex.png");
    let b = f.path("bumps.png");
    let hard = f.hard_link("bumps.png", "b-hard.png");
    for diff in [&a, &b, &hard] {
        assert_refused(
            &f,
            &[
                os("compare"),
                a.as_os_str(),
                b.as_os_str(),
                os("--diff"),
                diff.as_os_str(),
            ],
            &["input", "--diff"],
        );
    }
    // mesh: the model, its MTL library and the texture the library names.
    let model = f.path("m.obj");
    for json in ["m.obj", "cut_torus.mtl", "bumps.png"] {
        assert_refused(
            &f,
            &[
                os("mesh"),
                model.as_os_str(),
                os("--json"),
                f.path(json).as_os_str(),
            ],
            &["input", "--json"],
        );
    }
    // normalmap: the height map.
    for out in [a.clone(), f.symlink("tex.png", "tex-link.png")] {
        assert_refused(
            &f,
            &[os("normalmap"), a.as_os_str(), os("--out"), out.as_os_str()],
            &["input", "--out"],
        );
    }
    // bench: the scene, a texture it names, the baseline (through a hard
    // link: `files::same_file` compares device and inode, so the check of
    // --json against --compare finds it too).
    for json in ["s.toml", "tex.png"] {
        assert_refused(
            &f,
            &[
                os("bench"),
                s.as_os_str(),
                os("--validate"),
                os("--frames"),
                os("1"),
                os("--warmup"),
                os("0"),
                os("--json"),
                f.path(json).as_os_str(),
            ],
            &["input", "--json"],
        );
    }
    let baseline = f.path("base.json");
    common::succeed(common::tiny_triangle_bench(1).arg("--json").arg(&baseline));
    let base_hard = f.hard_link("base.json", "base-hard.json");
    assert_refused(
        &f,
        &[
            os("bench"),
            s.as_os_str(),
            os("--validate"),
            os("--compare"),
            baseline.as_os_str(),
            os("--max-ratio"),
            os("100"),
            os("--json"),
            base_hard.as_os_str(),
        ],
        &["same file", "--json"],
    );
    // view: a script's screenshot over the scene or the script, refused
    // before any window opens.
    let script = f.path("script.txt");
    for shot in ["s.toml", "script.txt", "tex.png"] {
        std::fs::write(
            &script,
            format!("1 screenshot {}\n2 quit\n", f.path(shot).display()),
        )
        .unwrap();
        assert_refused(
            &f,
            &[
                os("view"),
                s.as_os_str(),
                os("--validate"),
                os("--script"),
                script.as_os_str(),
            ],
            &["input", "screenshot"],
        );
    }
}

#[test]
fn outputs_are_named_by_their_format() {
    let f = Fixture::new();
    let scene = f.path("s.toml");
    for (flag, name, format) in [
        ("--out", "o.exr", "PNG"),
        ("--out", "o.jpg", "PNG"),
        ("--out", "o", "PNG"),
        ("--hdr", "h.png", "OpenEXR"),
        ("--hdr", "h.hdr", "OpenEXR"),
    ] {
        let mut args = vec![os("render"), scene.as_os_str(), os("--validate")];
        let target = f.path(name);
        let fresh = f.path("fresh.png");
        if flag == "--hdr" {
            args.extend([os("--out"), fresh.as_os_str()]);
        }
        args.extend([os(flag), target.as_os_str()]);
        assert_refused(&f, &args, &[flag, &format!("written as {format}")]);
    }
    let exr = f.path("x.exr");
    let pixels = aerial::render::Pixels {
        width: 2,
        height: 1,
        data: vec![0.5f32; 8],
    };
    aerial::image_io::write_exr(&exr, &pixels).unwrap();
    let tex = f.path("tex.png");
    let jpg = f.path("o.jpg");
    assert_refused(
        &f,
        &[
            os("tonemap"),
            exr.as_os_str(),
            os("--validate"),
            os("--out"),
            jpg.as_os_str(),
        ],
        &["--out", "written as PNG"],
    );
    assert_refused(
        &f,
        &[
            os("compare"),
            tex.as_os_str(),
            tex.as_os_str(),
            os("--diff"),
            f.path("d.exr").as_os_str(),
        ],
        &["--diff", "written as PNG"],
    );
    assert_refused(
        &f,
        &[
            os("normalmap"),
            tex.as_os_str(),
            os("--out"),
            f.path("n.tga").as_os_str(),
        ],
        &["--out", "written as PNG"],
    );
    // The library's writers refuse as well.
    let err = aerial::image_io::write_exr(&f.path("y.png"), &pixels).unwrap_err();
    assert!(err.to_string().contains("written as OpenEXR"), "{err}");
    let png = aerial::render::Pixels {
        width: 1,
        height: 1,
        data: vec![255u8; 4],
    };
    let err = aerial::image_io::write_png(&f.path("y.exr"), &png, &[]).unwrap_err();
    assert!(err.to_string().contains("written as PNG"), "{err}");
    assert!(!f.path("y.png").exists() && !f.path("y.exr").exists());

    // The extension in any case is accepted, and the data is what it says.
    let out = f.path("O.PNG");
    let hdr = f.path("H.Exr");
    common::succeed(
        common::aerial()
            .arg("render")
            .arg(&scene)
            .arg("--validate")
            .arg("--out")
            .arg(&out)
            .arg("--hdr")
            .arg(&hdr),
    );
    assert!(std::fs::read(&out).unwrap().starts_with(b"\x89PNG"));
    assert!(std::fs::read(&hdr)
        .unwrap()
        .starts_with(&[0x76, 0x2f, 0x31, 0x01]));
}

/// An output whose name the file system cannot hold is refused before any
/// work (no device is created, nothing is rendered), naming the limit; a
/// sweep whose output folder cannot be made is refused before rendering
/// and leaves no folder behind.
#[test]
fn unwritable_outputs_are_refused_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let long = "a".repeat(300);
    let out = dir.path().join(format!("{long}.png"));
    let started = std::time::Instant::now();
    let result = run(&[os("render"), os("--out"), out.as_os_str()]);
    let err = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{err}");
    assert!(
        err.contains("304 bytes long") && err.contains("at most 255"),
        "{err}"
    );
    assert!(!err.contains("device:"), "the work started: {err}");
    let deep = dir
        .path()
        .join(std::iter::repeat_n("d", 2100).collect::<Vec<_>>().join("/"))
        .join("x.png");
    let result = run(&[os("render"), os("--out"), deep.as_os_str()]);
    let err = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{err}");
    assert!(err.contains("at most 4095"), "{err}");

    let sweep_dir = dir.path().join("made").join(&long);
    let scene = assets().join("scenes/default.toml");
    let result = run(&[
        os("sweep"),
        scene.as_os_str(),
        os("--knob"),
        os("lights=1,2"),
        os("--out-dir"),
        sweep_dir.as_os_str(),
    ]);
    let err = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{err}");
    assert!(err.contains("at most 255"), "{err}");
    assert!(
        !dir.path().join("made").exists(),
        "a folder was left behind"
    );
    assert!(started.elapsed() < std::time::Duration::from_secs(30));
}
