//! The benchmark report: what was measured, on what, from which build, and
//! the timing summaries; serialised as JSON for baselines and dashboards.
//!
//! Every time is in milliseconds (fields named `ms`). A [`Summary`] holds
//! min, median, p95, max, mean and sample standard deviation over the
//! measured frames (see [`crate::report::stats`]).

use super::BenchError;
use crate::report::stats::Summary;
use crate::vk::DeviceInfo;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

/// The `format` of reports this build writes and reads; bumped when a
/// field changes meaning, so an old baseline fails loudly instead of being
/// compared wrongly.
pub const FORMAT: &str = "aerial-bench/1";

/// The largest report [`BenchReport::load`] reads: a report of 30 frames
/// per scene is a few kilobytes, and this holds millions of samples.
pub const MAX_REPORT_BYTES: u64 = 64 << 20;

/// The shortest non-zero time a report may hold, in ms: 1 ns, finer than
/// any timestamp or CPU clock this program reads resolves.
pub const MIN_NONZERO_MS: f64 = 1e-6;

/// Name of the row with the sum of a frame's pass times.
pub const GPU_TOTAL: &str = "gpu total";
/// Name of the row with a frame's CPU time (submit to fence signalled).
pub const CPU_FRAME: &str = "cpu frame";

/// One `aerial bench` run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchReport {
    /// [`FORMAT`].
    pub format: String,
    /// The commit the binary was built from (`git rev-parse --short HEAD`,
    /// `-dirty` if the tree had changes, `unknown` outside git).
    pub commit: String,
    /// The crate version of the binary.
    pub aerial_version: String,
    /// `release` or `debug`.
    pub build: String,
    pub device: DeviceRecord,
    /// Frames submitted and discarded before measuring, per run.
    pub warmup: u32,
    /// Frames measured per run.
    pub frames: u32,
    /// Whether the validation layer was on (which slows everything down).
    pub validate: bool,
    /// What was measured beyond time; reports from before this field
    /// measured time only.
    #[serde(default = "only_time")]
    pub metrics: Vec<Metric>,
    /// The empty pass at each resolution the scenes use.
    pub empty_passes: Vec<EmptyPassReport>,
    pub scenes: Vec<SceneReport>,
}

/// The device and driver, as the Vulkan driver reports them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceRecord {
    pub name: String,
    pub driver_name: String,
    pub driver_info: String,
    /// `VkPhysicalDeviceProperties::driverVersion`, vendor-encoded.
    pub driver_version: u32,
    /// The Vulkan API version the device supports, `major.minor.patch`.
    pub api_version: String,
}

impl From<&DeviceInfo> for DeviceRecord {
    fn from(d: &DeviceInfo) -> Self {
        DeviceRecord {
            name: d.name.clone(),
            driver_name: d.driver_name.clone(),
            driver_info: d.driver_info.clone(),
            driver_version: d.driver_version,
            api_version: d.api_version.clone(),
        }
    }
}

impl fmt::Display for DeviceRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({} {}, driverVersion {:#x}), Vulkan {}",
            self.name, self.driver_name, self.driver_info, self.driver_version, self.api_version
        )
    }
}

/// Output size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Resolution {
    pub width: u32,
    pub height: u32,
}

impl fmt::Display for Resolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

/// What a benchmark measures (`--metric`). Time is always measured; the
/// others are asked for.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Metric {
    /// GPU time per pass (timestamps) and CPU time per frame.
    Time,
    /// CPU instructions the driver executes per pass, counted under
    /// valgrind (CPU drivers only).
    Instructions,
    /// Pipeline statistics per pass: primitives, vertex, fragment and
    /// compute invocations (exact on any device with the queries).
    Work,
}

fn only_time() -> Vec<Metric> {
    vec![Metric::Time]
}

/// One measured row: a pass, or a whole-frame total.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PassReport {
    /// The pass name (`opaque`, `tonemap`, ...), [`GPU_TOTAL`] or
    /// [`CPU_FRAME`].
    pub name: String,
    /// Per-frame times in milliseconds, with the median's 95 % interval.
    pub ms: Summary,
    /// Median time divided by the empty pass's median GPU time at the same
    /// resolution (for a scene, the one timed between its frames); `None`
    /// for CPU rows or without timestamps.
    pub empty_pass_multiple: Option<f64>,
    /// Every measured frame's time, in frame order, for intervals of ratios
    /// (`--compare`, `--against`); absent in older reports.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub samples_ms: Vec<f64>,
    /// Instructions per frame (`--metric instructions`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instructions: Option<CountReport>,
    /// Pipeline statistics per frame (`--metric work`): the same in every
    /// frame, so one set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub work: Option<crate::vk::PipelineStats>,
}

