//! Tests of the metrics, the worst window, loading and the heat map.

use super::heat_map::{build_lut, magma_lut, HEAT};
use super::*;
use image::{Rgb, RgbImage};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh empty folder under the system temp dir, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Self {
        static N: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "aerial-image-diff-{tag}-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
    fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

fn png(dir: &TempDir, name: &str, img: &RgbImage) -> PathBuf {
    let p = dir.path(name);
    img.save_with_format(&p, ImageFormat::Png).unwrap();
    p
}

/// Writes a `w` x `h` OpenEXR file of the colours `rgb(x, y)` (alpha 1)
/// through `image_io`, the one writer of OpenEXR.
fn write_rgb_exr(path: &Path, w: usize, h: usize, rgb: impl Fn(usize, usize) -> [f32; 3]) {
    let mut data = Vec::with_capacity(w * h * 4);
    for y in 0..h {
        for x in 0..w {
            let [r, g, b] = rgb(x, y);
            data.extend([r, g, b, 1.0]);
        }
    }
    let pixels = crate::image_io::Pixels {
        width: w as u32,
        height: h as u32,
        data,
    };
    crate::image_io::write_exr(path, &pixels).unwrap();
}

fn exr(dir: &TempDir, name: &str, w: usize, h: usize, rgb: [f32; 3]) -> PathBuf {
    let p = dir.path(name);
    write_rgb_exr(&p, w, h, |_, _| rgb);
    p
}

/// A 64x64 image with some structure, so FLIP has edges to look at.
fn gradient() -> RgbImage {
    RgbImage::from_fn(64, 64, |x, y| Rgb([(x * 4) as u8, (y * 4) as u8, 128]))
}

#[test]
fn identical_images_score_zero() {
    let dir = TempDir::new("identical");
    let a = png(&dir, "a.png", &gradient());
    let b = png(&dir, "b.png", &gradient());

    let flip = compare_files(&a, &b, Metric::Flip).unwrap();
    assert_eq!((flip.mean, flip.p99, flip.max), (0.0, 0.0, 0.0));
    assert_eq!(flip.error_map.len(), 64 * 64);

    let rmse = compare_files(&a, &b, Metric::Rmse).unwrap();
    assert_eq!((rmse.mean, rmse.p99, rmse.max), (0.0, 0.0, 0.0));

    let psnr = compare_files(&a, &b, Metric::Psnr).unwrap();
    assert_eq!(psnr.mean, f64::INFINITY);
    assert!(psnr.passes(&Thresholds {
        mean: Some(60.0),
        p99: Some(0.0),
        ..Thresholds::default()
    }));

    // JSON has no infinity: it goes out as null and comes back as +inf.
    let json = serde_json::to_string(&psnr).unwrap();
    assert!(json.contains("\"mean\":null"), "{json}");
    assert!(!json.contains("error_map"), "{json}");
    let back: ImageDiff = serde_json::from_str(&json).unwrap();
    assert_eq!(back.mean, f64::INFINITY);
    assert_eq!(back.metric, Metric::Psnr);
    assert!(back.error_map.is_empty());
}

#[test]
fn rmse_and_psnr_by_hand_png() {
    // Every pixel differs by 51/255 = 0.2 in red only:
    // MSE = 0.2^2 / 3 = 0.04 / 3, RMSE = 0.2 / sqrt(3) = 0.11547...
    // PSNR = 10 log10(1 / (0.04 / 3)) = 10 log10(75) = 18.7506... dB
    let dir = TempDir::new("rmse-png");
    let a = png(&dir, "a.png", &RgbImage::from_pixel(8, 4, Rgb([0, 0, 0])));
    let b = png(&dir, "b.png", &RgbImage::from_pixel(8, 4, Rgb([51, 0, 0])));

    let rmse = compare_files(&a, &b, Metric::Rmse).unwrap();
    let expected = 0.2 / 3f64.sqrt();
    assert!((rmse.mean - expected).abs() < 1e-6, "{}", rmse.mean);
    assert!((rmse.p99 - expected).abs() < 1e-6);
    assert!((rmse.max - expected).abs() < 1e-6);
    assert_eq!((rmse.width, rmse.height), (8, 4));

    let psnr = compare_files(&a, &b, Metric::Psnr).unwrap();
    assert!(
        (psnr.mean - 10.0 * 75f64.log10()).abs() < 1e-4,
        "{}",
        psnr.mean
    );
    assert!(psnr.passes(&Thresholds {
        mean: Some(18.0),
        p99: None,
        ..Thresholds::default()
    }));
    assert!(!psnr.passes(&Thresholds {
        mean: Some(19.0),
        p99: None,
        ..Thresholds::default()
    }));
}

#[test]
fn rmse_mixed_pixels_by_hand() {
    // 2x2: one pixel white vs black (per-pixel error 1), three equal.
    // MSE = 3 / 12 = 0.25 -> RMSE = 0.5. Per-pixel map = [1, 0, 0, 0];
    // p99: h = 3 * 0.99 = 2.97 -> 0 + 0.97 * (1 - 0) = 0.97.
    let dir = TempDir::new("rmse-mixed");
    let a = png(&dir, "a.png", &RgbImage::from_pixel(2, 2, Rgb([0, 0, 0])));
    let mut bi = RgbImage::from_pixel(2, 2, Rgb([0, 0, 0]));
    bi.put_pixel(1, 1, Rgb([255, 255, 255]));
    let b = png(&dir, "b.png", &bi);
    let c = compare_files(&a, &b, Metric::Rmse).unwrap();
    assert!((c.mean - 0.5).abs() < 1e-9);
    assert!((c.p99 - 0.97).abs() < 1e-9);
    assert_eq!(c.max, 1.0);
    assert_eq!(c.error_map, vec![0.0, 0.0, 0.0, 1.0]);
}

#[test]
fn rmse_and_psnr_by_hand_exr() {
    // Reference (2, 1, 0.5), test (2, 1, 0.8): blue differs by 0.3.
    // MSE = 0.09 / 3 = 0.03, RMSE = 0.1732..., peak = 2 (largest
    // reference value), PSNR = 10 log10(4 / 0.03) = 21.249... dB.
    let dir = TempDir::new("rmse-exr");
    let a = exr(&dir, "a.exr", 5, 3, [2.0, 1.0, 0.5]);
    let b = exr(&dir, "b.exr", 5, 3, [2.0, 1.0, 0.8]);
    let rmse = compare_files(&a, &b, Metric::Rmse).unwrap();
    assert!((rmse.mean - 0.03f64.sqrt()).abs() < 1e-6, "{}", rmse.mean);
    let psnr = compare_files(&a, &b, Metric::Psnr).unwrap();
    let expected = 10.0 * (4.0f64 / 0.03).log10();
    assert!((psnr.mean - expected).abs() < 1e-4, "{}", psnr.mean);
}

#[test]
fn few_wrong_pixels_hide_in_the_mean_but_not_in_p99() {
    // 100 of 4096 pixels (a 10x10 block) black instead of white. Only
    // 2.4% of the frame is wrong, and FLIP's mean comes out at about 0.04
    // (a bit above 100/4096 because the error spills over the block's
    // edges), yet inside the block FLIP is close to 1. Note that FLIP
    // blurs isolated single-pixel dots on white much more (p99 ~0.25 for
    // 100 scattered dots), which is why this uses a block.
    let dir = TempDir::new("flip-block");
    let white = RgbImage::from_pixel(64, 64, Rgb([255, 255, 255]));
    let mut broken = white.clone();
    for y in 20..30 {
        for x in 30..40 {
            broken.put_pixel(x, y, Rgb([0, 0, 0]));
        }
    }
    let a = png(&dir, "a.png", &white);
    let b = png(&dir, "b.png", &broken);
    let c = compare_files(&a, &b, Metric::Flip).unwrap();
    assert!(c.mean > 0.005 && c.mean < 0.05, "mean {}", c.mean);
    assert!(c.p99 > 0.5, "p99 {}", c.p99);
    // A mean-only gate at a typical 0.05 would let this through.
    assert!(c.passes(&Thresholds {
        mean: Some(0.05),
        p99: None,
        ..Thresholds::default()
    }));
    assert!(!c.passes(&Thresholds {
        mean: Some(0.05),
        p99: Some(0.1),
        ..Thresholds::default()
    }));
}

#[test]
fn in_memory_images_score_like_files() {
    let dir = TempDir::new("memory");
    let mut other = gradient();
    other.put_pixel(10, 10, Rgb([255, 0, 0]));
    let a = png(&dir, "a.png", &gradient());
    let b = png(&dir, "b.png", &other);
    let rgba = |img: &RgbImage| DynamicImage::ImageRgb8(img.clone()).to_rgba8().into_raw();
    let (ra, rb) = (rgba(&gradient()), rgba(&other));
    let srgb = |rgba| ImageRef::Srgb8 {
        width: 64,
        height: 64,
        rgba,
    };
    for metric in [Metric::Flip, Metric::Rmse, Metric::Psnr] {
        let files = compare_files(&a, &b, metric).unwrap();
        let memory = compare_images("a", srgb(&ra), "b", srgb(&rb), metric).unwrap();
        assert_eq!(files, memory, "{metric}");
    }

    // Linear: same numbers as rmse_and_psnr_by_hand_exr, alpha ignored.
    let lin = |rgb: [f32; 3], alpha: f32| [rgb[0], rgb[1], rgb[2], alpha].repeat(15);
    let (la, lb) = (lin([2.0, 1.0, 0.5], 1.0), lin([2.0, 1.0, 0.8], 0.0));
    let linear = |rgba| ImageRef::Linear {
        width: 5,
        height: 3,
        rgba,
    };
    let c = compare_images("a", linear(&la), "b", linear(&lb), Metric::Rmse).unwrap();
    assert!((c.mean - 0.03f64.sqrt()).abs() < 1e-6, "{}", c.mean);
}

#[test]
fn bad_in_memory_images_are_errors_naming_them() {
    let ok = [0.0f32; 16];
    let short = [0.0f32; 15];
    let image = |rgba| ImageRef::Linear {
        width: 2,
        height: 2,
        rgba,
    };
    let err =
        compare_images("ref", image(&ok), "short one", image(&short), Metric::Rmse).unwrap_err();
    assert!(matches!(err, CompareError::BadBuffer { .. }), "{err}");
    assert!(err.to_string().contains("short one"), "{err}");

    let mut nan = ok;
    nan[6] = f32::NAN; // pixel (1, 0), blue
    let err = compare_images("ref", image(&ok), "nan", image(&nan), Metric::Rmse).unwrap_err();
    assert!(err.to_string().contains("nan: 1 non-finite"), "{err}");
    assert!(err.to_string().contains("(1, 0)"), "{err}");

    let err = compare_images("ref", image(&ok), "test", image(&ok), Metric::Flip).unwrap_err();
    assert!(matches!(err, CompareError::FlipOnHdr { .. }), "{err}");
}

#[test]
fn size_mismatch_names_both_files() {
    let dir = TempDir::new("size");
    let a = png(&dir, "ref.png", &RgbImage::new(4, 4));
    let b = png(&dir, "test.png", &RgbImage::new(4, 5));
    let err = compare_files(&a, &b, Metric::Rmse).unwrap_err();
    assert!(matches!(err, CompareError::SizeMismatch { .. }), "{err}");
    let msg = err.to_string();
    assert!(msg.contains("ref.png") && msg.contains("4x4"), "{msg}");
    assert!(msg.contains("test.png") && msg.contains("4x5"), "{msg}");
}

#[test]
fn flip_on_exr_is_an_error() {
    let dir = TempDir::new("flip-exr");
    let a = exr(&dir, "a.exr", 4, 4, [0.5, 0.5, 0.5]);
    let b = exr(&dir, "b.exr", 4, 4, [0.5, 0.5, 0.5]);
    let err = compare_files(&a, &b, Metric::Flip).unwrap_err();
    assert!(matches!(err, CompareError::FlipOnHdr { .. }), "{err}");
    let msg = err.to_string();
    assert!(msg.contains("a.exr") && msg.contains("rmse"), "{msg}");
}

#[test]
fn png_against_exr_is_an_error() {
    let dir = TempDir::new("mixed");
    let a = png(&dir, "a.png", &RgbImage::new(4, 4));
    let b = exr(&dir, "b.exr", 4, 4, [0.0, 0.0, 0.0]);
    let err = compare_files(&a, &b, Metric::Rmse).unwrap_err();
    assert!(matches!(err, CompareError::FormatMismatch { .. }), "{err}");
}

#[test]
fn exr_with_nan_is_an_error() {
    let dir = TempDir::new("nan");
    let a = exr(&dir, "a.exr", 4, 4, [0.0, 0.0, 0.0]);
    let p = dir.path("b.exr");
    write_rgb_exr(&p, 4, 4, |x, y| {
        let r = if (x, y) == (2, 1) { f32::NAN } else { 0.0 };
        [r, 0.0, 0.0]
    });
    let err = compare_files(&a, &p, Metric::Rmse).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("b.exr") && msg.contains("(2, 1)"), "{msg}");
}

