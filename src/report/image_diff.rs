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
use std::io::{self, BufWriter, Cursor, Write};
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::str::FromStr;

use image::codecs::png::PngEncoder;
use image::{DynamicImage, ExtendedColorType, ImageEncoder, ImageFormat};
use serde::{Deserialize, Serialize};
use thiserror::Error;

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
        source: exr::error::Error,
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

/// Pixels as loaded, keeping what each metric needs.
enum Pixels {
    /// A PNG, kept decoded at its own bit depth so RMSE/PSNR of 16-bit PNGs
    /// are not quantised, while FLIP gets an 8-bit view.
    Srgb(DynamicImage),
    /// An OpenEXR image as linear RGB, interleaved.
    Linear(Vec<f32>),
}

struct Loaded {
    width: u32,
    height: u32,
    pixels: Pixels,
}

impl Loaded {
    fn kind(&self) -> &'static str {
        match self.pixels {
            Pixels::Srgb(_) => "PNG, sRGB",
            Pixels::Linear(_) => "OpenEXR, linear",
        }
    }

    /// Interleaved RGB floats: `[0, 1]` for PNG, as stored for OpenEXR.
    fn rgb_f32(&self) -> Vec<f32> {
        match &self.pixels {
            Pixels::Srgb(img) => img.to_rgb32f().into_raw(),
            Pixels::Linear(v) => v.clone(),
        }
    }
}

/// Compares the reference image `a` with the test image `b` using `metric`.
///
/// See the module docs for supported inputs and the meaning of the result.
pub fn compare_files(a: &Path, b: &Path, metric: Metric) -> Result<ImageDiff, CompareError> {
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
            if matches!(img.pixels, Pixels::Linear(_)) {
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
            let (Pixels::Srgb(ra), Pixels::Srgb(tb)) = (&reference.pixels, &test.pixels) else {
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
                    Pixels::Srgb(_) => 1.0,
                    Pixels::Linear(_) => ra.iter().fold(0.0f64, |m, &v| m.max(f64::from(v))),
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
                hdr: matches!(reference.pixels, Pixels::Linear(_)),
                width,
                height,
                error_map: map,
            })
        }
    }
}

/// The largest `score` over all [`WINDOW`]x[`WINDOW`] squares inside a
/// `width` x `height` image (clipped to the image size), where `score` gets
/// the sums over the square of the `N` per-pixel values that `value` gives
/// for a row-major pixel index, and the number of pixels in the square.
///
/// Keeps running column sums, so it needs memory for one row rather than a
/// summed-area table of the whole image.
fn worst_window<const N: usize>(
    width: u32,
    height: u32,
    value: impl Fn(usize) -> [f64; N],
    score: impl Fn([f64; N], f64) -> f64,
) -> f64 {
    let (w, h) = (width as usize, height as usize);
    let (kx, ky) = (w.min(WINDOW as usize), h.min(WINDOW as usize));
    let count = (kx * ky) as f64;
    let add = |a: &mut [f64; N], b: [f64; N], sign: f64| {
        for (x, y) in a.iter_mut().zip(b) {
            *x += sign * y;
        }
    };
    // columns[x]: sums over the last ky rows of column x.
    let mut columns = vec![[0.0; N]; w];
    let mut worst = 0.0f64;
    for y in 0..h {
        for (x, column) in columns.iter_mut().enumerate() {
            add(column, value(y * w + x), 1.0);
            if y >= ky {
                add(column, value((y - ky) * w + x), -1.0);
            }
        }
        if y + 1 < ky {
            continue;
        }
        let mut sums = [0.0; N];
        for (x, &column) in columns.iter().enumerate() {
            add(&mut sums, column, 1.0);
            if x >= kx {
                add(&mut sums, columns[x - kx], -1.0);
            }
            if x + 1 >= kx {
                // Running sums of non-negative values can come out a hair
                // below zero after subtractions; clamp so a score never
                // turns NaN from a negative square root.
                let s = sums.map(|v| v.max(0.0));
                worst = worst.max(score(s, count));
            }
        }
    }
    worst
}

