//! Height maps: a material's `height_map` is turned into a normal map when
//! the scene is rendered, and `aerial normalmap` writes the same map to a
//! file. Checked against geometry as the normal maps are: a flat plane
//! whose height ramp tilts every normal by 30 degrees must shade like the
//! plane turned by 30 degrees without a map. Every render runs under
//! validation.

use crate::common;

use aerial::scene::Scene;
use std::path::Path;

const TILT_DEGREES: f32 = 30.0;
const WIDTH: u32 = 64;

/// A 16-bit grey ramp rising along +x: h = x / (WIDTH - 1).
fn write_ramp(path: &Path) {
    let img = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(WIDTH, 8, |x, _| {
        image::Luma([((x as f64 / (WIDTH - 1) as f64) * 65535.0).round() as u16])
    });
    img.save(path).unwrap();
}

/// The height scale that tilts the ramp's normals by `TILT_DEGREES`: the
/// slope per texel is 1 / (WIDTH - 1), so scale / (WIDTH - 1) = tan(tilt).
fn tilt_scale() -> f32 {
    (WIDTH - 1) as f32 * TILT_DEGREES.to_radians().tan()
}

const PLANE: &str = "{ type = \"plane\", width = 2, depth = 2 }";

fn scene(dir: &Path, lighting: &str, material: &str, rotate_z: f32) -> Scene {
    common::tilt_scene(dir, lighting, material, PLANE, rotate_z)
}

/// Mean RGB over the centre 8x8 pixels.
fn centre(scene: &Scene) -> [f32; 3] {
    common::centre_rgb(&common::render(scene, false).output)
}

use common::assert_close;

#[test]
fn a_height_ramp_shades_like_the_turned_plane() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ramp(&d.join("ramp.png"));
    let material = format!("height_map = \"ramp.png\"\nheight_scale = {}", tilt_scale());
    for lighting in ["forward", "deferred"] {
        let flat = centre(&scene(d, lighting, "", 0.0));
        // Heights rise along +x, so the surface faces -x: +Y turned
        // towards -X is a positive turn about +Z.
        let turned = centre(&scene(d, lighting, "", TILT_DEGREES));
        assert!(
            (turned[0] - flat[0]).abs() > 10.0,
            "{lighting}: the tilt must change the shading"
        );
        let mapped = centre(&scene(d, lighting, &material, 0.0));
        assert_close(mapped, turned, &format!("{lighting}: height ramp"));
    }
}

#[test]
fn the_normalmap_command_writes_the_map_the_renderer_makes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ramp(&d.join("ramp.png"));
    common::succeed(
        common::aerial()
            .arg("normalmap")
            .arg(d.join("ramp.png"))
            .arg("--out")
            .arg(d.join("normals.png"))
            .arg("--scale")
            .arg(tilt_scale().to_string()),
    );
    // The centre texel of the written map is the 30-degree tilt towards -x.
    let map = image::open(d.join("normals.png")).unwrap().to_rgba8();
    let texel = map.get_pixel(WIDTH / 2, 4).0;
    let (s, c) = TILT_DEGREES.to_radians().sin_cos();
    let expect = [-s, 0.0, c].map(|x| ((0.5 + 0.5 * x) * 255.0).round() as u8);
    for ch in 0..3 {
        assert!(
            texel[ch].abs_diff(expect[ch]) <= 1,
            "{texel:?} vs {expect:?}"
        );
    }
    // Rendering with the written map equals rendering with the height map.
    let from_file = common::render(
        &scene(d, "forward", "normal_map = \"normals.png\"", 0.0),
        false,
    );
    let material = format!("height_map = \"ramp.png\"\nheight_scale = {}", tilt_scale());
    let from_heights = common::render(&scene(d, "forward", &material, 0.0), false);
    assert_eq!(from_file.output.data, from_heights.output.data);

    // Bad input: a scale that is not positive, and an unreadable file.
    for (args, message) in [
        (vec!["--scale", "0"], "--scale"),
        (vec!["--scale", "nan"], "--scale"),
    ] {
        let out = common::aerial()
            .arg("normalmap")
            .arg(d.join("ramp.png"))
            .arg("--out")
            .arg(d.join("bad.png"))
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&out.stderr).contains(message));
        assert!(!d.join("bad.png").exists());
    }
    std::fs::write(d.join("junk.png"), b"not a png").unwrap();
    let out = common::aerial()
        .args(["normalmap"])
        .arg(d.join("junk.png"))
        .arg("--out")
        .arg(d.join("bad.png"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("junk.png"));
    assert!(!d.join("bad.png").exists());
}

#[test]
fn height_map_fields_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ramp(&d.join("ramp.png"));
    std::fs::copy(d.join("ramp.png"), d.join("n.png")).unwrap();
    for (material, field) in [
        (
            "height_map = \"ramp.png\"\nnormal_map = \"n.png\"",
            "height_map",
        ),
        ("height_scale = 2.0", "height_scale"),
        (
            "height_map = \"ramp.png\"\nheight_scale = 0.0",
            "height_scale",
        ),
        (
            "height_map = \"ramp.png\"\nheight_scale = -1.0",
            "height_scale",
        ),
        ("height_map = \"missing.png\"", "height_map"),
    ] {
        let toml = format!(
            "[camera]\neye = [0, 4, 0]\nlook_at = [0, 0, 0]\nup = [0, 0, -1]\n\
             [[materials]]\nname = \"m\"\nkd = [0.8, 0.8, 0.8]\n{material}\n"
        );
        let err = Scene::from_toml(&toml, "height.toml", d)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("materials[0].{field}")),
            "{material}: {err}"
        );
    }
}

#[test]
fn a_height_map_that_does_not_fit_the_memory_budget_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 2048 x 2048 grey: small as a file, about 100 MB to convert.
    image::GrayImage::new(2048, 2048)
        .save(d.join("big.png"))
        .unwrap();
    let out = common::aerial()
        .arg("normalmap")
        .arg(d.join("big.png"))
        .arg("--out")
        .arg(d.join("n.png"))
        .env("AERIAL_MEMORY_BUDGET", "16M")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("big.png") && stderr.contains("2048x2048"),
        "{stderr}"
    );
    assert!(!d.join("n.png").exists());
}