#[test]
fn black_exr_reference_has_no_psnr_peak() {
    let dir = TempDir::new("peak");
    let a = exr(&dir, "a.exr", 2, 2, [0.0, 0.0, 0.0]);
    let b = exr(&dir, "b.exr", 2, 2, [0.1, 0.0, 0.0]);
    let err = compare_files(&a, &b, Metric::Psnr).unwrap_err();
    assert!(matches!(err, CompareError::NoPsnrPeak { .. }), "{err}");
}

#[test]
fn unreadable_and_garbage_inputs_are_errors() {
    let dir = TempDir::new("garbage");
    let good = png(&dir, "good.png", &RgbImage::new(2, 2));
    let missing = dir.path("missing.png");
    let err = compare_files(&missing, &good, Metric::Rmse).unwrap_err();
    assert!(err.to_string().contains("missing.png"), "{err}");

    let text = dir.path("notes.png");
    fs::write(&text, "not an image").unwrap();
    let err = compare_files(&good, &text, Metric::Rmse).unwrap_err();
    assert!(matches!(err, CompareError::UnknownFormat { .. }), "{err}");

    // Valid signatures followed by junk must fail cleanly too.
    let trunc_png = dir.path("trunc.png");
    fs::write(&trunc_png, [&b"\x89PNG\r\n\x1a\n"[..], b"junk"].concat()).unwrap();
    let err = compare_files(&good, &trunc_png, Metric::Flip).unwrap_err();
    assert!(err.to_string().contains("trunc.png"), "{err}");
    let trunc_exr = dir.path("trunc.exr");
    fs::write(
        &trunc_exr,
        [&[0x76u8, 0x2F, 0x31, 0x01][..], b"\x02\0\0\0junk"].concat(),
    )
    .unwrap();
    let err = compare_files(&trunc_exr, &trunc_exr, Metric::Rmse).unwrap_err();
    assert!(err.to_string().contains("trunc.exr"), "{err}");
}

