//! The command line: exit codes, error messages and output files (the
//! same bytes from two processes, and the device in the PNG's metadata).

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

// What `aerial render` writes: the PNG's device metadata, and the same
// bytes from two separate processes (what a CI job comparing with stored
// references relies on).

fn render_with_cli(dir: &Path, name: &str) -> (PathBuf, PathBuf) {
    let (png, exr) = (
        dir.join(format!("{name}.png")),
        dir.join(format!("{name}.exr")),
    );
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/transparency.toml");
    common::succeed(
        common::aerial()
            .arg("render")
            .arg(&scene)
            .args(["--validate", "--width", "160", "--height", "90", "--out"])
            .arg(&png)
            .arg("--hdr")
            .arg(&exr),
    );
    (png, exr)
}

#[test]
fn two_processes_render_identical_images_and_record_the_device() {
    let dir = common::fresh_dir("cli", "determinism");
    let (png_a, exr_a) = render_with_cli(&dir, "a");
    let (png_b, exr_b) = render_with_cli(&dir, "b");

    let a = image::open(&png_a).unwrap().to_rgba8();
    let b = image::open(&png_b).unwrap().to_rgba8();
    assert_eq!(a.dimensions(), (160, 90));
    let decoded = aerial::render::Pixels {
        width: a.width(),
        height: a.height(),
        data: a.as_raw().clone(),
    };
    common::assert_not_blank(&decoded, 0.3);
    assert!(a.as_raw() == b.as_raw(), "the tone-mapped images differ");
    let (ha, hb) = (
        aerial::image_io::read_exr(&exr_a).unwrap(),
        aerial::image_io::read_exr(&exr_b).unwrap(),
    );
    assert!(
        ha.data
            .iter()
            .map(|x| x.to_bits())
            .eq(hb.data.iter().map(|x| x.to_bits())),
        "the HDR images differ"
    );

    // The metadata names the device and driver this process rendered on,
    // as the library reports them.
    let text = aerial::image_io::read_png_text(&png_a).unwrap();
    let get = |key: &str| {
        text.iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("no {key} in {text:?}"))
    };
    let ctx = aerial::vk::Context::new(&aerial::vk::ContextOptions::default()).unwrap();
    let info = ctx.device_info().clone();
    drop(ctx);
    assert_eq!(get("aerial:device"), info.name);
    let driver = get("aerial:driver");
    assert!(
        driver.contains(&info.driver_name)
            && driver.contains(&info.driver_info)
            && driver.contains(&format!("{:#x}", info.driver_version)),
        "{driver} vs {info:?}"
    );
    assert_eq!(get("aerial:vulkan"), info.api_version);
    assert_eq!(aerial::image_io::read_png_text(&png_b).unwrap(), text);
    std::fs::remove_dir_all(&dir).ok();
}
