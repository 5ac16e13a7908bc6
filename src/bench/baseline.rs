//! Comparing a benchmark run with a stored baseline, for CI.
//!
//! Rows are matched by scene file (as given on the command line), row name
//! (a pass, `gpu total` or `cpu frame`) and metric (time, and instructions
//! where both reports counted them); empty-pass rows by resolution. Each
//! matched row gets the ratio of medians `current / baseline` and its 95 %
//! interval, so a slowdown is judged relative to the same machine's earlier
//! figure rather than against an absolute time that only holds on one
//! machine, and the gate ([`Verdict`]) decides on the interval, not the
//! point.
//!
//! Differences that make the comparison less meaningful (another device or
//! driver, another resolution, a changed scene file, other knob settings,
//! another build profile) are reported as warnings, not failures: CI
//! decides what to do with them. Rows present on one side only are listed.

use super::report::{BenchReport, Metric, PassReport, Resolution, CPU_FRAME, GPU_TOTAL};
use crate::report::stats::{ratio_interval, Interval};
use std::fmt;

/// A row's identity: which scene (or empty pass) and which pass.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct RowKey {
    /// The scene file, or `empty pass WxH`.
    pub scene: String,
    pub pass: String,
}

impl fmt::Display for RowKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} / {}", self.scene, self.pass)
    }
}

/// One matched row.
#[derive(Clone, Debug, PartialEq)]
pub struct RatioRow {
    pub key: RowKey,
    /// Time (ms) or instructions.
    pub metric: Metric,
    /// The baseline's median.
    pub baseline: f64,
    /// This run's median.
    pub current: f64,
    /// `current / baseline`; `None` when the baseline median is not
    /// positive (a zero-length interval has no meaningful ratio).
    pub ratio: Option<f64>,
    /// The ratio's 95 % interval: a bootstrap over both sides' frames when
    /// both reports kept them, else over this run's frames against the
    /// baseline's median; `None` without samples on this side.
    pub interval: Option<Interval>,
    /// Why the gate does not judge this row, if it does not (see
    /// [`NotJudged`]); `None` for a judged row.
    pub not_judged: Option<NotJudged>,
}

/// Why a matched row is printed but not judged: its baseline median is
/// below what the metric can resolve, so its interval says more about the
/// measurement's noise than about the build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NotJudged {
    /// An instruction row under [`MIN_JUDGED_INSTRUCTIONS`].
    FewInstructions,
    /// A scene's pass faster than the baseline's empty pass at that
    /// resolution: on a binning driver a subpass can time near zero in one
    /// frame and a whole pass in the next, so its ratio has no bound. The
    /// GPU total and the CPU frame hold the whole frame's work wherever the
    /// driver did it, and are always judged: so a baseline whose empty
    /// pass is slower than everything (edited, or of a frame smaller than
    /// the empty pass) still judges the frame.
    BelowEmptyPass,
}

impl fmt::Display for NotJudged {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NotJudged::FewInstructions => "under 3.5e6 instructions",
            NotJudged::BelowEmptyPass => "faster than the empty pass",
        })
    }
}

/// The smallest instruction count a gate judges. The driver's thread
/// hand-offs move a submission's count by about ±2,000 instructions, and
/// now and then one frame carries an allocation of up to about 70,000
/// more (measured on lavapipe). With a few frames one such frame can
/// widen a row's interval by that much, and a 2 % gate cannot decide a
/// row under 70,000 / 0.02 = 3.5 million: smaller rows are printed, not
/// judged (at 1280x720 every pass of the example scenes is larger).
pub const MIN_JUDGED_INSTRUCTIONS: f64 = 3.5e6;

/// What the gate decides for a row, or for a whole comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    /// The whole interval (or, without one, the ratio) is at most the limit.
    Pass,
    /// The interval straddles the limit: more frames are needed to tell.
    Inconclusive,
    /// The whole interval lies above the limit.
    Fail,
}

impl RatioRow {
    /// Whether this row is slower than `max_ratio` allows: its interval
    /// lies above it.
    pub fn exceeds(&self, max_ratio: f64) -> bool {
        self.verdict(max_ratio) == Verdict::Fail
    }

    /// The gate's decision for this row at `max_ratio`.
    pub fn verdict(&self, max_ratio: f64) -> Verdict {
        let (Some(ratio), None) = (self.ratio, self.not_judged) else {
            return Verdict::Pass;
        };
        let interval = self.interval.unwrap_or(Interval::point(ratio));
        if interval.low > max_ratio {
            Verdict::Fail
        } else if interval.high <= max_ratio {
            Verdict::Pass
        } else {
            Verdict::Inconclusive
        }
    }
}