impl PassReport {
    /// A row with its times and nothing else yet.
    pub fn timed(name: &str, samples_ms: &[f64], ms: Summary) -> PassReport {
        PassReport {
            name: name.to_string(),
            ms,
            empty_pass_multiple: None,
            samples_ms: samples_ms.to_vec(),
            instructions: None,
            work: None,
        }
    }
}

/// A row's instruction counts over the measured frames.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CountReport {
    /// Every frame's count, in frame order.
    pub samples: Vec<u64>,
    /// Their summary, with the median's 95 % interval.
    pub summary: Summary,
    /// `max / min - 1` over the frames: how well the count repeats.
    pub spread: f64,
    /// The median divided by the empty pass's median count at the same
    /// resolution.
    pub empty_pass_multiple: Option<f64>,
}

impl CountReport {
    /// `None` for no samples.
    pub fn of(samples: Vec<u64>) -> Option<CountReport> {
        let as_f64: Vec<f64> = samples.iter().map(|&n| n as f64).collect();
        let summary = Summary::of(&as_f64)?;
        let spread = if summary.min > 0.0 {
            summary.max / summary.min - 1.0
        } else {
            0.0
        };
        Some(CountReport {
            samples,
            summary,
            spread,
            empty_pass_multiple: None,
        })
    }
}

/// The empty pass (the driver's floor) at one resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EmptyPassReport {
    pub resolution: Resolution,
    /// The pass's GPU time; `None` when the device has no timestamps.
    pub gpu: Option<PassReport>,
    pub cpu_frame: PassReport,
}

/// One scene file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneReport {
    /// The scene file as given on the command line; the key that
    /// comparisons match scenes by.
    pub file: String,
    /// SHA-256 of the file's bytes, lowercase hex.
    pub sha256: String,
    pub resolution: Resolution,
    /// Triangles drawn per frame (after tessellation).
    pub triangles: u64,
    /// Every knob's setting, after command-line overrides.
    pub knobs: BTreeMap<String, String>,
    /// GPU time of each pass, in frame order; empty without timestamps.
    pub passes: Vec<PassReport>,
    /// The sum of the passes per frame; `None` without timestamps.
    pub gpu_total: Option<PassReport>,
    pub cpu_frame: PassReport,
    /// The empty pass at this scene's resolution, timed after each of its
    /// frames on the same device: the floor its `empty_pass_multiple`s
    /// divide by. `None` without timestamps (and in reports from before
    /// this field, whose multiples divide by the separate empty-pass run).
    #[serde(default)]
    pub empty_pass_between_frames: Option<PassReport>,
    /// Asset warnings of the scene's models (missing MTL libraries and
    /// textures drawn with defaults and placeholders); 0 in reports from
    /// before this field.
    #[serde(default)]
    pub asset_warnings: usize,
}

impl SceneReport {
    /// The passes, then the GPU total, then the CPU frame time.
    pub fn rows(&self) -> impl Iterator<Item = &PassReport> {
        self.passes
            .iter()
            .chain(&self.gpu_total)
            .chain(std::iter::once(&self.cpu_frame))
    }
}

impl EmptyPassReport {
    /// The GPU pass (if timed), then the CPU frame time.
    pub fn rows(&self) -> impl Iterator<Item = &PassReport> {
        self.gpu.iter().chain(std::iter::once(&self.cpu_frame))
    }
}

impl BenchReport {
    /// Reads a report written by [`BenchReport::save`], rejecting other
    /// formats with an error naming the file and the `format` field.
    ///
    /// The file must be a regular file of at most [`MAX_REPORT_BYTES`]: a
    /// device, FIFO or folder is refused before it is opened, and reading
    /// stops at the bound, so `/dev/zero` or a pipe neither fills memory
    /// nor hangs the run.
    pub fn load(path: &Path) -> Result<BenchReport, BenchError> {
        let text = super::read_bounded_text(path, MAX_REPORT_BYTES, "a benchmark report")?;
        BenchReport::from_json(&text, path)
    }

    /// [`BenchReport::load`] of a report another process wrote into a
    /// temporary file (a round of `--against`, the counting run under
    /// valgrind): errors name `name` instead of the temporary path.
    pub fn load_named(path: &Path, name: &str) -> Result<BenchReport, BenchError> {
        let rename = |e: BenchError| match e {
            BenchError::Io { error, .. } => BenchError::Io {
                path: name.into(),
                error,
            },
            BenchError::Json { reason, .. } => BenchError::Json {
                path: name.into(),
                reason,
            },
            BenchError::Input { reason, .. } => BenchError::Input {
                path: name.into(),
                reason: reason.replace(&path.display().to_string(), name),
            },
            other => other,
        };
        let text = super::read_bounded_text(path, MAX_REPORT_BYTES, "a benchmark report")
            .map_err(rename)?;
        BenchReport::from_json(&text, Path::new(name))
    }

