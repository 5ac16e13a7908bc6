//! `aerial compare`: compare a test image with a reference image for
//! screenshot regression checks. Prints mean, p99 and max of the chosen
//! metric, optionally writes a diff image, and exits with status 1 when a
//! threshold is exceeded (errors exit with 2, see `main.rs`), so a CI step
//! can gate on it.

use aerial::image_io;
use aerial::report::image_diff::{
    compare_files, write_diff_png, ImageDiff, Metric, Thresholds, WINDOW,
};
use aerial::safe_files;
use anyhow::{bail, Context as _};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Exit status when the images were compared but a threshold was exceeded.
/// Distinct from errors (2) so a CI script can tell "the picture changed"
/// from "the check could not run".
const EXIT_THRESHOLD_EXCEEDED: u8 = 1;

#[derive(clap::Args)]
#[command(after_long_help = "\
Exit status: 0 when every threshold holds, 1 when one is exceeded, 2 on an \
error (unreadable file, size or format mismatch, bad option).

Example (CI):
  aerial compare tests/reference/default.png out.png --diff out.diff.png")]
pub struct CompareArgs {
    /// Reference image: PNG (sRGB), or OpenEXR (linear HDR; rmse/psnr only).
    reference: PathBuf,
    /// Image to check: same format and size as the reference.
    test: PathBuf,
    /// Write a per-pixel error image (PNG) here, whether or not the check
    /// passes.
    ///
    /// FLIP maps use FLIP's magma colours on the absolute 0..1 scale; rmse and
    /// psnr maps are a black-red-yellow-white heat map scaled to the largest
    /// error in the image.
    #[arg(long, value_name = "PNG")]
    diff: Option<PathBuf>,
    /// Error metric.
    ///
    /// flip: NVIDIA FLIP, perceptual, per pixel 0 (same) to 1; PNG only.
    /// rmse: root mean square error of R, G, B (0..1 for PNG, linear values
    /// for OpenEXR). psnr: peak signal-to-noise ratio in dB (peak 1 for PNG,
    /// the reference's brightest value for OpenEXR).
    #[arg(long, value_enum, default_value_t = MetricArg::Flip)]
    metric: MetricArg,
    /// Largest acceptable mean (for psnr: smallest acceptable PSNR in dB).
    ///
    /// Default for flip: 0.03. Measured on the example scenes, +-1 LSB
    /// rounding noise alone gives a FLIP mean of 0.011 and a 1 % exposure
    /// change 0.011-0.019 (differences another GPU or driver may make), while
    /// a 5 % exposure change gives 0.033 or more and a missing light 0.067 or
    /// more. No default for rmse and psnr: their values depend on the image
    /// content, so without limits they only report.
    #[arg(long, value_name = "X")]
    threshold: Option<f64>,
    /// Largest acceptable 99th percentile of the per-pixel error.
    ///
    /// Catches localised breakage that barely moves the mean. Default for
    /// flip: 0.1. Measured on the example scenes, edges moved by 1/20 pixel
    /// (rasterisation differences between drivers) mostly give a FLIP p99
    /// below 0.1 (toon-shaded bands up to 0.20), while a missing light gives 0.30 or more and a missing sphere,
    /// torus or flag 0.81 or more. Pass 1 (FLIP's maximum) to check only the
    /// mean. For psnr this is still a per-pixel RMS error, not dB.
    #[arg(long, value_name = "Y")]
    p99_threshold: Option<f64>,
    /// Largest acceptable error over the worst 12x12-pixel square.
    ///
    /// Catches small local defects (a missing or extra small object, a
    /// broken patch) that hide in the mean and p99 of a large frame. For
    /// flip the mean FLIP over the square, default 0.3: edges moved by 1/20
    /// pixel give at most 0.21, a 6x6 block inverted 0.50 or more. For rmse
    /// and psnr the mean error over the square relative to the reference's
    /// mean level there (or over the whole image, if larger); default 0.4
    /// for OpenEXR (1/20-pixel shifts give at most 0.29, a small missing
    /// object 0.44 or more), none for PNG. Pass a large value to turn it
    /// off.
    #[arg(long, value_name = "Z")]
    window_threshold: Option<f64>,
}