/// `worst_window` for RMSE and PSNR: the mean per-pixel error over the
/// window divided by the reference's mean level there or over the whole
/// image, whichever is larger (a pixel's level is the RMS of its R, G, B).
/// The floor keeps a faint change in a nearly black window, such as one edge
/// pixel against a black background, from counting as a huge relative
/// error; an all-black reference uses a level of 1. `reference` is
/// interleaved RGB, `map` the per-pixel RMS error.
fn relative_worst_window(reference: &[f32], map: &[f32], width: u32, height: u32) -> f64 {
    let level = |i: usize| {
        (reference[3 * i..3 * i + 3]
            .iter()
            .map(|&v| f64::from(v) * f64::from(v))
            .sum::<f64>()
            / 3.0)
            .sqrt()
    };
    let overall = (0..map.len()).map(level).sum::<f64>() / map.len() as f64;
    let floor = if overall > 0.0 { overall } else { 1.0 };
    worst_window(
        width,
        height,
        |i| [f64::from(map[i]), level(i)],
        |[err, reference], n| (err / n) / (reference / n).max(floor),
    )
}

/// 99th percentile and maximum of a non-empty error map.
fn tail_stats(map: &[f32]) -> (f64, f64) {
    let mut sorted: Vec<f64> = map.iter().map(|&v| f64::from(v)).collect();
    sorted.sort_unstable_by(f64::total_cmp);
    let max = sorted.last().copied().unwrap_or(0.0);
    (percentile(&sorted, 99.0), max)
}

fn load(path: &Path) -> Result<Loaded, CompareError> {
    let bytes = fs::read(path).map_err(|source| CompareError::Read {
        path: path.to_owned(),
        source,
    })?;
    match crate::image_io::sniff(&bytes) {
        FileFormat::Png => load_png(path, &bytes),
        FileFormat::OpenExr => load_exr(path, &bytes),
        FileFormat::Jpeg | FileFormat::Unknown => Err(CompareError::UnknownFormat {
            path: path.to_owned(),
        }),
    }
}

/// Runs a third-party decoder, turning a panic on malformed input into an
/// error so that one corrupt screenshot fails its check instead of the tool.
fn guard<T>(
    path: &Path,
    format: &'static str,
    f: impl FnOnce() -> Result<T, CompareError>,
) -> Result<T, CompareError> {
    panic::catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|_| {
        Err(CompareError::DecoderPanic {
            path: path.to_owned(),
            format,
        })
    })
}

fn check_size(path: &Path, width: usize, height: usize) -> Result<(u32, u32), CompareError> {
    let bad = || CompareError::BadSize {
        path: path.to_owned(),
        width,
        height,
        max: MAX_PIXELS,
    };
    let pixels = width.checked_mul(height).ok_or_else(bad)?;
    if pixels == 0 || pixels > MAX_PIXELS {
        return Err(bad());
    }
    // MAX_PIXELS keeps both sides (and width * height * 3, which the FLIP
    // binding computes in u32) far below u32::MAX.
    Ok((
        u32::try_from(width).map_err(|_| bad())?,
        u32::try_from(height).map_err(|_| bad())?,
    ))
}

fn load_png(path: &Path, bytes: &[u8]) -> Result<Loaded, CompareError> {
    // The image crate's default limits bound memory use for huge PNGs.
    let img = guard(path, "PNG", || {
        image::load_from_memory_with_format(bytes, ImageFormat::Png).map_err(|source| {
            CompareError::Png {
                path: path.to_owned(),
                source,
            }
        })
    })?;
    let (width, height) = check_size(path, img.width() as usize, img.height() as usize)?;
    Ok(Loaded {
        width,
        height,
        pixels: Pixels::Srgb(img),
    })
}

fn load_exr(path: &Path, bytes: &[u8]) -> Result<Loaded, CompareError> {
    // Builder steps of the exr reader are trait methods.
    use exr::prelude::{ReadChannels, ReadLayers};

    let exr_err = |source| CompareError::Exr {
        path: path.to_owned(),
        source,
    };
    // Check the claimed sizes before decoding, because the decoder allocates
    // whatever the header asks for.
    let meta = guard(path, "OpenEXR", || {
        exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(exr_err)
    })?;
    for header in &meta.headers {
        check_size(path, header.layer_size.0, header.layer_size.1)?;
    }

    struct Rgb {
        width: usize,
        data: Vec<f32>,
    }
    let image = guard(path, "OpenEXR", || {
        exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .rgb_channels(
                |size, _| Rgb {
                    width: size.0,
                    data: vec![0.0; size.0 * size.1 * 3],
                },
                |px: &mut Rgb, pos, (r, g, b): (f32, f32, f32)| {
                    let i = (pos.1 * px.width + pos.0) * 3;
                    if let Some(dst) = px.data.get_mut(i..i + 3) {
                        dst.copy_from_slice(&[r, g, b]);
                    }
                },
            )
            .first_valid_layer()
            .all_attributes()
            .from_buffered(Cursor::new(bytes))
            .map_err(exr_err)
    })?;

    let size = image.layer_data.size;
    let (width, height) = check_size(path, size.0, size.1)?;
    let data = image.layer_data.channel_data.pixels.data;

    check_finite(path, &data, size.0)?;
    Ok(Loaded {
        width,
        height,
        pixels: Pixels::Linear(data),
    })
}

