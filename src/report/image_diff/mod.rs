//! Image comparison for screenshot regression tests.
//!
//! [`compare_files`] loads a *reference* image (first argument) and a *test*
//! image (second argument) and measures how different they are with one
//! [`Metric`]. [`compare_images`] does the same for images already in memory
//! (e.g. straight from the renderer), with the same checks and results:
//!
//! - [`Metric::Flip`]: NVIDIA's FLIP perceptual difference (LDR variant, via
//!   the `nv-flip` binding), per pixel in `[0, 1]`. Viewing conditions are
//!   FLIP's default of 67 pixels per degree (a 0.7 m wide 4K monitor seen
//!   from 0.7 m). FLIP is defined on sRGB-encoded LDR images, so it is only
//!   offered for PNG inputs; OpenEXR inputs are rejected with an error that
//!   points to `rmse`/`psnr`.
//! - [`Metric::Rmse`]: root mean square error over all pixels and the R, G, B
//!   channels. PNG values are normalised to `[0, 1]` (still sRGB-encoded, i.e.
//!   compared as stored); OpenEXR values are the linear values as stored.
//! - [`Metric::Psnr`]: `10 * log10(peak^2 / MSE)` in dB over the whole image,
//!   with `peak = 1` for PNG and, for OpenEXR, `peak` = the largest R, G or B
//!   value of the *reference* image (HDR images have no fixed white level, so
//!   the reference's own range is the natural scale). Identical images give
//!   `+inf`.
//!
//! # What the fields of [`ImageDiff`] mean
//!
//! `error_map` holds one value per pixel, row-major from the top-left:
//! the FLIP value for FLIP, and for RMSE and PSNR the per-pixel RMS error over
//! R, G, B (`sqrt(((dr)^2 + (dg)^2 + (db)^2) / 3)`). `p99` and `max` are always
//! statistics of `error_map` (99th percentile as defined in
//! [`super::stats`]). `mean` is the headline number: the mean FLIP value, the
//! whole-image RMSE, or the whole-image PSNR in dB. So for PSNR `mean` is in
//! dB (higher is better) while `p99`/`max` are per-pixel errors in value units
//! (lower is better).
//!
//! A high percentile is gated as well as the mean because a localised
//! breakage (a missing object, a few exploded pixels) barely moves the mean
//! of a large frame but dominates the top percentile.
//!
//! `worst_window` catches what is too small even for the 99th percentile
//! (under 1 % of the pixels): it pools the error over every
//! [`WINDOW`]x[`WINDOW`]-pixel square inside the image and reports the
//! worst square. For FLIP that is the mean FLIP value over the square. For
//! RMSE and PSNR it is the mean of `error_map` over the square divided by
//! the reference's mean level (per pixel the RMS of R, G, B) over the same
//! square or over the whole image, whichever is larger, so that one limit
//! suits HDR images of any brightness; the floor keeps faint changes in
//! nearly black areas from counting as huge relative errors.
//!
//! # Inputs
//!
//! The format is detected from the file signature, not the extension. PNGs
//! are treated as sRGB; 16-bit PNGs keep full precision for RMSE/PSNR and are
//! rounded to 8 bits for FLIP. Alpha is ignored in both formats: FLIP has no
//! notion of it and the renderer's screenshots are opaque. An OpenEXR file
//! must have `R`, `G` and `B` channels in its first valid layer (any sample
//! type); NaN or infinite samples are reported as an error rather than
//! producing a NaN score that would compare oddly against thresholds.
//! Comparing a PNG with an OpenEXR is an error, since one is display-encoded
//! and the other linear.
//!
//! # Serialisation
//!
//! [`ImageDiff`] serialises to JSON for reports. An infinite `mean` (PSNR of
//! identical images) is written as `null` and read back as `+inf`, because JSON
//! cannot represent infinity. `error_map` is *not* serialised (it would be
//! millions of numbers); write it with [`write_diff_png`] instead, and note
//! that a deserialised `ImageDiff` has an empty `error_map`.

use std::fmt;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::str::FromStr;

use image::codecs::png::PngEncoder;
use image::{DynamicImage, ExtendedColorType, ImageEncoder, ImageFormat};
use serde::{Deserialize, Serialize};
use thiserror::Error;

mod heat_map;
mod load;
mod window;

pub use heat_map::write_diff_png;
use load::{from_memory, load};
use window::{relative_worst_window, worst_window};

use super::stats::percentile;
use crate::image_io::FileFormat;