/// The metric names on the command line; clap lists them in the help.
#[derive(Clone, Copy, clap::ValueEnum)]
enum MetricArg {
    Flip,
    Psnr,
    Rmse,
}

impl From<MetricArg> for Metric {
    fn from(m: MetricArg) -> Metric {
        match m {
            MetricArg::Flip => Metric::Flip,
            MetricArg::Psnr => Metric::Psnr,
            MetricArg::Rmse => Metric::Rmse,
        }
    }
}

pub fn run(args: CompareArgs) -> anyhow::Result<ExitCode> {
    let metric = Metric::from(args.metric);
    // Check the options before reading any file, so a typo fails fast.
    let given = thresholds(
        metric,
        args.threshold,
        args.p99_threshold,
        args.window_threshold,
    )?;
    // The diff image may be neither of the images compared.
    safe_files::protect_inputs_as_read();
    safe_files::protect_inputs([&args.reference, &args.test]);
    if let Some(diff) = &args.diff {
        safe_files::check_output(diff, safe_files::Format::Png).context("--diff")?;
        // The diff has the reference's size: room for it, before the work
        // (an unreadable reference is reported by the comparison).
        if let Ok((width, height)) = image_io::image_size(&args.reference) {
            safe_files::check_room(&[(diff, image_io::png_size_bound(width, height))])
                .context("--diff")?;
        }
    }
    // The library's errors name the file and the reason, and also carry
    // the reason as their `source`; converting through Display keeps
    // main's `{:#}` from printing that reason a second time.
    let cmp =
        compare_files(&args.reference, &args.test, metric).map_err(|e| anyhow::anyhow!("{e}"))?;

    // The defaults depend on the format, known only once the files are read.
    let defaults = cmp.default_thresholds();
    let limits = Thresholds {
        mean: given.mean.or(defaults.mean),
        p99: given.p99.or(defaults.p99),
        worst_window: given.worst_window.or(defaults.worst_window),
    };

    print_provenance(&args.reference, &args.test);
    print_report(&cmp, &limits);
    if let Some(diff) = &args.diff {
        write_diff_png(&cmp, diff).map_err(|e| anyhow::anyhow!("{e}"))?;
        eprintln!("wrote {}", diff.display());
    }
    let failures = exceeded(&cmp, &limits);
    if failures.is_empty() {
        println!("result  pass");
        Ok(ExitCode::SUCCESS)
    } else {
        println!("result  FAIL: {}", failures.join("; "));
        Ok(ExitCode::from(EXIT_THRESHOLD_EXCEEDED))
    }
}

/// The limits given on the command line; the metric's defaults fill in the
/// others after the comparison. Rejects limits that could never be
/// meaningful.
fn thresholds(
    metric: Metric,
    mean: Option<f64>,
    p99: Option<f64>,
    window: Option<f64>,
) -> anyhow::Result<Thresholds> {
    for (flag, value) in [
        ("--threshold", mean),
        ("--p99-threshold", p99),
        ("--window-threshold", window),
    ] {
        if value.is_some_and(f64::is_nan) {
            bail!("{flag}: NaN is not a threshold");
        }
    }
    // Errors are never negative, so a negative limit would fail every
    // comparison; PSNR's mean limit is a minimum in dB and may be anything.
    if metric != Metric::Psnr {
        if let Some(v) = mean.filter(|v| *v < 0.0) {
            bail!("--threshold: {v} is negative; a {metric} mean is never below 0");
        }
    }
    if let Some(v) = p99.filter(|v| *v < 0.0) {
        bail!("--p99-threshold: {v} is negative; a per-pixel error is never below 0");
    }
    if let Some(v) = window.filter(|v| *v < 0.0) {
        bail!("--window-threshold: {v} is negative; a window's error is never below 0");
    }
    Ok(Thresholds {
        mean,
        p99,
        worst_window: window,
    })
}

