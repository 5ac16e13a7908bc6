//! Comparing a benchmark run with a stored baseline, for CI.
//!
//! Rows are matched by scene file (as given on the command line) and row
//! name (a pass, `gpu total` or `cpu frame`); empty-pass rows by resolution.
//! Each matched row gets the ratio of medians `current / baseline`, so a
//! slowdown is judged relative to the same machine's earlier figure rather
//! than against an absolute time that only holds on one machine.
//!
//! Differences that make the comparison less meaningful (another device or
//! driver, another resolution, a changed scene file, other knob settings,
//! another build profile) are reported as warnings, not failures: CI
//! decides what to do with them. Rows present on one side only are listed.

use super::report::{BenchReport, PassReport, Resolution};
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
    pub baseline_ms: f64,
    pub current_ms: f64,
    /// `current_ms / baseline_ms`; `None` when the baseline median is not
    /// positive (a zero-length interval has no meaningful ratio).
    pub ratio: Option<f64>,
}

impl RatioRow {
    /// Whether this row is slower than `max_ratio` allows.
    pub fn exceeds(&self, max_ratio: f64) -> bool {
        self.ratio.is_some_and(|r| r > max_ratio)
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
    /// The rows whose ratio is above `max_ratio`.
    pub fn exceeding(&self, max_ratio: f64) -> Vec<&RatioRow> {
        self.rows.iter().filter(|r| r.exceeds(max_ratio)).collect()
    }
}

/// The key of the empty pass at `resolution`.
pub fn empty_pass_scene(resolution: Resolution) -> String {
    format!("empty pass {resolution}")
}

/// Every timed row of a report with its median, in report order: the empty
/// passes, then each scene's passes and totals.
pub fn rows(report: &BenchReport) -> Vec<(RowKey, f64)> {
    let mut out = Vec::new();
    let mut push = |scene: &str, row: &PassReport| {
        out.push((
            RowKey {
                scene: scene.to_string(),
                pass: row.name.clone(),
            },
            row.ms.median,
        ));
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

/// Compares `current` with `baseline`.
pub fn compare(current: &BenchReport, baseline: &BenchReport) -> BaselineComparison {
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

    let current_rows = rows(current);
    let baseline_rows = rows(baseline);
    let mut matched = Vec::new();
    let mut new = Vec::new();
    for (key, current_ms) in &current_rows {
        match baseline_rows.iter().find(|(k, _)| k == key) {
            Some((_, baseline_ms)) => matched.push(RatioRow {
                key: key.clone(),
                baseline_ms: *baseline_ms,
                current_ms: *current_ms,
                ratio: (*baseline_ms > 0.0 && baseline_ms.is_finite() && current_ms.is_finite())
                    .then(|| current_ms / baseline_ms),
            }),
            None => new.push(key.clone()),
        }
    }
    let missing = baseline_rows
        .into_iter()
        .filter(|(k, _)| !current_rows.iter().any(|(c, _)| c == k))
        .map(|(k, _)| k)
        .collect();
    BaselineComparison {
        rows: matched,
        missing,
        new,
        warnings,
    }
}

fn on_off(b: bool) -> &'static str {
    if b {
        "on"
    } else {
        "off"
    }
}