/// Largest image, in pixels, that we agree to load from an OpenEXR header.
/// A corrupt or hostile header can claim any size, and allocating for it would
/// abort the process (not a catchable panic); 2^28 pixels is 16k x 16k, far
/// beyond any screenshot this renderer makes.
const MAX_PIXELS: usize = 1 << 28;

/// How two images are compared; see the module docs for definitions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Metric {
    /// NVIDIA FLIP (LDR), per-pixel perceptual error in `[0, 1]`.
    Flip,
    /// Peak signal-to-noise ratio in dB (higher is better).
    Psnr,
    /// Root mean square error (lower is better).
    Rmse,
}

impl fmt::Display for Metric {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Metric::Flip => "flip",
            Metric::Psnr => "psnr",
            Metric::Rmse => "rmse",
        })
    }
}

impl FromStr for Metric {
    type Err = CompareError;

    /// Parses the lowercase names used on the command line and in JSON
    /// (case-insensitive, so `FLIP` from a config file works too).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "flip" => Ok(Metric::Flip),
            "psnr" => Ok(Metric::Psnr),
            "rmse" => Ok(Metric::Rmse),
            _ => Err(CompareError::UnknownMetric { name: s.to_owned() }),
        }
    }
}

/// Result of comparing a reference image with a test image.
///
/// See the module docs for what `mean`, `p99`, `max` and `error_map` hold for
/// each metric.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageDiff {
    /// The metric that produced this result.
    pub metric: Metric,
    /// Mean FLIP, whole-image RMSE, or whole-image PSNR in dB (`+inf` for
    /// identical images, serialised as `null`).
    #[serde(with = "infinite_as_null")]
    pub mean: f64,
    /// 99th percentile of `error_map`.
    pub p99: f64,
    /// Largest value of `error_map`.
    pub max: f64,
    /// Error over the worst [`WINDOW`]x[`WINDOW`]-pixel square: the mean
    /// FLIP there, or for RMSE and PSNR the RMS error there relative to the
    /// reference's RMS level (see the module docs). Catches small, local
    /// defects that the mean and p99 of a large frame hide.
    #[serde(default)]
    pub worst_window: f64,
    /// Whether the images were linear HDR (OpenEXR or [`ImageRef::Linear`]),
    /// which decides the default limits ([`ImageDiff::default_thresholds`]).
    #[serde(default)]
    pub hdr: bool,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Per-pixel error, row-major from the top-left, `width * height` values.
    /// Not serialised.
    #[serde(skip)]
    pub error_map: Vec<f32>,
}

/// Pass/fail limits for an [`ImageDiff`]; a limit left as `None` is not
/// checked.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Thresholds {
    /// For FLIP and RMSE: the largest acceptable `mean`. For PSNR: the
    /// *smallest* acceptable PSNR in dB.
    pub mean: Option<f64>,
    /// The largest acceptable `p99` of the per-pixel error (for every metric,
    /// including PSNR, whose `p99` is a per-pixel RMS error).
    pub p99: Option<f64>,
    /// The largest acceptable `worst_window` (for every metric).
    #[serde(default)]
    pub worst_window: Option<f64>,
}

/// Side, in pixels, of the square over which `worst_window` pools the
/// error. At FLIP's 67 pixels per degree 12 pixels are 0.18 degrees: a
/// small object, but large enough that the error of edges moved by a
/// fraction of a pixel (a thin line of moderate values) averages out over
/// it. Images narrower or lower than this use a window as wide or as high
/// as the image.
pub const WINDOW: u32 = 12;