/// The result of [`compare`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BaselineComparison {
    /// Rows present in both, in the current run's order.
    pub rows: Vec<RatioRow>,
    /// Rows of the baseline that this run lacks.
    pub missing: Vec<RowKey>,
    /// Rows of this run that the baseline lacks.
    pub new: Vec<RowKey>,
    /// Why the comparison may be less meaningful.
    pub warnings: Vec<String>,
}

impl BaselineComparison {
    /// The rows whose interval lies above `max_ratio`.
    pub fn exceeding(&self, max_ratio: f64) -> Vec<&RatioRow> {
        self.rows.iter().filter(|r| r.exceeds(max_ratio)).collect()
    }

    /// The worst row verdict ([`Verdict::Pass`] for no rows).
    pub fn verdict(&self, max_ratio: f64) -> Verdict {
        self.rows
            .iter()
            .map(|r| r.verdict(max_ratio))
            .max()
            .unwrap_or(Verdict::Pass)
    }
}

/// Why a comparison cannot back a gate's verdict: a gate that judged
/// none of the workload, or less than it claims, must not pass.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Unjudgeable {
    #[error("nothing to compare: no scene and pass of this run is in the baseline")]
    NothingMatched,
    #[error(
        "nothing of the workload was compared: only empty-pass rows of this run are in the \
         baseline"
    )]
    OnlyEmptyPasses,
    #[error(
        "--metric {metric}: no scene row has {metric} in both this run and the baseline, so \
         the gate cannot judge them"
    )]
    MetricMissing { metric: String },
    #[error("nothing large enough to judge in {metric}: {reason}")]
    NothingJudged { metric: String, reason: String },
    #[error(
        "{} row(s) have no usable baseline median (must be a positive number), so they \
         cannot be compared: {}",
        .rows.len(),
        .rows.join(", ")
    )]
    NoUsableMedian { rows: Vec<String> },
    #[error(
        "{} row(s) of this run have no usable median (must be a number, at least 0), so they \
         cannot be compared: {}",
        .rows.len(),
        .rows.join(", ")
    )]
    NoUsableCurrentMedian { rows: Vec<String> },
}

impl BaselineComparison {
    /// Whether the rows can back a verdict on `metrics` (the metrics the
    /// gate judges; `work` is never judged): some row of the scenes must
    /// have been matched and judged in each metric. For time the GPU total
    /// and CPU frame always are; for instructions, a row of 3.5 million
    /// instructions or more must be there. And no judged row may lack its
    /// ratio (a median of 0 or below).
    pub fn judgeable(&self, metrics: &[Metric]) -> Result<(), Unjudgeable> {
        if self.rows.is_empty() {
            return Err(Unjudgeable::NothingMatched);
        }
        let workload = |r: &&RatioRow| !r.key.scene.starts_with(EMPTY_PASS_PREFIX);
        if !self.rows.iter().any(|r| workload(&r)) {
            return Err(Unjudgeable::OnlyEmptyPasses);
        }
        for &metric in metrics.iter().filter(|m| **m != Metric::Work) {
            let name = metric_name(metric).to_string();
            let rows: Vec<&RatioRow> = self
                .rows
                .iter()
                .filter(workload)
                .filter(|r| r.metric == metric)
                .collect();
            if rows.is_empty() {
                return Err(Unjudgeable::MetricMissing { metric: name });
            }
            if !rows.iter().any(|r| r.not_judged.is_none()) {
                let reason = match metric {
                    Metric::Instructions => format!(
                        "every matched scene row is under {MIN_JUDGED_INSTRUCTIONS:e} \
                         instructions, below what the counts resolve (render larger images)"
                    ),
                    _ => "every matched scene row is faster than the baseline's empty pass"
                        .to_string(),
                };
                return Err(Unjudgeable::NothingJudged {
                    metric: name,
                    reason,
                });
            }
        }
        // A judged row without a ratio (a median of 0 or below) was not
        // compared; a gate that compared less than it claims must not pass.
        let unusable = |baseline: bool| -> Vec<String> {
            self.rows
                .iter()
                .filter(|r| r.not_judged.is_none() && r.ratio.is_none())
                .filter(|r| {
                    let usable = r.baseline > 0.0 && r.baseline.is_finite();
                    baseline != usable
                })
                .map(|r| match baseline {
                    true => format!("{} (baseline {})", r.key, r.baseline),
                    false => format!("{} (this run {})", r.key, r.current),
                })
                .collect()
        };
        let rows = unusable(true);
        if !rows.is_empty() {
            return Err(Unjudgeable::NoUsableMedian { rows });
        }
        let rows = unusable(false);
        if !rows.is_empty() {
            return Err(Unjudgeable::NoUsableCurrentMedian { rows });
        }
        Ok(())
    }
}