#[test]
fn diff_png_has_the_right_size() {
    let dir = TempDir::new("diff");
    let mut other = gradient();
    other.put_pixel(10, 10, Rgb([255, 0, 0]));
    let a = png(&dir, "a.png", &gradient());
    let b = png(&dir, "b.png", &other);
    for metric in [Metric::Flip, Metric::Rmse, Metric::Psnr] {
        let c = compare_files(&a, &b, metric).unwrap();
        let out = dir.path(&format!("diff-{metric}.png"));
        write_diff_png(&c, &out).unwrap();
        assert!(fs::metadata(&out).unwrap().len() > 0);
        let img = image::open(&out).unwrap().into_rgb8();
        assert_eq!(img.dimensions(), (64, 64));
        // The changed pixel is the hottest one of a relative heat map.
        if metric != Metric::Flip {
            assert_eq!(img.get_pixel(10, 10), &Rgb([255, 255, 255]));
            assert_eq!(img.get_pixel(0, 0), &Rgb([0, 0, 0]));
        }
    }
    // Only inputs and diffs remain: no temp files.
    assert_eq!(
        dir.entries(),
        [
            "a.png",
            "b.png",
            "diff-flip.png",
            "diff-psnr.png",
            "diff-rmse.png"
        ]
    );
}

#[test]
fn failed_diff_write_leaves_nothing_behind() {
    let dir = TempDir::new("diff-fail");
    let c = ImageDiff {
        metric: Metric::Flip,
        mean: 0.0,
        p99: 0.0,
        max: 0.0,
        worst_window: 0.0,
        hdr: false,
        width: 2,
        height: 1,
        error_map: vec![0.0, 1.0],
    };
    // The target is a directory, so the final rename fails after the
    // temp file has been written.
    let target = dir.path("taken");
    fs::create_dir(&target).unwrap();
    let err = write_diff_png(&c, &target).unwrap_err();
    assert!(err.to_string().contains("taken"), "{err}");
    assert_eq!(dir.entries(), ["taken"]);

    // A map that does not match the size is refused before any I/O.
    let bad = ImageDiff {
        error_map: vec![0.0],
        ..c
    };
    let out = dir.path("bad.png");
    assert!(matches!(
        write_diff_png(&bad, &out),
        Err(CompareError::BadErrorMap { .. })
    ));
    assert_eq!(dir.entries(), ["taken"]);
}