/// Default FLIP limits of `aerial compare` and the screenshot regression
/// suite: mean <= 0.03, p99 <= 0.1 and worst 12x12 window <= 0.3, meaning
/// "looks the same to a viewer, allowing for a different GPU or driver".
///
/// Chosen from measurements on the example scenes (lavapipe, at 160x90,
/// 320x180 and 640x360; mean and p99 barely depend on the size; "window" is
/// `worst_window`):
///
/// | change to the image                      | FLIP mean   | FLIP p99    | window      |
/// |------------------------------------------|-------------|-------------|-------------|
/// | +-1 LSB noise on half the channels       | 0.011-0.012 | 0.025-0.028 | 0.016-0.021 |
/// | up to +-3 LSB noise on every channel     | 0.024-0.026 | 0.053-0.061 | 0.037-0.046 |
/// | exposure +1 %                            | 0.011-0.019 | 0.033-0.046 | 0.029-0.048 |
/// | camera turned by 1/20 pixel (edges shift)| 0.002-0.013 | 0.021-0.20  | 0.037-0.208 |
/// | exposure +5 %                            | 0.033-0.058 | 0.071-0.107 | 0.067-0.112 |
/// | a sphere, torus or flag removed          | 0.004-0.17  | 0.000-0.99  | 0.41-0.98   |
/// | 6x6 pixel block inverted                 | 0.000-0.006 | 0.000-0.10  | 0.50-0.54   |
/// | 12x12 pixel block inverted               | 0.001-0.012 | 0.000-0.45  | 0.80-0.98   |
/// | small sphere added/removed, 7 px across  | 0.001-0.005 | 0.001-0.11  | 0.36-0.40   |
///
/// The first four are what another driver's rounding, rasterisation rules
/// or texture filtering plausibly produce, and pass (except one p99 of 0.20:
/// `shading_models` at 320x180 turned vertically, where the toon shading's
/// bands move); the rest are real regressions, and fail. A mean limit of 0.01 would already reject +-1 LSB
/// rounding noise. Mean and p99 alone let small defects through: in a
/// 640x360 frame the inverted 12x12 block has mean 0.001 and p99 0.000,
/// because it covers only 0.06 % of the pixels. The window limit catches
/// it; the largest window value of a change that must pass came from the
/// textured flag, whose texels snap as the camera turns. Defects smaller
/// than about 6 pixels across (a sphere 5 px across: window 0.23 at 160x90)
/// can still pass; look at `max` and the diff image too.
pub const FLIP_DEFAULT_THRESHOLDS: Thresholds = Thresholds {
    mean: Some(0.03),
    p99: Some(0.1),
    worst_window: Some(0.3),
};

/// Default limits for comparing linear HDR images (OpenEXR) with RMSE or
/// PSNR: only `worst_window` <= 0.4, the mean error over the worst 12x12
/// window relative to the reference's mean level there (or over the whole
/// image, if larger).
///
/// The whole-image RMSE and PSNR scale with the scene's brightness, so they
/// have no default; the window statistic is relative, so one limit fits any
/// exposure. Measured on HDR renders of the example scenes at 160x90 and
/// 320x180: noise of up to +-1 % on every channel gives at most 0.006,
/// exposure +1 % 0.010, the camera turned by 1/20 pixel 0.021-0.29 (the
/// most from the flag's texture); a removed sphere, torus or flag 0.44 or
/// more, a small sphere 7 px across added or removed 0.47-0.68, a 12x12
/// block with its colour channels rotated 0.41-0.60.
pub const HDR_DEFAULT_THRESHOLDS: Thresholds = Thresholds {
    mean: None,
    p99: None,
    worst_window: Some(0.4),
};

impl ImageDiff {
    /// Whether this result is within `t`.
    ///
    /// FLIP and RMSE pass when `mean <= t.mean`; PSNR passes when
    /// `mean >= t.mean` (PSNR grows as images get closer, and identical images
    /// with `+inf` dB pass any PSNR limit). For every metric `p99 <= t.p99`
    /// and `worst_window <= t.worst_window` are required as well. Any NaN
    /// involved makes the check fail, so a broken threshold or result can
    /// never pass by accident.
    pub fn passes(&self, t: &Thresholds) -> bool {
        let mean_ok = match t.mean {
            None => true,
            Some(limit) => match self.metric {
                Metric::Psnr => self.mean >= limit,
                Metric::Flip | Metric::Rmse => self.mean <= limit,
            },
        };
        let p99_ok = t.p99.is_none_or(|limit| self.p99 <= limit);
        let window_ok = t
            .worst_window
            .is_none_or(|limit| self.worst_window <= limit);
        mean_ok && p99_ok && window_ok
    }

    /// The limits `aerial compare` applies when none are given:
    /// [`FLIP_DEFAULT_THRESHOLDS`] for FLIP, [`HDR_DEFAULT_THRESHOLDS`] for
    /// RMSE and PSNR of HDR images, and none for RMSE and PSNR of PNGs
    /// (whose errors are in display-encoded values, where a relative error
    /// of dark pixels says little).
    pub fn default_thresholds(&self) -> Thresholds {
        match (self.metric, self.hdr) {
            (Metric::Flip, _) => FLIP_DEFAULT_THRESHOLDS,
            (Metric::Rmse | Metric::Psnr, true) => HDR_DEFAULT_THRESHOLDS,
            (Metric::Rmse | Metric::Psnr, false) => Thresholds::default(),
        }
    }
}