/// Which device and driver rendered each image, from the PNG text chunks
/// `aerial render` writes. Differing drivers explain small differences;
/// images without the chunks (or OpenEXR files) are silently skipped.
fn print_provenance(reference: &Path, test: &Path) {
    let origin = |path: &Path| -> Option<String> {
        let text = image_io::read_png_text(path).ok()?;
        let get = |key: &str| text.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str());
        match (get("aerial:device"), get("aerial:driver")) {
            (Some(device), Some(driver)) => Some(format!("{device}; driver {driver}")),
            _ => None,
        }
    };
    let (a, b) = (origin(reference), origin(test));
    if a.is_none() && b.is_none() {
        return;
    }
    let show = |o: &Option<String>| o.clone().unwrap_or_else(|| "unknown".into());
    println!("reference rendered by {}", show(&a));
    println!("test      rendered by {}", show(&b));
    if a.is_some() && b.is_some() && a != b {
        println!("note: different devices or drivers; expect small differences");
    }
}

fn print_report(cmp: &ImageDiff, limits: &Thresholds) {
    let (mean_unit, map_unit) = match cmp.metric {
        Metric::Flip => ("", "FLIP"),
        Metric::Rmse => ("", "RMS error"),
        Metric::Psnr => (" dB", "RMS error"),
    };
    let limit = |l: Option<f64>, op: &str, unit: &str| match l {
        Some(v) => format!("(limit {op} {v}{unit})"),
        None => "(not checked)".to_string(),
    };
    let mean_op = if cmp.metric == Metric::Psnr {
        ">="
    } else {
        "<="
    };
    println!(
        "metric  {} ({}x{} pixels)",
        cmp.metric, cmp.width, cmp.height
    );
    // dB need no more than two decimals; error values span decades.
    let mean = match cmp.metric {
        Metric::Psnr => format!("{:.2}", cmp.mean),
        Metric::Flip | Metric::Rmse => format!("{:.6}", cmp.mean),
    };
    println!(
        "mean    {mean}{mean_unit}  {}",
        limit(limits.mean, mean_op, mean_unit)
    );
    println!(
        "p99     {:.6}  per-pixel {map_unit}  {}",
        cmp.p99,
        limit(limits.p99, "<=", "")
    );
    println!("max     {:.6}  per-pixel {map_unit}", cmp.max);
    let window_what = match cmp.metric {
        Metric::Flip => "mean FLIP",
        Metric::Rmse | Metric::Psnr => "relative error",
    };
    println!(
        "window  {:.6}  {window_what} of the worst {WINDOW}x{WINDOW} pixels  {}",
        cmp.worst_window,
        limit(limits.worst_window, "<=", "")
    );
}

/// Human-readable reasons `cmp` fails `limits`, empty when it passes. Each
/// limit is checked with `ImageDiff::passes`, so the exit status can never
/// disagree with the library's definition (including its NaN handling).
fn exceeded(cmp: &ImageDiff, limits: &Thresholds) -> Vec<String> {
    let mut reasons = Vec::new();
    if let Some(l) = limits.mean {
        if !cmp.passes(&Thresholds {
            mean: Some(l),
            ..Thresholds::default()
        }) {
            reasons.push(match cmp.metric {
                Metric::Psnr => format!("psnr {:.2} dB is below {l} dB", cmp.mean),
                m => format!("{m} mean {:.6} exceeds {l}", cmp.mean),
            });
        }
    }
    if let Some(l) = limits.p99 {
        if !cmp.passes(&Thresholds {
            p99: Some(l),
            ..Thresholds::default()
        }) {
            reasons.push(format!("p99 {:.6} exceeds {l}", cmp.p99));
        }
    }
    if let Some(l) = limits.worst_window {
        if !cmp.passes(&Thresholds {
            worst_window: Some(l),
            ..Thresholds::default()
        }) {
            reasons.push(format!(
                "worst {WINDOW}x{WINDOW} window {:.6} exceeds {l}",
                cmp.worst_window
            ));
        }
    }
    reasons
}