/// How `--metric` names a metric.
pub fn metric_name(metric: Metric) -> &'static str {
    match metric {
        Metric::Time => "time",
        Metric::Instructions => "instructions",
        Metric::Work => "work",
    }
}

/// How the keys of empty-pass rows begin.
pub const EMPTY_PASS_PREFIX: &str = "empty pass ";

/// The key of the empty pass at `resolution`.
pub fn empty_pass_scene(resolution: Resolution) -> String {
    format!("{EMPTY_PASS_PREFIX}{resolution}")
}

/// One metric of one row: its median and its frames' values.
#[derive(Clone, Debug)]
pub struct MetricRow {
    pub key: RowKey,
    pub metric: Metric,
    pub median: f64,
    pub samples: Vec<f64>,
}

/// Every row of a report, per metric it carries (time always,
/// instructions where counted), in report order: the empty passes, then
/// each scene's passes and totals.
pub fn rows(report: &BenchReport) -> Vec<MetricRow> {
    let mut out = Vec::new();
    let mut push = |scene: &str, row: &PassReport| {
        let key = RowKey {
            scene: scene.to_string(),
            pass: row.name.clone(),
        };
        out.push(MetricRow {
            key: key.clone(),
            metric: Metric::Time,
            median: row.ms.median,
            samples: row.samples_ms.clone(),
        });
        if let Some(c) = &row.instructions {
            out.push(MetricRow {
                key,
                metric: Metric::Instructions,
                median: c.summary.median,
                samples: c.samples.iter().map(|&n| n as f64).collect(),
            });
        }
    };
    for e in &report.empty_passes {
        let scene = empty_pass_scene(e.resolution);
        e.rows().for_each(|r| push(&scene, r));
    }
    for s in &report.scenes {
        s.rows().for_each(|r| push(&s.file, r));
    }
    out
}

/// Compares `current` with `baseline` in the `metrics` asked for (time
/// rows always exist; instruction rows where both reports counted).
pub fn compare(
    current: &BenchReport,
    baseline: &BenchReport,
    metrics: &[Metric],
) -> BaselineComparison {
    let warnings = setting_warnings(current, baseline);
    let wanted = |r: &MetricRow| metrics.contains(&r.metric);
    let current_rows: Vec<MetricRow> = rows(current).into_iter().filter(wanted).collect();
    let baseline_rows: Vec<MetricRow> = rows(baseline).into_iter().filter(wanted).collect();
    let same = |a: &MetricRow, b: &MetricRow| a.key == b.key && a.metric == b.metric;
    let mut matched = Vec::new();
    let mut new = Vec::new();
    for c in &current_rows {
        match baseline_rows.iter().find(|b| same(b, c)) {
            Some(b) => matched.push(ratio_row(baseline, c, b)),
            None => new.push(c.key.clone()),
        }
    }
    let mut missing: Vec<RowKey> = baseline_rows
        .iter()
        .filter(|b| !current_rows.iter().any(|c| same(b, c)))
        .map(|b| b.key.clone())
        .collect();
    missing.dedup();
    new.dedup();
    BaselineComparison {
        rows: matched,
        missing,
        new,
        warnings,
    }
}

/// Warnings for every setting the two reports differ in: device, build,
/// validation, frame counts, and each scene's resolution, file and knobs.
fn setting_warnings(current: &BenchReport, baseline: &BenchReport) -> Vec<String> {
    let mut warnings = Vec::new();
    if current.device != baseline.device {
        warnings.push(format!(
            "device differs: baseline {}, this run {}",
            baseline.device, current.device
        ));
    }
    if current.build != baseline.build {
        warnings.push(format!(
            "build differs: baseline {}, this run {}",
            baseline.build, current.build
        ));
    }
    if current.validate != baseline.validate {
        warnings.push(format!(
            "validation differs: baseline {}, this run {}",
            on_off(baseline.validate),
            on_off(current.validate)
        ));
    }
    if (current.warmup, current.frames) != (baseline.warmup, baseline.frames) {
        warnings.push(format!(
            "frame counts differ: baseline {} warm-up + {} measured, this run {} + {}",
            baseline.warmup, baseline.frames, current.warmup, current.frames
        ));
    }
    for scene in &current.scenes {
        let Some(base) = baseline.scenes.iter().find(|b| b.file == scene.file) else {
            continue;
        };
        if scene.resolution != base.resolution {
            warnings.push(format!(
                "{}: resolution differs: baseline {}, this run {}",
                scene.file, base.resolution, scene.resolution
            ));
        }
        if scene.sha256 != base.sha256 {
            warnings.push(format!(
                "{}: the scene file changed since the baseline (SHA-256 differs)",
                scene.file
            ));
        }
        for (knob, value) in &scene.knobs {
            // Size is already reported as the resolution.
            if knob == "size" {
                continue;
            }
            match base.knobs.get(knob) {
                Some(b) if b == value => {}
                Some(b) => warnings.push(format!(
                    "{}: knob {knob} differs: baseline {b}, this run {value}",
                    scene.file
                )),
                None => warnings.push(format!(
                    "{}: knob {knob} is not in the baseline",
                    scene.file
                )),
            }
        }
    }
    warnings
}

