//! `aerial compare` with its default limits on real renders: small local
//! defects (a missing or an extra small object, an inverted 12x12 block)
//! must fail, through the worst-window criterion, while what another driver
//! plausibly changes (+-3 LSB noise, edges moved by 1/20 pixel) must pass.
//! For PNG with FLIP and for OpenEXR with rmse and psnr. Every render runs
//! under the validation layer and must produce no messages.
//!
//! Set `AERIAL_KEEP_TEST_IMAGES=<folder>` to keep the images for a look.

use crate::common;

use aerial::image_io;
use aerial::render::Pixels;
use aerial::report::{compare_files, ImageDiff, Metric, FLIP_DEFAULT_THRESHOLDS};
use aerial::scene::Scene;
use std::path::{Path, PathBuf};
use std::process::Output;

/// The default scene's camera, ground, red ball and lights, plus (when
/// `speck` is true) a small gold sphere in front: 0.12 units in radius,
/// about 7 pixels across at 320x180, 0.1 % of the frame.
fn scene(speck: bool) -> Scene {
    let speck = if speck {
        r#"
[[objects]]
name = "speck"
material = "gold"
shape = { type = "sphere", radius = 0.12 }
tessellation = [32, 16]
translate = [0.0, 0.4, 1.5]
"#
    } else {
        ""
    };
    let mut scene = common::scene(&format!(
        r#"
ambient = [0.04, 0.04, 0.05]

[output]
width = 320
height = 180

[camera]
eye = [0.0, 2.4, 7.0]
look_at = [0.0, 0.8, 0.0]
fov_y = 45.0

[tone_map]
operator = "reinhard"

[[lights]]
type = "point"
position = [3.0, 4.0, 3.0]
color = [1.0, 0.92, 0.8]
intensity = 4.0
attenuation = [1.0, 0.0, 0.08]

[[lights]]
type = "directional"
direction = [-0.3, -1.0, -0.4]
color = [0.25, 0.25, 0.3]

[[materials]]
name = "red"
kd = [0.8, 0.08, 0.06]
ks = [0.6, 0.6, 0.6]
shininess = 48.0

[[materials]]
name = "gold"
kd = [0.8, 0.6, 0.2]
ks = [0.8, 0.7, 0.5]
shininess = 64.0

[[materials]]
name = "ground"
kd = [0.25, 0.25, 0.24]

[[objects]]
name = "ground"
material = "ground"
shape = {{ type = "plane", width = 14.0, depth = 14.0 }}

[[objects]]
name = "ball"
material = "red"
shape = {{ type = "sphere", radius = 1.0 }}
tessellation = [64, 32]
translate = [-1.4, 1.0, 0.0]
{speck}"#
    ));
    scene.set_output_size(Some(320), Some(180)).unwrap();
    scene
}

/// Turns the camera by `pixels` pixels (sideways, or up when `vertical`),
/// by moving the point it looks at: every edge in the image moves by about
/// that much, as a different rasteriser's sub-pixel rules might move it.
fn turned(mut scene: Scene, pixels: f32, vertical: bool) -> Scene {
    let c = scene.camera;
    let forward = (c.look_at - c.eye).normalize().as_vec3();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let distance = (c.look_at - c.eye).length() as f32;
    let pixel =
        2.0 * distance * (c.fov_y_degrees.to_radians() * 0.5).tan() / scene.output.height as f32;
    let direction = if vertical { up } else { right };
    scene.camera.look_at += (direction * pixel * pixels).as_dvec3();
    scene
}

/// A folder for one test's files: kept under `AERIAL_KEEP_TEST_IMAGES` if
/// set, otherwise a temporary one removed at the end.
struct Folder {
    path: PathBuf,
    keep: bool,
}