    /// Parses a report; `path` is only used in error messages.
    pub fn from_json(text: &str, path: &Path) -> Result<BenchReport, BenchError> {
        // Check the format first, so a report of another version says so
        // rather than failing on whichever field changed.
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| BenchError::Json {
                path: path.to_path_buf(),
                reason: e.to_string(),
            })?;
        match value.get("format").and_then(|f| f.as_str()) {
            Some(FORMAT) => {}
            Some(other) => {
                return Err(BenchError::Json {
                    path: path.to_path_buf(),
                    reason: format!("format: '{other}' is not {FORMAT}"),
                })
            }
            None => {
                return Err(BenchError::Json {
                    path: path.to_path_buf(),
                    reason: format!(
                        "format: missing; not a benchmark report (expected \"{FORMAT}\")"
                    ),
                })
            }
        }
        // Parsed again from the text so errors keep their line and column,
        // and through serde_path_to_error so they name the field.
        let report: BenchReport =
            serde_path_to_error::deserialize(&mut serde_json::Deserializer::from_str(text))
                .map_err(|e| BenchError::Json {
                    path: path.to_path_buf(),
                    reason: format!("{}: {}", e.path(), e.inner()),
                })?;
        report
            .check_unique()
            .and_then(|()| report.check_values())
            .map_err(|reason| BenchError::Json {
                path: path.to_path_buf(),
                reason,
            })?;
        Ok(report)
    }

    /// Refuses a scene file, an empty-pass resolution or a scene's pass
    /// named twice: a comparison matches rows by these names, and would
    /// judge the first entry and silently drop the second.
    fn check_unique(&self) -> Result<(), String> {
        fn first_repeat<T: PartialEq>(items: impl Iterator<Item = T>) -> Option<(usize, T)> {
            let items: Vec<T> = items.collect();
            let i = (1..items.len()).find(|&i| items[..i].contains(&items[i]))?;
            items.into_iter().nth(i).map(|item| (i, item))
        }
        if let Some((i, r)) = first_repeat(self.empty_passes.iter().map(|e| e.resolution)) {
            return Err(format!("empty_passes[{i}]: resolution {r} appears twice"));
        }
        if let Some((i, file)) = first_repeat(self.scenes.iter().map(|s| &s.file)) {
            return Err(format!("scenes[{i}].file: '{file}' appears twice"));
        }
        for (s, scene) in self.scenes.iter().enumerate() {
            if let Some((i, name)) = first_repeat(scene.passes.iter().map(|p| &p.name)) {
                return Err(format!(
                    "scenes[{s}].passes[{i}].name: '{name}' appears twice in {}",
                    scene.file
                ));
            }
        }
        Ok(())
    }

    /// Refuses values no measurement gives, naming the field: a frame's
    /// time or count that is negative; 0 in a row that always costs
    /// something (an empty pass, a frame's GPU total, a CPU frame); a
    /// non-zero time under [`MIN_NONZERO_MS`]; a summary of no frames, or
    /// of another number of frames than the row keeps; a value that is not
    /// a finite number. Summaries are kept as stated: a gate judges a
    /// baseline's medians, and refuses those it cannot divide by (see
    /// [`super::baseline::Unjudgeable`]).
    fn check_values(&self) -> Result<(), String> {
        for (i, e) in self.empty_passes.iter().enumerate() {
            if let Some(gpu) = &e.gpu {
                check_row(&format!("empty_passes[{i}].gpu"), gpu, true)?;
            }
            check_row(&format!("empty_passes[{i}].cpu_frame"), &e.cpu_frame, true)?;
        }
        for (s, scene) in self.scenes.iter().enumerate() {
            for (i, p) in scene.passes.iter().enumerate() {
                check_row(&format!("scenes[{s}].passes[{i}]"), p, false)?;
            }
            if let Some(total) = &scene.gpu_total {
                check_row(&format!("scenes[{s}].gpu_total"), total, true)?;
            }
            check_row(&format!("scenes[{s}].cpu_frame"), &scene.cpu_frame, true)?;
            if let Some(floor) = &scene.empty_pass_between_frames {
                check_row(
                    &format!("scenes[{s}].empty_pass_between_frames"),
                    floor,
                    true,
                )?;
            }
        }
        Ok(())
    }

    /// Writes the report as pretty-printed JSON.
    pub fn save(&self, path: &Path) -> Result<(), BenchError> {
        let mut text = serde_json::to_string_pretty(self).map_err(|e| BenchError::Json {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        text.push('\n');
        crate::safe_files::write_bytes(path, text.as_bytes()).map_err(|e| match e {
            crate::safe_files::FileError::Io { error, .. } => BenchError::Io {
                path: path.to_path_buf(),
                error,
            },
            crate::safe_files::FileError::Refused { reason, .. } => BenchError::Json {
                path: path.to_path_buf(),
                reason: format!("cannot write: {reason}"),
            },
        })?;
        Ok(())
    }

    /// The empty pass measured at `resolution`, if any.
    pub fn empty_pass(&self, resolution: Resolution) -> Option<&EmptyPassReport> {
        self.empty_passes
            .iter()
            .find(|e| e.resolution == resolution)
    }
}

/// What a value of a row is, for [`check_row`]'s messages and bounds.
#[derive(Clone, Copy)]
struct Quantity {
    /// "time" or "instruction count".
    what: &'static str,
    /// 0 is impossible (see [`BenchReport::check_values`]).
    positive: bool,
    /// The smallest non-zero value ([`MIN_NONZERO_MS`] for times).
    min_nonzero: f64,
}

/// Checks one row: its times, its multiple, its instruction counts.
/// `positive` says the row always costs something. Errors start with the
/// field's path (`scenes[0].passes[1].ms.median`) and name the row.
fn check_row(field: &str, row: &PassReport, positive: bool) -> Result<(), String> {
    let named = |e: String| format!("{field}{e} (row '{}')", row.name);
    let time = Quantity {
        what: "time",
        positive,
        min_nonzero: MIN_NONZERO_MS,
    };
    check_samples(".ms", ".samples_ms", &row.ms, &row.samples_ms, time).map_err(named)?;
    if let Some(m) = row.empty_pass_multiple {
        check_number(".empty_pass_multiple", m).map_err(named)?;
    }
    if let Some(c) = &row.instructions {
        let count = Quantity {
            what: "instruction count",
            positive,
            min_nonzero: 0.0,
        };
        let samples: Vec<f64> = c.samples.iter().map(|&n| n as f64).collect();
        check_samples(
            ".instructions.summary",
            ".instructions.samples",
            &c.summary,
            &samples,
            count,
        )
        .map_err(named)?;
        check_number(".instructions.spread", c.spread).map_err(named)?;
        if let Some(m) = c.empty_pass_multiple {
            check_number(".instructions.empty_pass_multiple", m).map_err(named)?;
        }
    }
    Ok(())
}

/// A finite number, at least 0.
fn check_number(field: &str, value: f64) -> Result<(), String> {
    if !value.is_finite() {
        return Err(format!("{field}: {} is not a finite number", show(value)));
    }
    if value < 0.0 {
        return Err(format!("{field}: {} is negative", show(value)));
    }
    Ok(())
}

/// A value for a message: plain, or with an exponent when far from 1.
fn show(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// One value of a row: finite, not negative, not 0 where the row always
/// costs something, and not below the smallest non-zero value.
fn check_value(field: &str, value: f64, q: Quantity) -> Result<(), String> {
    check_number(field, value).map_err(|e| format!("{e}; a {} is at least 0", q.what))?;
    if value == 0.0 && q.positive {
        return Err(format!(
            "{field}: 0; this row always costs something (an empty pass, a frame's GPU \
             total or its CPU time), so a {} of 0 is not a measurement",
            q.what
        ));
    }
    if value > 0.0 && value < q.min_nonzero {
        return Err(format!(
            "{field}: {} ms is shorter than 1 ns, finer than any clock this program \
             reads resolves",
            show(value)
        ));
    }
    Ok(())
}

/// Checks a summary and the samples it summarises (none in old reports).
fn check_samples(
    at: &str,
    samples_at: &str,
    s: &Summary,
    samples: &[f64],
    q: Quantity,
) -> Result<(), String> {
    for (k, &v) in samples.iter().enumerate() {
        check_value(&format!("{samples_at}[{k}]"), v, q)?;
    }
    if s.count == 0 {
        return Err(format!("{at}.count: 0; a summary is of at least one frame"));
    }
    if !samples.is_empty() && s.count != samples.len() {
        return Err(format!(
            "{at}.count: {}, but {} holds {} values",
            s.count,
            &samples_at[1..],
            samples.len()
        ));
    }
    // The summary's values are what a gate divides, as stated (a
    // baseline's medians may be edited to move it): only what no
    // comparison can use is refused here; a median the gate cannot divide
    // by is refused by the gate, naming the row (`baseline::Unjudgeable`).
    for (name, v) in s.named() {
        if !v.is_finite() {
            return Err(format!("{at}.{name}: {v} is not a finite number"));
        }
    }
    Ok(())
}
