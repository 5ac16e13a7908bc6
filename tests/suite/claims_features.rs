//! Independent checks of features whose other tests would pass a broken
//! implementation: mip levels and texture filters, tone-map exposure,
//! toon shading, per-object light culling, PNG metadata and determinism
//! across processes. Every render runs under validation (all checks) with
//! zero messages.

use crate::common;

use aerial::render::Pixels;
use std::path::{Path, PathBuf};

use common::aerial;

// ---------------------------------------------------------------------------
// Mip levels and texture filters
//
// A 512x512 one-texel black/white checker (sRGB 0 and 255, linear 0 and 1)
// on a plane facing the camera, lit by ambient light only (ka = 1,
// ambient = 1), so the linear HDR value of a pixel is the filtered texture
// value itself. A plane parallel to the image plane maps to the screen by a
// uniform scale, so every pixel covers the same number of texels, rho, and
// the level of detail is lambda = log2(rho) everywhere.
//
// Level 0 is the checker; every level from 1 on is the mean of 2x2 black
// and white texels, uniform grey 0.5 (linear; stored as sRGB 188, which
// decodes to 0.503). Hence, independently of the renderer:
// - lambda = 2.5: every filter reads only grey levels: every pixel 0.5.
// - lambda = 0.4: `nearest` reads level 0 with the nearest texel: every
//   pixel exactly 0 or 1. `bilinear` reads level 0 with bilinear
//   filtering: values in between. `trilinear` blends that same level-0
//   sample with level 1 (grey) by the fraction 0.4, so at every pixel
//   trilinear - 0.5 = (1 - 0.4) (bilinear - 0.5).

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
    let dir = common::fresh_dir("claims-features", "mip");
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
    let dir = common::fresh_dir("claims-features", "filters");
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

// ---------------------------------------------------------------------------
// Tone mapping: both operators at exposures other than 1, through the
// library and through `aerial tonemap --operator --exposure`. The oracle is
// the operators' formulas and the sRGB encoding, within one 8-bit step.