/// The comparison of the current row `c` with its baseline row `b`: the
/// ratio of their medians, its interval, and why it is not judged, if so.
fn ratio_row(baseline: &BenchReport, c: &MetricRow, b: &MetricRow) -> RatioRow {
    let usable = b.median > 0.0 && b.median.is_finite() && c.median >= 0.0 && c.median.is_finite();
    let interval = if !usable || c.samples.is_empty() {
        None
    } else if same_values(&c.samples, &b.samples) {
        // One set of frames on both sides (a report compared
        // with itself or a copy): resampling it twice, each
        // side on its own, would invent a difference where
        // there is none. The ratio is its medians'.
        Some(Interval::point(c.median / b.median))
    } else if b.samples.is_empty() {
        ratio_interval(&c.samples, &[b.median])
            .map(|i| around(i, &c.samples, &[b.median], c.median / b.median))
    } else {
        ratio_interval(&c.samples, &b.samples)
            .map(|i| around(i, &c.samples, &b.samples, c.median / b.median))
    };
    RatioRow {
        key: c.key.clone(),
        metric: c.metric,
        baseline: b.median,
        current: c.median,
        ratio: usable.then(|| c.median / b.median),
        interval,
        not_judged: not_judged(baseline, c, b),
    }
}

/// Why the row `c` (baseline row `b`) is not judged, if it is not: too
/// few instructions, or a pass's time below the time floor of its scene,
/// the baseline's empty pass at the scene's resolution (the cheapest pass
/// that timestamps resolve).
fn not_judged(baseline: &BenchReport, c: &MetricRow, b: &MetricRow) -> Option<NotJudged> {
    let time_floor = |scene: &str| -> Option<f64> {
        let s = baseline.scenes.iter().find(|s| s.file == scene)?;
        let empty = baseline.empty_pass(s.resolution)?;
        empty.gpu.as_ref().map(|g| g.ms.median)
    };
    match c.metric {
        Metric::Instructions if b.median < MIN_JUDGED_INSTRUCTIONS => {
            Some(NotJudged::FewInstructions)
        }
        Metric::Time if c.key.pass != CPU_FRAME && c.key.pass != GPU_TOTAL => {
            time_floor(&c.key.scene)
                .filter(|&floor| b.median < floor)
                .map(|_| NotJudged::BelowEmptyPass)
        }
        _ => None,
    }
}

/// Whether `a` and `b` hold the same values, in any order.
fn same_values(a: &[f64], b: &[f64]) -> bool {
    let sorted = |x: &[f64]| {
        let mut v = x.to_vec();
        v.sort_unstable_by(f64::total_cmp);
        v
    };
    a.len() == b.len() && sorted(a) == sorted(b)
}

/// The interval `i` of the ratio of the samples' medians, moved to be
/// about `ratio`, the ratio of the reports' medians: the samples give the
/// interval's relative width, the medians its place. The two agree in
/// every report `bench` writes and every report it loads (a median that
/// is not its samples' is refused on loading); they can differ only in
/// reports built in code.
fn around(i: Interval, a: &[f64], b: &[f64], ratio: f64) -> Interval {
    let median = |x: &[f64]| {
        let mut v = x.to_vec();
        v.sort_unstable_by(f64::total_cmp);
        crate::report::stats::percentile(&v, 50.0)
    };
    let sampled = median(a) / median(b);
    if !(sampled.is_finite() && sampled > 0.0) {
        return i;
    }
    let k = ratio / sampled;
    Interval {
        low: i.low * k,
        high: i.high * k,
    }
}

fn on_off(b: bool) -> &'static str {
    if b {
        "on"
    } else {
        "off"
    }
}