/// Everything that can go wrong while comparing images or writing a diff.
/// Every variant names the file involved.
#[derive(Debug, Error)]
pub enum CompareError {
    /// Comparing these images needs more memory than the budget allows
    /// (checked from the files' headers, before decoding).
    #[error(transparent)]
    Budget(#[from] crate::budget::BudgetError),
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Underlying I/O error.
        source: io::Error,
    },
    /// The file is neither PNG nor OpenEXR.
    #[error("{}: not a PNG or OpenEXR file (unrecognised file signature)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The PNG could not be decoded.
    #[error("{}: cannot decode PNG: {source}", path.display())]
    Png {
        /// The file.
        path: PathBuf,
        /// Decoder error.
        source: image::ImageError,
    },
    /// The OpenEXR file could not be decoded.
    #[error("{}: cannot read OpenEXR (need R, G, B channels in a flat layer): {source}", path.display())]
    Exr {
        /// The file.
        path: PathBuf,
        /// Decoder error.
        source: crate::image_io::ExrError,
    },
    /// A decoder panicked on malformed input; reported instead of crashing.
    #[error("{}: the {format} decoder failed on malformed data", path.display())]
    DecoderPanic {
        /// The file.
        path: PathBuf,
        /// "PNG" or "OpenEXR".
        format: &'static str,
    },
    /// The image is empty or larger than this tool accepts.
    #[error("{}: unsupported image size {width}x{height} (must be non-empty and at most {max} pixels)", path.display())]
    BadSize {
        /// The file.
        path: PathBuf,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Largest accepted pixel count.
        max: usize,
    },
    /// The OpenEXR file has NaN or infinite samples.
    #[error("{}: {count} non-finite (NaN or infinite) R/G/B samples, first at pixel ({x}, {y})", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// Number of non-finite samples.
        count: usize,
        /// Column of the first one.
        x: usize,
        /// Row of the first one.
        y: usize,
    },
    /// The two images differ in size.
    #[error("image sizes differ: {} is {}x{} but {} is {}x{}", reference.display(), reference_size.0, reference_size.1, test.display(), test_size.0, test_size.1)]
    SizeMismatch {
        /// The reference file.
        reference: PathBuf,
        /// Its width and height.
        reference_size: (u32, u32),
        /// The test file.
        test: PathBuf,
        /// Its width and height.
        test_size: (u32, u32),
    },
    /// One image is PNG and the other OpenEXR.
    #[error("cannot compare {} ({reference_kind}) with {} ({test_kind}): both must be PNG or both OpenEXR", reference.display(), test.display())]
    FormatMismatch {
        /// The reference file.
        reference: PathBuf,
        /// Its format description.
        reference_kind: &'static str,
        /// The test file.
        test: PathBuf,
        /// Its format description.
        test_kind: &'static str,
    },
    /// FLIP was requested for an OpenEXR image.
    #[error("{}: FLIP here compares sRGB LDR images (PNG) only; this is OpenEXR (linear HDR), use the rmse or psnr metric to compare linear HDR images", path.display())]
    FlipOnHdr {
        /// The OpenEXR file.
        path: PathBuf,
    },
    /// PSNR needs a positive peak, taken from the OpenEXR reference.
    #[error("{}: PSNR is undefined because the reference has no positive R/G/B value to use as peak; use the rmse metric", path.display())]
    NoPsnrPeak {
        /// The reference file.
        path: PathBuf,
    },
    /// `write_diff_png` was given an `ImageDiff` whose map does not match its
    /// size (e.g. one read back from JSON, which has no map).
    #[error("cannot write diff {}: error map has {len} values but the image is {width}x{height}", path.display())]
    BadErrorMap {
        /// The diff file that was to be written.
        path: PathBuf,
        /// Values in the map.
        len: usize,
        /// Claimed width.
        width: u32,
        /// Claimed height.
        height: u32,
    },
    /// The diff PNG could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The diff file.
        path: PathBuf,
        /// Underlying I/O error.
        source: io::Error,
    },
    /// The diff PNG could not be encoded.
    #[error("cannot encode {} as PNG: {source}", path.display())]
    Encode {
        /// The diff file.
        path: PathBuf,
        /// Encoder error.
        source: image::ImageError,
    },
    /// An in-memory image whose buffer does not match its size.
    #[error("{}: {len} values do not make a {width}x{height} RGBA image ({} expected)", path.display(), *width as usize * *height as usize * 4)]
    BadBuffer {
        /// The name given for the image.
        path: PathBuf,
        /// Values in the buffer.
        len: usize,
        /// Claimed width.
        width: u32,
        /// Claimed height.
        height: u32,
    },
    /// An unknown metric name was parsed.
    #[error("unknown metric {name:?}: expected flip, psnr or rmse")]
    UnknownMetric {
        /// The name given.
        name: String,
    },
}