fn srgb_encode(linear: f64) -> f64 {
    let c = linear.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

fn reinhard(x: f64) -> f64 {
    x / (1.0 + x)
}

/// Narkowicz's ACES fit, as docs/frame.md names it.
fn aces(x: f64) -> f64 {
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// Log-spaced values 1e-3 .. 1e2 in R, half of them in G, twice in B.
fn hdr_ramp() -> Pixels<f32> {
    let n = 101;
    let data = (0..n)
        .flat_map(|i| {
            let x = 10f32.powf(-3.0 + i as f32 * 0.05);
            [x, 0.5 * x, 2.0 * x, 1.0]
        })
        .collect();
    Pixels {
        width: n,
        height: 1,
        data,
    }
}

fn assert_tone_mapped(
    what: &str,
    input: &Pixels<f32>,
    output: &[u8],
    exposure: f64,
    curve: fn(f64) -> f64,
) {
    assert_eq!(output.len(), input.data.len(), "{what}");
    let mut worst: f64 = 0.0;
    for (i, (inp, got)) in input.data.iter().zip(output).enumerate() {
        if i % 4 == 3 {
            assert_eq!(*got, 255, "{what}: alpha");
            continue;
        }
        let expected = 255.0 * srgb_encode(curve(*inp as f64 * exposure));
        worst = worst.max((*got as f64 - expected).abs());
        assert!(
            (*got as f64 - expected).abs() <= 1.0,
            "{what}: value {i}: input {inp}, got {got}, expected {expected:.2}"
        );
    }
    // Exposure must have mattered: without it some outputs would be off by
    // far more than the tolerance.
    let unexposed = input
        .data
        .iter()
        .zip(output)
        .enumerate()
        .filter(|(i, _)| i % 4 != 3)
        .map(|(_, (inp, got))| (255.0 * srgb_encode(curve(*inp as f64)) - *got as f64).abs())
        .fold(0.0, f64::max);
    assert!(
        unexposed > 10.0,
        "{what}: exposure {exposure} changed nothing"
    );
}

#[test]
fn both_operators_apply_the_exposure() {
    use aerial::app::{self, RenderSettings, RunSource};
    use aerial::scene::{ToneMap, ToneMapOperator};
    let input = hdr_ramp();
    for (operator, curve) in [
        (ToneMapOperator::Aces, aces as fn(f64) -> f64),
        (ToneMapOperator::Reinhard, reinhard),
    ] {
        for exposure in [0.3f32, 3.0] {
            let run = app::run(
                RunSource::HdrImage(&input, ToneMap { operator, exposure }),
                &RenderSettings {
                    validate: aerial::vk::validation::Validation::All,
                    ..Default::default()
                },
                &mut || {},
            )
            .unwrap();
            common::assert_no_validation_messages(&run);
            assert_tone_mapped(
                &format!("{operator:?} at exposure {exposure}"),
                &input,
                &run.output.data,
                exposure as f64,
                curve,
            );
        }
    }
}

#[test]
fn the_tonemap_command_honours_operator_and_exposure() {
    let dir = common::fresh_dir("claims-features", "tonemap");
    let exr = dir.join("ramp.exr");
    let input = hdr_ramp();
    aerial::image_io::write_exr(&exr, &input).unwrap();
    for (operator, curve, exposure) in [
        ("aces", aces as fn(f64) -> f64, 2.5),
        ("reinhard", reinhard as fn(f64) -> f64, 0.4),
    ] {
        let png = dir.join(format!("{operator}.png"));
        let out = aerial()
            .arg("tonemap")
            .arg(&exr)
            .args(["--operator", operator, "--exposure", &exposure.to_string()])
            .arg("--validate")
            .arg("--out")
            .arg(&png)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{operator}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let img = image::open(&png).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (input.width, input.height));
        assert_tone_mapped(
            &format!("aerial tonemap --operator {operator} --exposure {exposure}"),
            &input,
            img.as_raw(),
            exposure,
            curve,
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------------
// Timings: the passes run inside the submission the CPU frame time spans
// (submit to fence), so their sum cannot exceed it. A timestamp period or
// mask applied wrongly (ticks read as milliseconds, garbage high bits)
// breaks this by orders of magnitude.

#[test]
fn the_sum_of_pass_times_does_not_exceed_the_cpu_frame_time() {
    let mut scene = aerial::scene::Scene::default_scene();
    scene.set_output_size(Some(160), Some(90)).unwrap();
    let run = aerial::app::render(
        &scene,
        &aerial::app::RenderSettings {
            validate: aerial::vk::validation::Validation::All,
            warmup: 1,
            frames: 5,
            ..Default::default()
        },
    )
    .unwrap();
    common::assert_no_validation_messages(&run);
    assert_eq!(run.frames.len(), 5);
    for (i, f) in run.frames.iter().enumerate() {
        assert_eq!(
            f.pass_ms.len(),
            run.passes.len(),
            "frame {i}: one time per pass"
        );
        let gpu: f64 = f.pass_ms.iter().sum();
        assert!(
            f.pass_ms.iter().all(|t| t.is_finite() && *t >= 0.0) && gpu > 0.0,
            "frame {i}: {:?}",
            f.pass_ms
        );
        assert!(
            gpu <= f.cpu_ms,
            "frame {i}: passes sum to {gpu} ms, more than the CPU frame time {} ms",
            f.cpu_ms
        );
    }
}

// ---------------------------------------------------------------------------
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
        aerial()
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
    let dir = common::fresh_dir("claims-features", "determinism");
    let (png_a, exr_a) = render_with_cli(&dir, "a");
    let (png_b, exr_b) = render_with_cli(&dir, "b");

    let a = image::open(&png_a).unwrap().to_rgba8();
    let b = image::open(&png_b).unwrap().to_rgba8();
    assert_eq!(a.dimensions(), (160, 90));
    let decoded = Pixels {
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
    assert_eq!(read_png_text_of(&png_b), text);
    std::fs::remove_dir_all(&dir).ok();
}

fn read_png_text_of(path: &Path) -> Vec<(String, String)> {
    aerial::image_io::read_png_text(path).unwrap()
}

// ---------------------------------------------------------------------------
// The bench gate fails when nothing matched: a gate that compared nothing
// must not pass.

#[test]
fn the_bench_gate_fails_when_no_pass_matched() {
    let dir = common::fresh_dir("claims-features", "gate");
    let current = dir.join("current.json");
    common::succeed(common::tiny_triangle_bench(2).arg("--json").arg(&current));

    // The same report compared with itself is not a failure; with every scene renamed
    // and no empty pass, nothing matches and the gate fails, whatever the
    // ratio limit.
    let gate = |baseline: &Path| {
        aerial()
            .arg("bench")
            .arg("--from-json")
            .arg(&current)
            .arg("--compare")
            .arg(baseline)
            .args(["--max-ratio", "1000"])
            .output()
            .unwrap()
    };
    // (Passes, or is inconclusive when a subpass timed near 0 in one of
    // the two frames and its ratio's interval reaches past the limit.)
    let same = gate(&current);
    assert!(
        matches!(same.status.code(), Some(0) | Some(3)),
        "{}",
        String::from_utf8_lossy(&same.stderr)
    );

    let mut value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&current).unwrap()).unwrap();
    value["empty_passes"] = serde_json::json!([]);
    for s in value["scenes"].as_array_mut().unwrap() {
        s["file"] = serde_json::json!("some/other/scene.toml");
    }
    let baseline = dir.join("baseline.json");
    std::fs::write(&baseline, serde_json::to_string(&value).unwrap()).unwrap();
    let out = gate(&baseline);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("nothing to compare"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------------
// Toon shading on a sphere, against a ray-traced oracle.
//
// A unit sphere at the origin seen from (0, 0, 4), lit by one directional
// light travelling along -Z (radiance 1), kd = 0.5, ks = 0.3, no ambient.
// Every visible point has N.L = N.z >= R/D = 0.25 (the silhouette circle
// lies at z = R^2/D), so it is lit: the diffuse tones are 0.5 (N.L > 0.5)
// and 0.2 (0.4 x 0.5, for 0 < N.L <= 0.5), the highlight adds 0.3, and the
// silhouette where |N.V| < 0.2 is black. Which pixels are in the silhouette
// ring follows from the exact ray-sphere intersection through each pixel
// centre; the scene is symmetric about the view axis, so the image's
// orientation does not matter.

const TOON_SIZE: u32 = 128;
const TOON_EYE: f64 = 4.0;
const TOON_FOV_DEG: f64 = 40.0;

/// |N.V| at the sphere point seen through pixel (x, y), or None if the
/// pixel's ray misses the unit sphere.
fn sphere_n_dot_v(x: u32, y: u32) -> Option<f64> {
    let half = (TOON_FOV_DEG.to_radians() / 2.0).tan();
    let px = ((x as f64 + 0.5) / TOON_SIZE as f64 * 2.0 - 1.0) * half;
    let py = ((y as f64 + 0.5) / TOON_SIZE as f64 * 2.0 - 1.0) * half;
    let len = (px * px + py * py + 1.0).sqrt();
    let d = [px / len, py / len, -1.0 / len];
    // |E + t d|^2 = 1 with E = (0, 0, D): t^2 + 2 t (E.d) + D^2 - 1 = 0.
    let b = TOON_EYE * d[2];
    let disc = b * b - (TOON_EYE * TOON_EYE - 1.0);
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    let p = [t * d[0], t * d[1], TOON_EYE + t * d[2]];
    // N = P (unit sphere), V = -d.
    Some((p[0] * d[0] + p[1] * d[1] + p[2] * d[2]).abs())
}

#[test]
fn toon_has_two_diffuse_tones_a_highlight_and_a_silhouette_of_the_right_width() {
    let toml = format!(
        r#"
[output]
width = {TOON_SIZE}
height = {TOON_SIZE}
hdr_format = "rgba32f"
[camera]
eye = [0.0, 0.0, {TOON_EYE}]
look_at = [0.0, 0.0, 0.0]
fov_y = {TOON_FOV_DEG}
[[lights]]
type = "directional"
direction = [0.0, 0.0, -1.0]
[[materials]]
name = "m"
kd = [0.5, 0.5, 0.5]
ka = [0.0, 0.0, 0.0]
ks = [0.3, 0.3, 0.3]
shininess = 60.0
shading = "toon"
[[objects]]
name = "ball"
material = "m"
shape = {{ type = "sphere", radius = 1.0 }}
tessellation = [256, 128]
"#
    );
    let run = common::render(&common::scene(&toml), true);
    let hdr = run.hdr.unwrap();

    // The only values on the sphere: black, the two tones, tone + highlight.
    let allowed = [0.0, 0.2, 0.5, 0.8];
    let mut seen = [0usize; 4];
    let (mut ring_expected, mut ring_rendered, mut wrong) = (0usize, 0usize, Vec::new());
    for y in 0..TOON_SIZE {
        for x in 0..TOON_SIZE {
            let p = common::pixel(&hdr, x, y);
            if p[3] == 0.0 {
                continue; // background: not covered by the mesh
            }
            let v = p[0] as f64;
            assert!(
                p[1] == p[0] && p[2] == p[0],
                "({x}, {y}) is not grey: {p:?}"
            );
            let k = allowed
                .iter()
                .position(|a| (v - a).abs() < 1e-4)
                .unwrap_or_else(|| panic!("({x}, {y}) = {v}: not one of {allowed:?}"));
            seen[k] += 1;
            let Some(n_dot_v) = sphere_n_dot_v(x, y) else {
                continue; // covered by a polygon, missed by the exact sphere
            };
            let black = k == 0;
            ring_expected += (n_dot_v < 0.2) as usize;
            ring_rendered += black as usize;
            // Within 0.02 of the threshold, the mesh's interpolated normals
            // may fall either way; elsewhere the classification is exact.
            if (n_dot_v - 0.2).abs() > 0.02 && black != (n_dot_v < 0.2) {
                wrong.push((x, y, n_dot_v, v));
            }
        }
    }
    assert!(wrong.is_empty(), "silhouette misclassified at {wrong:?}");
    // Each kind of pixel is present: ring, dark tone, bright tone, highlight.
    // (This also rules out a blank image: the sphere covers about a third
    // of the view.)
    assert!(seen.iter().all(|&n| n > 10), "pixel counts {seen:?}");
    assert!(seen.iter().sum::<usize>() > 4000, "pixel counts {seen:?}");
    // The ring's area matches |N.V| < 0.2 within 10 %.
    let ratio = ring_rendered as f64 / ring_expected as f64;
    eprintln!("toon: pixels {seen:?}, ring {ring_rendered} rendered, {ring_expected} predicted");
    assert!(
        (0.9..=1.1).contains(&ratio),
        "black ring {ring_rendered} pixels, |N.V| < 0.2 predicts {ring_expected}"
    );
}

// ---------------------------------------------------------------------------
// Per-object light culling, checked on pixels.
//
// A unit sphere at the origin, seen from (0, 0, 5), lit by a dim directional
// light and a point light at (0, 0, 4) with attenuation 1/(1 + d^2). The
// point light's distance to the sphere's bounding sphere is 3, so it
// reaches the object with at most 1/10 of its intensity I. With
// light_cutoff = 0.01 it is culled for I = 0.05 (0.005 < 0.01) and kept for
// I = 0.15 (0.015 > 0.01; judged at the sphere's centre, 4 away, it would
// wrongly be culled: 0.15/17 < 0.01).
//
// A culled light contributes nothing, and with the windowed attenuation
// (1 / (1 + d^2) - cutoff / I, clamped at 0) a light beyond its range
// contributes nothing either, so culling changes no pixel. Against no
// cutoff at all (no window) the difference is at most the light's
// unwindowed radiance at the nearest point, I/10, times kd + ks = 1, for
// a light that is culled, and cutoff x (kd + ks) for one that is kept.

fn culling_scene(intensity: Option<f64>, cutoff: f64) -> aerial::scene::Scene {
    let light = intensity.map_or(String::new(), |i| {
        format!(
            "[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 4.0]\n\
             intensity = {i}\nattenuation = [1.0, 0.0, 1.0]\n"
        )
    });
    common::scene(&format!(
        r#"
light_cutoff = {cutoff}
[output]
width = 96
height = 96
hdr_format = "rgba32f"
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
[[lights]]
type = "directional"
direction = [-1.0, -1.0, -1.0]
intensity = 0.5
{light}
[[materials]]
name = "m"
kd = [0.5, 0.5, 0.5]
ka = [0.0, 0.0, 0.0]
ks = [0.5, 0.5, 0.5]
shininess = 20.0
[[objects]]
name = "ball"
material = "m"
shape = {{ type = "sphere", radius = 1.0 }}
"#
    ))
}

/// Largest per-channel difference over pixels covered in both images, and
/// how many covered pixels there are.
fn max_difference(a: &Pixels<f32>, b: &Pixels<f32>) -> (f64, usize) {
    let mut worst: f64 = 0.0;
    let mut covered = 0;
    for (pa, pb) in a.data.chunks_exact(4).zip(b.data.chunks_exact(4)) {
        if pa[3] == 0.0 || pb[3] == 0.0 {
            continue;
        }
        covered += 1;
        for c in 0..3 {
            worst = worst.max((pa[c] as f64 - pb[c] as f64).abs());
        }
    }
    (worst, covered)
}

fn hdr(scene: &aerial::scene::Scene) -> Pixels<f32> {
    let run = common::render(scene, true);
    common::assert_not_blank(&run.output, 0.2);
    run.hdr.unwrap()
}

#[test]
fn a_culled_light_changes_no_pixel_beyond_the_cutoff_bound() {
    let cutoff = 0.01;
    let without = hdr(&culling_scene(None, cutoff));

    // Culled: the object's pixels are exactly those without the light.
    let culled = hdr(&culling_scene(Some(0.05), cutoff));
    let (diff, covered) = max_difference(&culled, &without);
    assert!(covered > 2000, "{covered} covered pixels");
    assert_eq!(diff, 0.0, "a culled light changed the object");

    // Without culling the same light does reach the object, by no more
    // than the bound I/10 x (kd + ks) = 0.005 (plus float rounding).
    let exact = hdr(&culling_scene(Some(0.05), 0.0));
    let (diff, _) = max_difference(&exact, &culled);
    assert!(
        diff > 0.001 && diff <= 0.005 + 1e-5,
        "culling changed a pixel by {diff}, bound 0.005"
    );

    // Above the cutoff the light is kept, and it changes the object: its
    // windowed attenuation (1 / (1 + d^2) - cutoff / I, from d = 3 at the
    // nearest point) gives 0.15 x (0.1 - 0.0667) x (kd + ks) = 0.005 there.
    let kept = hdr(&culling_scene(Some(0.15), cutoff));
    let (diff, _) = max_difference(&kept, &without);
    assert!(
        diff > 0.003 && diff <= 0.005 + 1e-5,
        "a light above the cutoff changed the object by {diff}, expected 0.005"
    );
    // The window dims it by at most cutoff x (kd + ks) = 0.01 against no
    // cutoff at all.
    let kept_exact = hdr(&culling_scene(Some(0.15), 0.0));
    let (diff, _) = max_difference(&kept, &kept_exact);
    assert!(
        diff > 0.0 && diff <= 0.01 + 1e-5,
        "the window changed a pixel by {diff}, bound 0.01"
    );
}
