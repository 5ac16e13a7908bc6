//! Mip levels and texture filters (`[output] texture_filter`), checked on
//! pixels. Every render runs under validation with zero messages.
//!
//! A 512x512 one-texel black/white checker (sRGB 0 and 255, linear 0 and 1)
//! on a plane facing the camera, lit by ambient light only (ka = 1,
//! ambient = 1), so the linear HDR value of a pixel is the filtered texture
//! value itself. A plane parallel to the image plane maps to the screen by a
//! uniform scale, so every pixel covers the same number of texels, rho, and
//! the level of detail is lambda = log2(rho) everywhere.
//!
//! Level 0 is the checker; every level from 1 on is the mean of 2x2 black
//! and white texels, uniform grey 0.5 (linear; stored as sRGB 188, which
//! decodes to 0.503). Hence, independently of the renderer:
//! - lambda = 2.5: every filter reads only grey levels: every pixel 0.5.
//! - lambda = 0.4: `nearest` reads level 0 with the nearest texel: every
//!   pixel exactly 0 or 1. `bilinear` reads level 0 with bilinear
//!   filtering: values in between. `trilinear` blends that same level-0
//!   sample with level 1 (grey) by the fraction 0.4, so at every pixel
//!   trilinear - 0.5 = (1 - 0.4) (bilinear - 0.5).

use crate::common;

use aerial::render::Pixels;
use std::path::{Path, PathBuf};

const CHECKER_SIZE: u32 = 512;
const VIEW: u32 = 64;
const EYE_HEIGHT: f64 = 2.0;
const FOV_Y_DEG: f64 = 45.0;

fn checker_texture(dir: &Path) -> PathBuf {
    let img = image::RgbaImage::from_fn(CHECKER_SIZE, CHECKER_SIZE, |x, y| {
        let v = if (x + y) % 2 == 0 { 255 } else { 0 };
        image::Rgba([v, v, v, 255])
    });
    let path = dir.join("checker1.png");
    img.save(&path).unwrap();
    path
}

/// The plane's width for which one pixel covers 2^lambda texels.
fn plane_width(lambda: f64) -> f64 {
    let pixel = 2.0 * EYE_HEIGHT * (FOV_Y_DEG.to_radians() / 2.0).tan() / VIEW as f64;
    CHECKER_SIZE as f64 * pixel / 2f64.powf(lambda)
}

fn checker_render(texture: &Path, lambda: f64, filter: &str) -> Pixels<f32> {
    let w = plane_width(lambda);
    let toml = format!(
        r#"
ambient = [1.0, 1.0, 1.0]
[output]
width = {VIEW}
height = {VIEW}
hdr_format = "rgba32f"
texture_filter = "{filter}"
[camera]
eye = [0.0, {EYE_HEIGHT}, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_y = {FOV_Y_DEG}
[[materials]]
name = "checker"
kd = [1.0, 1.0, 1.0]
ka = [1.0, 1.0, 1.0]
texture = "{}"
[[objects]]
name = "floor"
material = "checker"
shape = {{ type = "plane", width = {w}, depth = {w} }}
tessellation = [4, 4]
"#,
        texture.display()
    );
    let run = common::render(&common::scene(&toml), true);
    run.hdr.expect("HDR kept")
}

/// The red channel of every pixel (the texture is grey).
fn values(p: &Pixels<f32>) -> Vec<f64> {
    p.data.chunks_exact(4).map(|c| c[0] as f64).collect()
}

#[test]
fn a_strongly_minified_checker_is_the_grey_of_its_mip_levels() {
    let dir = common::fresh_dir("texture-filters", "mip");
    let texture = checker_texture(&dir);
    // The plane must fill the view, or the background would be counted.
    assert!(plane_width(2.5) > 2.0 * EYE_HEIGHT * (FOV_Y_DEG.to_radians() / 2.0).tan());
    for filter in ["nearest", "bilinear", "trilinear"] {
        let v = values(&checker_render(&texture, 2.5, filter));
        // 0.5 +- 0.01: the 8-bit sRGB storage of the grey levels (188 is
        // 0.503) plus filtering rounding.
        let worst = v.iter().map(|x| (x - 0.5).abs()).fold(0.0, f64::max);
        assert!(
            worst <= 0.01,
            "{filter}: a pixel is {worst:.4} from the mip levels' grey 0.5"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn nearest_bilinear_and_trilinear_differ_as_their_definitions_say() {
    let dir = common::fresh_dir("texture-filters", "filters");
    let texture = checker_texture(&dir);
    let lambda = 0.4;
    let nearest = values(&checker_render(&texture, lambda, "nearest"));
    let bilinear = values(&checker_render(&texture, lambda, "bilinear"));
    let trilinear = values(&checker_render(&texture, lambda, "trilinear"));

    // Nearest: single texels of level 0, black or white, both present.
    assert!(
        nearest.iter().all(|x| *x <= 0.01 || *x >= 0.99),
        "nearest gave an in-between value"
    );
    let white = nearest.iter().filter(|x| **x >= 0.99).count() as f64 / nearest.len() as f64;
    assert!((0.3..=0.7).contains(&white), "white fraction {white}");

    // Bilinear: level 0 blended between texels, so most pixels are in
    // between; its spread is well below nearest's 0.5 (for uniformly
    // spread sample positions its RMS deviation from 0.5 is 1/6).
    let rms =
        |v: &[f64]| (v.iter().map(|x| (x - 0.5).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
    let between = bilinear.iter().filter(|x| **x > 0.02 && **x < 0.98).count();
    assert!(
        between * 2 > bilinear.len(),
        "bilinear is mostly black/white"
    );
    let rms_b = rms(&bilinear);
    assert!(
        (0.1..=0.25).contains(&rms_b),
        "bilinear RMS deviation {rms_b:.4}"
    );

    // Trilinear: the bilinear deviation scaled by 1 - 0.4 pixel by pixel;
    // the least-squares ratio must be 0.6 within 0.06 (the driver's
    // level-of-detail arithmetic is approximate). Nearest-mip sampling
    // would give 1.0.
    let (num, den) = trilinear
        .iter()
        .zip(&bilinear)
        .fold((0.0, 0.0), |(n, d), (t, b)| {
            (n + (t - 0.5) * (b - 0.5), d + (b - 0.5).powi(2))
        });
    let ratio = num / den;
    eprintln!("bilinear RMS {rms_b:.4}, trilinear/bilinear ratio {ratio:.4}");
    assert!(
        (ratio - (1.0 - lambda)).abs() <= 0.06,
        "trilinear / bilinear deviation ratio {ratio:.4}, expected {:.2}",
        1.0 - lambda
    );
    std::fs::remove_dir_all(&dir).ok();
}
