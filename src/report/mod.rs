//! Reporting helpers for CI: summarising benchmark samples, comparing
//! rendered screenshots against references, and plotting.
//!
//! - [`stats`] turns raw frame-time samples into a [`Summary`] (min, median,
//!   p95, max, mean, sample standard deviation) that serialises to JSON for
//!   dashboards and regression checks, and a run's per-frame pass times into
//!   one per pass plus the frame total.
//! - [`image_diff`] compares two images (PNG as sRGB 8-bit, OpenEXR as linear
//!   float) with FLIP, PSNR or RMSE, gates the result against [`Thresholds`],
//!   and writes a diff picture for humans to look at.
//! - [`plot`] draws error against GPU time as SVG, for the sweep (which
//!   calls it; nothing here knows the sweep).
//!
//! All are deliberately free of Vulkan so they can run on CI machines without
//! a GPU, e.g. to re-check stored screenshots.

pub mod image_diff;
pub mod plot;
pub mod stats;

pub use image_diff::{
    compare_files, compare_images, write_diff_png, CompareError, ImageDiff, ImageRef, Metric,
    Thresholds, FLIP_DEFAULT_THRESHOLDS,
};
pub use stats::{percentile, summarise_passes, PassSummaries, PassTimesError, Summary};
