//! The command line: exit codes, error messages and output files.

use crate::common;
use std::path::{Path, PathBuf};

fn bad_scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_scenes");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

#[test]
fn default_scene_renders_to_png_and_exr_under_validation() {
    let dir = common::fresh_dir("cli", "default");
    let (png, exr) = (dir.join("out.png"), dir.join("out.exr"));
    let out = common::aerial()
        .args([
            "render",
            "--validate",
            "--width",
            "160",
            "--height",
            "90",
            "--out",
        ])
        .arg(&png)
        .arg("--hdr")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&png).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (160, 90));
    assert!(std::fs::metadata(&exr).unwrap().len() > 1000);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn every_bad_scene_fails_with_a_message_naming_the_file() {
    let scenes = bad_scenes();
    assert!(!scenes.is_empty());
    for scene in scenes {
        let dir = common::fresh_dir("cli", "bad");
        let png = dir.join("out.png");
        let out = common::aerial()
            .arg("render")
            .arg(&scene)
            .arg("--out")
            .arg(&png)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{} was accepted", scene.display());
        let name = scene.file_name().unwrap().to_string_lossy();
        assert!(
            stderr.contains(name.as_ref()),
            "{name}: message does not name the file: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{name}: panicked: {stderr}");
        assert!(!png.exists(), "{name}: an output file was left behind");
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[test]
fn a_missing_scene_file_is_a_clear_error() {
    let out = common::aerial()
        .args(["render", "no/such/scene.toml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/scene.toml"));
}

#[test]
fn a_zero_size_override_is_rejected() {
    let out = common::aerial()
        .args(["render", "--width", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("width"));
}