/// The worst window mean by brute force, for checking the running sums.
fn brute_worst_mean(map: &[f32], w: usize, h: usize) -> f64 {
    let (kx, ky) = (w.min(WINDOW as usize), h.min(WINDOW as usize));
    let mut worst = 0.0f64;
    for y in 0..=h - ky {
        for x in 0..=w - kx {
            let sum: f64 = (y..y + ky)
                .flat_map(|r| (x..x + kx).map(move |c| f64::from(map[r * w + c])))
                .sum();
            worst = worst.max(sum / (kx * ky) as f64);
        }
    }
    worst
}

#[test]
fn worst_window_matches_brute_force() {
    // Pseudo-random maps of sizes below, at and above the window.
    let mut state = 7u32;
    for (w, h) in [(1, 1), (5, 3), (12, 12), (13, 30), (40, 17)] {
        let map: Vec<f32> = (0..w * h)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 8) as f32 / (1u32 << 24) as f32
            })
            .collect();
        let fast = worst_window(w as u32, h as u32, |i| [f64::from(map[i])], |[s], n| s / n);
        let slow = brute_worst_mean(&map, w, h);
        assert!((fast - slow).abs() < 1e-9, "{w}x{h}: {fast} vs {slow}");
    }
}

#[test]
fn relative_window_by_hand_exr() {
    // Reference 40x30 at level 1 (every channel 1). A 6x6 block raised
    // to 1.5: per-pixel error 0.5, so the worst window holds 36 such
    // pixels out of 144: 0.5 * 36 / 144 = 0.125, over a level of 1.
    let dir = TempDir::new("window-exr");
    let reference = exr(&dir, "a.exr", 40, 30, [1.0, 1.0, 1.0]);
    let block = |size: usize, name: &str| {
        let p = dir.path(name);
        write_rgb_exr(&p, 40, 30, |x, y| {
            let v = if (10..10 + size).contains(&x) && (5..5 + size).contains(&y) {
                1.5f32
            } else {
                1.0
            };
            [v, v, v]
        });
        p
    };
    let small = compare_files(&reference, &block(6, "b6.exr"), Metric::Rmse).unwrap();
    assert!((small.worst_window - 0.125).abs() < 1e-9, "{small:?}");
    assert!(small.hdr);
    // A 12x12 block fills a window: 0.5.
    let big = compare_files(&reference, &block(12, "b12.exr"), Metric::Psnr).unwrap();
    assert!((big.worst_window - 0.5).abs() < 1e-9, "{big:?}");
    // Defaults for HDR: only the window, at 0.4.
    assert_eq!(big.default_thresholds(), HDR_DEFAULT_THRESHOLDS);
    assert!(small.passes(&HDR_DEFAULT_THRESHOLDS));
    assert!(!big.passes(&HDR_DEFAULT_THRESHOLDS));
}