/// Samples as loaded (display-encoded or linear), keeping what each metric
/// needs; not `render::Pixels`, which is one renderer image.
enum Samples {
    /// A PNG, kept decoded at its own bit depth so RMSE/PSNR of 16-bit PNGs
    /// are not quantised, while FLIP gets an 8-bit view.
    Srgb(DynamicImage),
    /// An OpenEXR image as linear RGB, interleaved.
    Linear(Vec<f32>),
}

struct Loaded {
    width: u32,
    height: u32,
    pixels: Samples,
}

impl Loaded {
    fn kind(&self) -> &'static str {
        match self.pixels {
            Samples::Srgb(_) => "PNG, sRGB",
            Samples::Linear(_) => "OpenEXR, linear",
        }
    }

    /// Interleaved RGB floats: `[0, 1]` for PNG, as stored for OpenEXR.
    fn rgb_f32(&self) -> Vec<f32> {
        match &self.pixels {
            Samples::Srgb(img) => img.to_rgb32f().into_raw(),
            Samples::Linear(v) => v.clone(),
        }
    }
}

/// Peak memory of a comparison per pixel of each image: its decoded
/// samples, their float copies, the error map and FLIP's working images.
/// Measured peaks (whole process, release build, 1024² and 2048² images):
/// 44–47 bytes per pixel per image for PNG with FLIP, 31–34 for OpenEXR
/// with RMSE; this bound leaves a third more (tested in
/// `tests/suite/cli_compare.rs`).
pub const BYTES_PER_PIXEL: u64 = 64;

/// Compares the reference image `a` with the test image `b` using `metric`.
///
/// See the module docs for supported inputs and the meaning of the result.
pub fn compare_files(a: &Path, b: &Path, metric: Metric) -> Result<ImageDiff, CompareError> {
    // Sized from the headers and the files' lengths before anything is
    // decoded: the decoders and FLIP allocate whatever the images need.
    let mut need = 0u64;
    for path in [a, b] {
        let (w, h) = load::header_size(path)?;
        let file = fs::metadata(path).map_or(0, |m| m.len());
        need = need.saturating_add((w as u64 * h as u64).saturating_mul(BYTES_PER_PIXEL) + file);
    }
    crate::budget::MemoryBudget::from_env()?.check(
        format!("comparing {} with {}", a.display(), b.display()),
        need,
    )?;
    let reference = load(a)?;
    let test = load(b)?;
    compare_loaded(a, &reference, b, &test, metric)
}

/// An image in memory for [`compare_images`]: interleaved RGBA, row-major
/// from the top-left, `width * height * 4` values. Alpha is ignored, as it
/// is for files.
#[derive(Debug, Clone, Copy)]
pub enum ImageRef<'a> {
    /// 8-bit sRGB-encoded values, compared like a PNG.
    Srgb8 {
        width: u32,
        height: u32,
        rgba: &'a [u8],
    },
    /// Linear values, compared like an OpenEXR file.
    Linear {
        width: u32,
        height: u32,
        rgba: &'a [f32],
    },
}

/// Compares the in-memory `reference` with `test` using `metric`, exactly
/// as [`compare_files`] would compare them saved as PNG (`Srgb8`) or OpenEXR
/// (`Linear`). The names stand in for file paths in error messages.
pub fn compare_images(
    reference_name: &str,
    reference: ImageRef<'_>,
    test_name: &str,
    test: ImageRef<'_>,
    metric: Metric,
) -> Result<ImageDiff, CompareError> {
    let (a, b) = (Path::new(reference_name), Path::new(test_name));
    compare_loaded(
        a,
        &from_memory(a, reference)?,
        b,
        &from_memory(b, test)?,
        metric,
    )
}

