//! `aerial compare` as a CI step sees it: exit status (0 pass, 1 threshold
//! exceeded, 2 error), the printed numbers, the diff file and the error
//! messages. Runs the built binary on small synthetic images; no GPU needed.

use crate::common::Scratch;
use aerial::image_io;
use aerial::render::Pixels;
use image::{Rgb, RgbImage};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn compare(args: &[&Path], options: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aerial"))
        .arg("compare")
        .args(args)
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

/// A 96x64 picture with edges and gradients, so FLIP has structure to see.
fn picture() -> RgbImage {
    RgbImage::from_fn(96, 64, |x, y| {
        let inside = (x as i32 - 48).pow(2) + (y as i32 - 32).pow(2) < 400;
        if inside {
            Rgb([200, 40, 30])
        } else {
            Rgb([(x * 2) as u8, (y * 3) as u8, 90])
        }
    })
}

fn save(dir: &Scratch, name: &str, img: &RgbImage) -> PathBuf {
    let path = dir.path(name);
    img.save(&path).unwrap();
    path
}

#[test]
fn identical_images_pass() {
    let dir = Scratch::new();
    let a = save(&dir, "a.png", &picture());
    let b = save(&dir, "b.png", &picture());
    let out = compare(&[&a, &b], &[]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    // The defaults are applied and shown.
    assert!(stdout.contains("limit <= 0.03"), "{}", text(&out));
    assert!(stdout.contains("limit <= 0.1"), "{}", text(&out));
    assert!(stdout.contains("limit <= 0.3"), "{}", text(&out));
    assert!(stdout.contains("result  pass"), "{}", text(&out));
}

#[test]
fn a_small_rounding_difference_passes_the_defaults() {
    let dir = Scratch::new();
    let mut changed = picture();
    for (i, p) in changed.pixels_mut().enumerate() {
        if i % 3 == 0 {
            p.0[1] = p.0[1].saturating_add(1);
        }
    }
    let a = save(&dir, "a.png", &picture());
    let b = save(&dir, "b.png", &changed);
    let out = compare(&[&a, &b], &[]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
}

#[test]
fn a_modified_image_fails_and_writes_the_diff() {
    let dir = Scratch::new();
    let mut broken = picture();
    // The red disc is gone: a missing object.
    for (x, y, p) in broken.enumerate_pixels_mut() {
        *p = Rgb([(x * 2) as u8, (y * 3) as u8, 90]);
    }
    let a = save(&dir, "a.png", &picture());
    let b = save(&dir, "b.png", &broken);
    let diff = dir.path("diff.png");
    let out = compare(&[&a, &b], &["--diff", diff.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("FAIL"),
        "{}",
        text(&out)
    );
    let img = image::open(&diff).unwrap();
    assert_eq!((img.width(), img.height()), (96, 64));

    // A loose enough limit lets the same pair through.
    let out = compare(
        &[&a, &b],
        &[
            "--threshold",
            "1",
            "--p99-threshold",
            "1",
            "--window-threshold",
            "1",
            "--metric",
            "flip",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
}

#[test]
fn psnr_threshold_is_a_minimum() {
    let dir = Scratch::new();
    let mut changed = picture();
    changed.put_pixel(3, 3, Rgb([255, 255, 255]));
    let a = save(&dir, "a.png", &picture());
    let b = save(&dir, "b.png", &changed);
    let out = compare(&[&a, &b], &["--metric", "psnr", "--threshold", "30"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let out = compare(&[&a, &b], &["--metric", "psnr", "--threshold", "90"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    // Without limits rmse and psnr only report.
    let out = compare(&[&a, &b], &["--metric", "rmse"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("not checked"),
        "{}",
        text(&out)
    );
}

#[test]
fn a_size_mismatch_is_a_clear_error() {
    let dir = Scratch::new();
    let a = save(&dir, "ref.png", &picture());
    let b = save(&dir, "small.png", &RgbImage::new(95, 64));
    let diff = dir.path("diff.png");
    let out = compare(&[&a, &b], &["--diff", diff.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("sizes differ"), "{}", text(&out));
    assert!(
        stderr.contains("ref.png") && stderr.contains("96x64"),
        "{}",
        text(&out)
    );
    assert!(
        stderr.contains("small.png") && stderr.contains("95x64"),
        "{}",
        text(&out)
    );
    assert!(!diff.exists());
}

#[test]
fn a_missing_file_is_a_clear_error_naming_it() {
    let dir = Scratch::new();
    let a = save(&dir, "a.png", &picture());
    let missing = dir.path("no-such-image.png");
    for args in [[a.as_path(), &missing], [&missing, &a]] {
        let out = compare(&args, &[]);
        assert_eq!(out.status.code(), Some(2), "{}", text(&out));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("no-such-image.png") && stderr.contains("cannot read"),
            "{}",
            text(&out)
        );
        assert!(!stderr.contains("panicked"), "{}", text(&out));
    }
}

#[test]
fn bad_options_and_flip_on_exr_are_errors() {
    let dir = Scratch::new();
    let a = save(&dir, "a.png", &picture());
    for bad in [
        &["--threshold", "nan"][..],
        &["--threshold", "-0.1"],
        &["--p99-threshold", "-1"],
        &["--window-threshold", "-0.5"],
        &["--window-threshold", "nan"],
        &["--metric", "ssim"],
    ] {
        let out = compare(&[&a, &a], bad);
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {}", text(&out));
    }

    let exr = dir.path("a.exr");
    let hdr = Pixels {
        width: 4,
        height: 4,
        data: vec![0.5f32; 64],
    };
    image_io::write_exr(&exr, &hdr).unwrap();
    let out = compare(&[&exr, &exr], &[]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("a.exr") && stderr.contains("rmse"),
        "{}",
        text(&out)
    );
    let out = compare(&[&exr, &exr], &["--metric", "rmse", "--threshold", "0"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
}

#[test]
fn the_rendering_device_and_driver_are_reported() {
    let dir = Scratch::new();
    let pixels = Pixels {
        width: 8,
        height: 8,
        data: vec![128u8; 8 * 8 * 4],
    };
    let made_by = |driver: &str| {
        vec![
            ("aerial:device", "llvmpipe".to_string()),
            ("aerial:driver", driver.to_string()),
        ]
    };
    let (a, b) = (dir.path("a.png"), dir.path("b.png"));
    image_io::write_png(&a, &pixels, &made_by("Mesa 24.0")).unwrap();
    image_io::write_png(&b, &pixels, &made_by("Mesa 25.1")).unwrap();
    let out = compare(&[&a, &b], &[]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("llvmpipe; driver Mesa 24.0")
            && stdout.contains("llvmpipe; driver Mesa 25.1"),
        "{}",
        text(&out)
    );
    assert!(
        stdout.contains("different devices or drivers"),
        "{}",
        text(&out)
    );
}

/// Runs `aerial compare` and returns its exit code and its own peak
/// resident memory: `VmHWM` of its process, read while it runs (a high-water
/// mark, so a late read still holds the peak). Not the child's rusage: a
/// child spawned from this process starts as a copy of it, and its
/// `ru_maxrss` keeps this (large) process's peak from before the exec.
#[cfg(target_os = "linux")]
fn compare_with_peak(a: &Path, b: &Path, metric: &str) -> (i32, u64) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_aerial"))
        .args(["compare", "--metric", metric])
        .arg(a)
        .arg(b)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let status_file = format!("/proc/{}/status", child.id());
    let mut peak = 0u64;
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code().unwrap_or(-1);
        }
        let hwm = std::fs::read_to_string(&status_file).ok().and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?.to_owned();
            line.split_whitespace().nth(1)?.parse::<u64>().ok()
        });
        peak = peak.max(hwm.unwrap_or(0) * 1024);
        std::thread::sleep(std::time::Duration::from_millis(2));
    };
    assert!(peak > 0, "no reading of the child's memory");
    (code, peak)
}

/// `compare` sizes its memory from the headers before decoding: the
/// estimate (`BYTES_PER_PIXEL` per pixel of each image plus the files)
/// bounds the whole process's measured peak for PNG with FLIP and OpenEXR
/// with RMSE, and a budget below it refuses the comparison by name.
#[test]
#[cfg(target_os = "linux")]
fn compare_memory_is_estimated_before_decoding_and_bounds_the_peak() {
    let dir = Scratch::new();
    let side = 1024u32;
    let noisy = |seed: u32| {
        RgbImage::from_fn(side, side, |x, y| {
            let h = (x.wrapping_mul(73856093) ^ y.wrapping_mul(19349663) ^ seed) % 251;
            Rgb([(x % 256) as u8, (y % 256) as u8, h as u8])
        })
    };
    let a = save(&dir, "a.png", &noisy(1));
    let b = save(&dir, "b.png", &noisy(2));
    let hdr = |seed: u32| Pixels {
        width: side,
        height: side,
        data: (0..side * side * 4)
            .map(|i| ((i ^ seed) % 97) as f32 / 13.0)
            .collect(),
    };
    let ea = dir.path("a.exr");
    let eb = dir.path("b.exr");
    image_io::write_exr(&ea, &hdr(1)).unwrap();
    image_io::write_exr(&eb, &hdr(2)).unwrap();
    for (x, y, metric) in [(&a, &b, "flip"), (&ea, &eb, "rmse")] {
        let files = std::fs::metadata(x).unwrap().len() + std::fs::metadata(y).unwrap().len();
        let estimate =
            2 * u64::from(side * side) * aerial::report::image_diff::BYTES_PER_PIXEL + files;
        let (code, peak) = compare_with_peak(x, y, metric);
        assert!(code == 0 || code == 1, "{metric}: exit {code}");
        eprintln!("{metric}: peak {peak} bytes, estimate {estimate}");
        assert!(
            peak <= estimate,
            "{metric}: peak {peak} above the estimate {estimate}"
        );
        let out = Command::new(env!("CARGO_BIN_EXE_aerial"))
            .args(["compare", "--metric", metric])
            .arg(x)
            .arg(y)
            .env("AERIAL_MEMORY_BUDGET", (estimate / 2).to_string())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains("memory budget") && err.contains("comparing"),
            "{err}"
        );
    }
}