#[test]
fn relative_window_is_floored_at_the_image_level() {
    // Left half of the reference black, right half at level 2: the
    // image's mean level is 1. One pixel on the black side turns 0.6:
    // relative to its black window that would be infinite, but the
    // floor makes it 0.6 / 144 / 1.
    let lin = |f: &dyn Fn(usize) -> f32| -> Vec<f32> {
        (0..32 * 16)
            .flat_map(|i| {
                let v = f(i);
                [v, v, v, 1.0]
            })
            .collect()
    };
    let reference = lin(&|i| if i % 32 < 16 { 0.0 } else { 2.0 });
    let test = lin(&|i| match i {
        i if i == 3 * 32 + 2 => 0.6,
        i if i % 32 < 16 => 0.0,
        _ => 2.0,
    });
    let image = |rgba| ImageRef::Linear {
        width: 32,
        height: 16,
        rgba,
    };
    let c = compare_images("a", image(&reference), "b", image(&test), Metric::Rmse).unwrap();
    assert!((c.worst_window - 0.6 / 144.0).abs() < 1e-9, "{c:?}");
}

#[test]
fn flip_window_catches_a_block_that_mean_and_p99_miss() {
    // A 12x12 block inverted in a 320x180 picture is 0.25 % of it: far
    // too few pixels to move the mean or p99, yet a window fits inside
    // it, where FLIP is close to 1 (the block is mid-grey turned into
    // its complement, with texture around so FLIP sees edges).
    let picture = RgbImage::from_fn(320, 180, |x, y| {
        Rgb([(x % 64 * 3) as u8, (y % 48 * 4) as u8, 100])
    });
    let mut broken = picture.clone();
    for y in 80..92 {
        for x in 150..162 {
            let p = broken.get_pixel_mut(x, y);
            p.0 = p.0.map(|c| 255 - c);
        }
    }
    let dir = TempDir::new("flip-window");
    let a = png(&dir, "a.png", &picture);
    let b = png(&dir, "b.png", &broken);
    let c = compare_files(&a, &b, Metric::Flip).unwrap();
    assert!(c.mean <= 0.03 && c.p99 <= 0.1, "{c:?}");
    assert!(c.worst_window > 0.5, "{c:?}");
    assert!((c.worst_window - brute_worst_mean(&c.error_map, 320, 180)).abs() < 1e-9);
    assert!(!c.hdr);
    assert_eq!(c.default_thresholds(), FLIP_DEFAULT_THRESHOLDS);
    assert!(!c.passes(&FLIP_DEFAULT_THRESHOLDS));
    // PNGs compared with rmse have no default limits.
    let rmse = compare_files(&a, &b, Metric::Rmse).unwrap();
    assert_eq!(rmse.default_thresholds(), Thresholds::default());
}