/// Rejects NaN and infinite values in interleaved RGB `data` of an image
/// `width` pixels wide, naming the first one.
fn check_finite(path: &Path, data: &[f32], width: usize) -> Result<(), CompareError> {
    let mut bad = data.iter().enumerate().filter(|(_, v)| !v.is_finite());
    if let Some((first, _)) = bad.next() {
        let pixel = first / 3;
        return Err(CompareError::NonFinite {
            path: path.to_owned(),
            count: 1 + bad.count(),
            x: pixel % width.max(1),
            y: pixel / width.max(1),
        });
    }
    Ok(())
}

/// Copies an in-memory RGBA image into the form [`load`] produces, with the
/// same size and value checks as a file gets.
fn from_memory(path: &Path, image: ImageRef<'_>) -> Result<Loaded, CompareError> {
    let (width, height, len) = match image {
        ImageRef::Srgb8 {
            width,
            height,
            rgba,
        } => (width, height, rgba.len()),
        ImageRef::Linear {
            width,
            height,
            rgba,
        } => (width, height, rgba.len()),
    };
    let (width, height) = check_size(path, width as usize, height as usize)?;
    // check_size bounds the pixel count, so this cannot overflow.
    let expected = width as usize * height as usize * 4;
    if len != expected {
        return Err(CompareError::BadBuffer {
            path: path.to_owned(),
            len,
            width,
            height,
        });
    }
    let pixels = match image {
        ImageRef::Srgb8 { rgba, .. } => {
            // The length was checked above; the error is only a fallback.
            let img =
                image::RgbaImage::from_raw(width, height, rgba.to_vec()).ok_or_else(|| {
                    CompareError::BadBuffer {
                        path: path.to_owned(),
                        len,
                        width,
                        height,
                    }
                })?;
            Pixels::Srgb(DynamicImage::ImageRgba8(img))
        }
        ImageRef::Linear { rgba, .. } => {
            let rgb: Vec<f32> = rgba
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            check_finite(path, &rgb, width as usize)?;
            Pixels::Linear(rgb)
        }
    };
    Ok(Loaded {
        width,
        height,
        pixels,
    })
}