impl Folder {
    fn new(name: &str) -> Folder {
        let (path, keep) = match std::env::var_os("AERIAL_KEEP_TEST_IMAGES") {
            Some(dir) => (PathBuf::from(dir).join(name), true),
            None => (
                std::env::temp_dir().join(format!(
                    "aerial-local-defects-{name}-{}",
                    std::process::id()
                )),
                false,
            ),
        };
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path).unwrap();
        Folder { path, keep }
    }

    fn png(&self, name: &str, pixels: &Pixels<u8>) -> PathBuf {
        let path = self.path.join(name);
        image_io::write_png(&path, pixels, &[]).unwrap();
        path
    }

    fn exr(&self, name: &str, pixels: &Pixels<f32>) -> PathBuf {
        let path = self.path.join(name);
        image_io::write_exr(&path, pixels).unwrap();
        path
    }
}

impl Drop for Folder {
    fn drop(&mut self) {
        if !self.keep {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

fn ldr(scene: &Scene) -> Pixels<u8> {
    common::render(scene, false).output
}

fn hdr(scene: &Scene) -> Pixels<f32> {
    common::render(scene, true)
        .hdr
        .expect("keep_hdr returns the HDR image")
}

fn compare(reference: &Path, test: &Path, options: &[&str]) -> Output {
    common::aerial()
        .arg("compare")
        .arg(reference)
        .arg(test)
        .args(options)
        .output()
        .unwrap()
}

fn text(out: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Runs `aerial compare` with its defaults and asserts it passes.
fn assert_passes(reference: &Path, test: &Path, options: &[&str]) {
    let out = compare(reference, test, options);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("result  pass"),
        "{}",
        text(&out)
    );
}

/// Runs `aerial compare` with its defaults and asserts that it fails, and
/// fails on the worst window alone (mean and p99 are within their limits).
fn assert_fails_on_the_window(reference: &Path, test: &Path, options: &[&str]) {
    let out = compare(reference, test, options);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let result = stdout
        .lines()
        .find(|l| l.starts_with("result"))
        .unwrap_or_default();
    assert!(
        result.contains("FAIL: worst 12x12 window") && !result.contains(';'),
        "{}",
        text(&out)
    );
}

/// Inverts the colours of a `size` x `size` block with its top-left corner
/// at (`x`, `y`).
fn invert_block(image: &Pixels<u8>, x: u32, y: u32, size: u32) -> Pixels<u8> {
    let mut out = image.clone();
    for row in y..y + size {
        for col in x..x + size {
            let i = ((row * image.width + col) * 4) as usize;
            for c in &mut out.data[i..i + 3] {
                *c = 255 - *c;
            }
        }
    }
    out
}

/// Where the red ball is in the 320x180 image: the centre of the pixels
/// that are clearly red. Found from the render, so the block lands on the
/// ball wherever the camera puts it.
fn red_centre(image: &Pixels<u8>) -> (u32, u32) {
    let (mut sx, mut sy, mut n) = (0u64, 0u64, 0u64);
    for (i, p) in image.data.chunks_exact(4).enumerate() {
        if p[0] > 100 && p[0] / 2 > p[1] && p[0] / 2 > p[2] {
            sx += i as u64 % u64::from(image.width);
            sy += i as u64 / u64::from(image.width);
            n += 1;
        }
    }
    assert!(n > 500, "the red ball covers only {n} pixels");
    ((sx / n) as u32, (sy / n) as u32)
}

#[test]
fn small_png_defects_fail_and_driver_noise_passes() {
    let dir = Folder::new("png");
    let base = ldr(&scene(false));
    common::assert_not_blank(&base, 0.5);
    let reference = dir.png("reference.png", &base);

    // The reported case: a 12x12 block (0.25 % of the frame) inverted on
    // the red ball, a cyan square anyone would see.
    let (cx, cy) = red_centre(&base);
    let block = dir.png("block.png", &invert_block(&base, cx - 6, cy - 6, 12));
    assert_fails_on_the_window(&reference, &block, &[]);
    // The library agrees, and mean and p99 alone would have let it through.
    let diff: ImageDiff = compare_files(&reference, &block, Metric::Flip).unwrap();
    assert!(diff.mean <= 0.03 && diff.p99 <= 0.1, "{diff:?}");
    assert!(diff.worst_window > 0.6, "{diff:?}");
    assert!(!diff.passes(&FLIP_DEFAULT_THRESHOLDS));

    // A small sphere, 7 px across, added to or missing from the picture.
    let with_speck = dir.png("speck.png", &ldr(&scene(true)));
    assert_fails_on_the_window(&reference, &with_speck, &[]);
    assert_fails_on_the_window(&with_speck, &reference, &[]);

    // Up to +-3 LSB on every channel (a fixed pseudo-random pattern).
    let mut noisy = base.clone();
    let mut state = 0x2545_f491_u32;
    for (i, v) in noisy.data.iter_mut().enumerate() {
        if i % 4 != 3 {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let delta = (state >> 24) as i32 % 7 - 3;
            *v = (i32::from(*v) + delta).clamp(0, 255) as u8;
        }
    }
    let noisy = dir.png("noise.png", &noisy);
    assert_passes(&reference, &noisy, &[]);

    // The camera turned by 1/20 pixel, sideways and up.
    for vertical in [false, true] {
        let moved = ldr(&turned(scene(false), 0.05, vertical));
        assert_ne!(moved.data, base.data, "the turn changed nothing");
        let moved = dir.png(&format!("turned-{vertical}.png"), &moved);
        assert_passes(&reference, &moved, &[]);
    }
}

/// Rotates the colour channels (R, G, B to B, R, G) of a block: a local
/// colour error of about the scene's own brightness, for HDR images, where
/// inverting has no meaning.
fn rotate_block(image: &Pixels<f32>, x: u32, y: u32, size: u32) -> Pixels<f32> {
    let mut out = image.clone();
    for row in y..y + size {
        for col in x..x + size {
            let i = ((row * image.width + col) * 4) as usize;
            out.data[i..i + 3].rotate_right(1);
        }
    }
    out
}

#[test]
fn small_exr_defects_fail_and_driver_noise_passes() {
    let dir = Folder::new("exr");
    let base = hdr(&scene(false));
    let reference = dir.exr("reference.exr", &base);
    let (cx, cy) = red_centre(&ldr(&scene(false)));

    for metric in ["rmse", "psnr"] {
        let options = ["--metric", metric];
        let block = dir.exr("block.exr", &rotate_block(&base, cx - 6, cy - 6, 12));
        assert_fails_on_the_window(&reference, &block, &options);

        let with_speck = dir.exr("speck.exr", &hdr(&scene(true)));
        assert_fails_on_the_window(&reference, &with_speck, &options);
        assert_fails_on_the_window(&with_speck, &reference, &options);

        // Up to +-1 % on every channel, far more than half-float rounding.
        let mut noisy = base.clone();
        let mut state = 0x9e37_79b9_u32;
        for v in &mut noisy.data {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            *v *= 1.0 + ((state >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * 0.02;
        }
        let noisy = dir.exr("noise.exr", &noisy);
        assert_passes(&reference, &noisy, &options);

        for vertical in [false, true] {
            let moved = dir.exr(
                &format!("turned-{vertical}.exr"),
                &hdr(&turned(scene(false), 0.05, vertical)),
            );
            assert_passes(&reference, &moved, &options);
        }
    }

    // The relative window error does not depend on the exposure: the same
    // defect in an image 100 times brighter scores the same.
    let scale = |p: &Pixels<f32>| Pixels {
        width: p.width,
        height: p.height,
        data: p.data.iter().map(|v| v * 100.0).collect(),
    };
    let block = rotate_block(&base, cx - 6, cy - 6, 12);
    let dim = compare_files(&reference, &dir.exr("b1.exr", &block), Metric::Rmse).unwrap();
    let bright = compare_files(
        &dir.exr("r100.exr", &scale(&base)),
        &dir.exr("b100.exr", &scale(&block)),
        Metric::Rmse,
    )
    .unwrap();
    assert!(dim.hdr && bright.hdr);
    assert!(
        (dim.worst_window - bright.worst_window).abs() < 1e-4 * dim.worst_window,
        "{} vs {}",
        dim.worst_window,
        bright.worst_window
    );
}