#[test]
fn flip_diff_uses_flips_magma_colours() {
    // Endpoints of the magma table published with FLIP, rounded to
    // 8 bits: (0.001462, 0.000466, 0.013866) and (0.987053, 0.991438,
    // 0.749504).
    let lut = magma_lut();
    assert_eq!(lut.len(), 256);
    assert_eq!(lut[0], [0, 0, 4]);
    assert_eq!(lut[255], [252, 253, 191]);

    // The diff PNG of a 0..1 ramp is coloured exactly as FLIP's own
    // colour mapping colours the same values.
    let ramp: Vec<f32> = (0..300).map(|i| i as f32 / 299.0).collect();
    let cmp = ImageDiff {
        metric: Metric::Flip,
        mean: 0.5,
        p99: 0.99,
        max: 1.0,
        worst_window: 0.5,
        hdr: false,
        width: 300,
        height: 1,
        error_map: ramp.clone(),
    };
    let dir = TempDir::new("magma");
    let out = dir.path("ramp.png");
    write_diff_png(&cmp, &out).unwrap();
    let ours = image::open(&out).unwrap().into_rgb8().into_raw();
    let theirs = nv_flip::FlipImageFloat::with_data(300, 1, &ramp)
        .apply_color_lut(&nv_flip::magma_lut())
        .to_vec();
    assert_eq!(ours, theirs);
}

#[test]
fn heat_lut_interpolates_its_control_points() {
    let lut = build_lut(&HEAT);
    assert_eq!(lut.len(), 256);
    assert_eq!(lut[0], [0, 0, 0]);
    assert_eq!(lut[85], [255, 0, 0]);
    // 42/85 of the way from black to red: 255 * 42 / 85 = 126.
    assert_eq!(lut[42], [126, 0, 0]);
    assert_eq!(lut[170], [255, 255, 0]);
    assert_eq!(lut[255], [255, 255, 255]);
}

#[test]
fn thresholds_and_metric_names() {
    let c = ImageDiff {
        metric: Metric::Rmse,
        mean: 0.1,
        p99: 0.3,
        max: 0.5,
        worst_window: 0.5,
        hdr: false,
        width: 1,
        height: 1,
        error_map: vec![0.5],
    };
    assert!(c.passes(&Thresholds::default()));
    assert!(c.passes(&Thresholds {
        mean: Some(0.1),
        p99: Some(0.3),
        ..Thresholds::default()
    }));
    assert!(!c.passes(&Thresholds {
        mean: Some(0.09),
        p99: None,
        ..Thresholds::default()
    }));
    assert!(!c.passes(&Thresholds {
        mean: None,
        p99: Some(f64::NAN),
        ..Thresholds::default()
    }));
    for m in [Metric::Flip, Metric::Psnr, Metric::Rmse] {
        assert_eq!(m.to_string().parse::<Metric>().unwrap(), m);
        let json = serde_json::to_string(&m).unwrap();
        assert_eq!(json, format!("\"{m}\""));
    }
    assert!("ssim".parse::<Metric>().is_err());
}