/// FLIP's own magma colour map, 256 entries of 8-bit sRGB, taken from the
/// FLIP library so our error maps look exactly like those of FLIP's tools.
fn magma_lut() -> Vec<[u8; 3]> {
    nv_flip::magma_lut()
        .to_vec()
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

/// Black-red-yellow-white ramp for RMSE/PSNR maps. Deliberately not magma, so
/// nobody mistakes a relative heat map for FLIP's absolute scale.
const HEAT: [(u8, [u8; 3]); 4] = [
    (0, [0, 0, 0]),
    (85, [255, 0, 0]),
    (170, [255, 255, 0]),
    (255, [255, 255, 255]),
];

/// Expands control points (ascending indices, first 0, last 255) into a
/// 256-entry table by linear interpolation.
fn build_lut(points: &[(u8, [u8; 3])]) -> Vec<[u8; 3]> {
    (0..=255u8)
        .map(|i| {
            // First segment whose end is at or past i; the clamp keeps a
            // malformed table from indexing out of range.
            let k = points.windows(2).position(|w| i <= w[1].0).unwrap_or(0);
            let ((i0, lo), (i1, hi)) = match (points.get(k), points.get(k + 1)) {
                (Some(&a), Some(&b)) => (a, b),
                (Some(&a), None) => (a, a),
                _ => return [0, 0, 0],
            };
            let span = f64::from(i1) - f64::from(i0);
            let f = if span > 0.0 {
                ((f64::from(i) - f64::from(i0)) / span).clamp(0.0, 1.0)
            } else {
                0.0
            };
            std::array::from_fn(|c| {
                (f64::from(lo[c]) + f * (f64::from(hi[c]) - f64::from(lo[c]))).round() as u8
            })
        })
        .collect()
}

/// Writes `cmp.error_map` as an RGB PNG at `path`.
///
/// FLIP maps are coloured with FLIP's magma map on its absolute `[0, 1]`
/// scale, so pictures from different runs are comparable. RMSE/PSNR maps are
/// a heat map (black, red, yellow, white) normalised to the map's maximum, so
/// even tiny differences are visible; an all-zero map is black.
///
/// The PNG is written to a temporary file in the same folder and renamed into
/// place, so a failed write never leaves a partial or stale-looking file at
/// `path`.
pub fn write_diff_png(cmp: &ImageDiff, path: &Path) -> Result<(), CompareError> {
    let expected = (cmp.width as usize).checked_mul(cmp.height as usize);
    if cmp.width == 0 || cmp.height == 0 || expected != Some(cmp.error_map.len()) {
        return Err(CompareError::BadErrorMap {
            path: path.to_owned(),
            len: cmp.error_map.len(),
            width: cmp.width,
            height: cmp.height,
        });
    }

    let (lut, scale) = match cmp.metric {
        Metric::Flip => (magma_lut(), 1.0f32),
        Metric::Rmse | Metric::Psnr => {
            let max = cmp.error_map.iter().copied().fold(0.0f32, f32::max);
            let scale = if max > 0.0 && max.is_finite() {
                1.0 / max
            } else {
                0.0
            };
            (build_lut(&HEAT), scale)
        }
    };
    let mut rgb = Vec::with_capacity(cmp.error_map.len() * 3);
    for &v in &cmp.error_map {
        let t = v * scale;
        // NaN fails both comparisons and lands on index 0.
        let t = if t > 0.0 { t.min(1.0) } else { 0.0 };
        rgb.extend_from_slice(&lut[(t * 255.0).round() as usize]);
    }

    write_atomically(path, |w| {
        PngEncoder::new(w)
            .write_image(&rgb, cmp.width, cmp.height, ExtendedColorType::Rgb8)
            .map_err(|source| CompareError::Encode {
                path: path.to_owned(),
                source,
            })
    })
}

/// Writes through `write` into a temporary file for `path` and renames it
/// into place ([`crate::files`], the crate's one file writer); on any
/// failure the temporary file is removed. The sweep report writes its files
/// through `crate::files` directly.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), CompareError>,
) -> Result<(), CompareError> {
    let io_err = |source| CompareError::Write {
        path: path.to_owned(),
        source,
    };
    let as_io = |e: crate::files::FileError| match e {
        crate::files::FileError::Io { error, .. } => io_err(error),
        refused => io_err(io::Error::other(refused.to_string())),
    };
    crate::files::check_output(path, crate::files::Format::Png).map_err(as_io)?;
    let pending = crate::files::PendingFile::create(path).map_err(as_io)?;
    let mut w = BufWriter::new(pending.file().try_clone().map_err(io_err)?);
    write(&mut w)?;
    w.flush().map_err(io_err)?;
    drop(w);
    pending.commit().map_err(as_io)?;
    Ok(())
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
mod tests {
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

    fn exr(dir: &TempDir, name: &str, w: usize, h: usize, rgb: [f32; 3]) -> PathBuf {
        let p = dir.path(name);
        exr::prelude::write_rgb_file(&p, w, h, |_, _| (rgb[0], rgb[1], rgb[2])).unwrap();
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
        let err = compare_images("ref", image(&ok), "short one", image(&short), Metric::Rmse)
            .unwrap_err();
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
        exr::prelude::write_rgb_file(&p, 4, 4, |x, y| {
            let r = if (x, y) == (2, 1) { f32::NAN } else { 0.0 };
            (r, 0.0f32, 0.0f32)
        })
        .unwrap();
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
            exr::prelude::write_rgb_file(&p, 40, 30, |x, y| {
                let v = if (10..10 + size).contains(&x) && (5..5 + size).contains(&y) {
                    1.5f32
                } else {
                    1.0
                };
                (v, v, v)
            })
            .unwrap();
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
}