/// The checks and metrics shared by [`compare_files`] and
/// [`compare_images`]; `a` and `b` name the images in errors.
fn compare_loaded(
    a: &Path,
    reference: &Loaded,
    b: &Path,
    test: &Loaded,
    metric: Metric,
) -> Result<ImageDiff, CompareError> {
    if matches!(metric, Metric::Flip) {
        // Name whichever input is HDR so the user knows which file to change.
        for (path, img) in [(a, reference), (b, test)] {
            if matches!(img.pixels, Samples::Linear(_)) {
                return Err(CompareError::FlipOnHdr {
                    path: path.to_owned(),
                });
            }
        }
    }
    if std::mem::discriminant(&reference.pixels) != std::mem::discriminant(&test.pixels) {
        return Err(CompareError::FormatMismatch {
            reference: a.to_owned(),
            reference_kind: reference.kind(),
            test: b.to_owned(),
            test_kind: test.kind(),
        });
    }
    if (reference.width, reference.height) != (test.width, test.height) {
        return Err(CompareError::SizeMismatch {
            reference: a.to_owned(),
            reference_size: (reference.width, reference.height),
            test: b.to_owned(),
            test_size: (test.width, test.height),
        });
    }

    let (width, height) = (reference.width, reference.height);
    match metric {
        Metric::Flip => {
            let (Samples::Srgb(ra), Samples::Srgb(tb)) = (&reference.pixels, &test.pixels) else {
                // Unreachable after the checks above; answer with the same
                // error rather than panicking.
                return Err(CompareError::FlipOnHdr { path: a.to_owned() });
            };
            let ref8 = nv_flip::FlipImageRgb8::with_data(width, height, ra.to_rgb8().as_raw());
            let test8 = nv_flip::FlipImageRgb8::with_data(width, height, tb.to_rgb8().as_raw());
            let map = nv_flip::flip(ref8, test8, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec();
            let mean = map.iter().map(|&v| f64::from(v)).sum::<f64>() / map.len() as f64;
            let (p99, max) = tail_stats(&map);
            let worst_window =
                worst_window(width, height, |i| [f64::from(map[i])], |[sum], n| sum / n);
            Ok(ImageDiff {
                metric,
                mean,
                p99,
                max,
                worst_window,
                hdr: false,
                width,
                height,
                error_map: map,
            })
        }
        Metric::Rmse | Metric::Psnr => {
            let ra = reference.rgb_f32();
            let tb = test.rgb_f32();
            let mut map = Vec::with_capacity(ra.len() / 3);
            let mut sum_sq = 0.0f64;
            for (pa, pb) in ra.chunks_exact(3).zip(tb.chunks_exact(3)) {
                let sq: f64 = pa
                    .iter()
                    .zip(pb)
                    .map(|(&x, &y)| {
                        let d = f64::from(x) - f64::from(y);
                        d * d
                    })
                    .sum();
                sum_sq += sq;
                map.push((sq / 3.0).sqrt() as f32);
            }
            let mse = sum_sq / ra.len() as f64;
            let mean = if metric == Metric::Rmse {
                mse.sqrt()
            } else {
                let peak = match reference.pixels {
                    Samples::Srgb(_) => 1.0,
                    Samples::Linear(_) => ra.iter().fold(0.0f64, |m, &v| m.max(f64::from(v))),
                };
                if peak <= 0.0 {
                    return Err(CompareError::NoPsnrPeak { path: a.to_owned() });
                }
                if mse == 0.0 {
                    f64::INFINITY
                } else {
                    10.0 * (peak * peak / mse).log10()
                }
            };
            let (p99, max) = tail_stats(&map);
            let worst_window = relative_worst_window(&ra, &map, width, height);
            Ok(ImageDiff {
                metric,
                mean,
                p99,
                max,
                worst_window,
                hdr: matches!(reference.pixels, Samples::Linear(_)),
                width,
                height,
                error_map: map,
            })
        }
    }
}

/// 99th percentile and maximum of a non-empty error map.
fn tail_stats(map: &[f32]) -> (f64, f64) {
    let mut sorted: Vec<f64> = map.iter().map(|&v| f64::from(v)).collect();
    sorted.sort_unstable_by(f64::total_cmp);
    let max = sorted.last().copied().unwrap_or(0.0);
    (percentile(&sorted, 99.0), max)
}

/// Serde adapter writing `+inf` as `null` (JSON has no infinity) and reading
/// `null` back as `+inf`.
mod infinite_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if *v == f64::INFINITY {
            s.serialize_none()
        } else {
            s.serialize_f64(*v)
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }
}

#[cfg(test)]
mod tests;
