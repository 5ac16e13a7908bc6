//! Summary statistics for benchmark samples (frame times, pass timings, ...).
//!
//! # Percentile definition
//!
//! Percentiles use linear interpolation between order statistics (Hyndman &
//! Fan type 7, the default of NumPy, R and spreadsheet `PERCENTILE.INC`). For
//! `n` sorted samples `x[0] <= ... <= x[n-1]` and a percentile `p` in
//! `[0, 100]`:
//!
//! ```text
//! h = (n - 1) * p / 100
//! P(p) = x[floor(h)] + (h - floor(h)) * (x[floor(h) + 1] - x[floor(h)])
//! ```
//!
//! so `P(0)` is the minimum, `P(100)` the maximum and `P(50)` the usual median
//! (mean of the two middle samples when `n` is even). This definition is
//! continuous in `p` and never invents values outside the sample range, which
//! keeps p95 stable when a run gains or loses a single sample.
//!
//! # Standard deviation
//!
//! [`Summary::std_dev`] is the *sample* standard deviation (divisor `n - 1`,
//! Bessel's correction), because benchmark runs are a sample of the frame-time
//! distribution, not the whole population. It is defined as 0 for one sample.
//!
//! # Per-pass GPU times
//!
//! [`summarise_passes`] turns the per-frame pass times of a run into one
//! [`Summary`] per pass plus one of the per-frame total, the same way for
//! `aerial render --frames`, `aerial bench` and `aerial sweep`.

use serde::{Deserialize, Serialize};

/// Descriptive statistics of a set of samples; see the module docs for the
/// exact percentile and standard deviation definitions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Number of samples.
    pub count: usize,
    /// Smallest sample.
    pub min: f64,
    /// 50th percentile.
    pub median: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Largest sample.
    pub max: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample standard deviation (divisor `n - 1`); 0 when `count == 1`.
    pub std_dev: f64,
}

impl Summary {
    /// Summarises `samples` (any order).
    ///
    /// Returns `None` for an empty slice and for any non-finite sample (NaN or
    /// ±infinity) instead of skipping it: a NaN frame time means the
    /// measurement is broken, and quietly dropping it would make a broken
    /// benchmark look healthy. Rejecting infinities as well keeps every field
    /// finite, so a `Summary` always round-trips through JSON (which has no
    /// representation for NaN or infinity).
    pub fn of(samples: &[f64]) -> Option<Summary> {
        if samples.is_empty() || samples.iter().any(|s| !s.is_finite()) {
            return None;
        }
        let mut sorted = samples.to_vec();
        // All values are finite here, so total_cmp agrees with numeric order.
        sorted.sort_unstable_by(f64::total_cmp);

        let count = sorted.len();
        let n = count as f64;
        let mean = sorted.iter().sum::<f64>() / n;
        // Two-pass variance: summing squared deviations from the mean avoids
        // the catastrophic cancellation of the sum-of-squares formula when
        // samples are large and close together (e.g. frame times in ns).
        let std_dev = if count > 1 {
            let ss: f64 = sorted.iter().map(|x| (x - mean) * (x - mean)).sum();
            (ss / (n - 1.0)).sqrt()
        } else {
            0.0
        };

        Some(Summary {
            count,
            min: sorted[0],
            median: percentile(&sorted, 50.0),
            p95: percentile(&sorted, 95.0),
            max: sorted[count - 1],
            mean,
            std_dev,
        })
    }
}

/// Each pass's GPU time over a run's frames, and the per-frame total.
#[derive(Debug, Clone, PartialEq)]
pub struct PassSummaries {
    /// One per pass, in the order of the names given.
    pub passes: Vec<(String, Summary)>,
    /// The sum of the pass times of each frame.
    pub total: Summary,
}

/// Why [`summarise_passes`] could not summarise a run's pass times.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PassTimesError {
    #[error("pass {0}: its times are not all finite numbers")]
    Pass(String),
    #[error("the per-frame sum of the pass times is not finite")]
    Total,
}

/// Summarises per-frame pass times: `frames` holds one slice per frame,
/// with one time per name in `names`, in that order.
///
/// Returns `Ok(None)` when there is nothing to summarise: no passes, no
/// frames, or a frame without a time for every pass. A device without
/// timestamp queries gives every frame an empty slice; a partial frame would
/// be a driver bug, and is treated as "no timestamps" too rather than
/// pairing times with the wrong pass. A non-finite time is an error naming
/// the pass (see [`Summary::of`] for why it is not skipped).
pub fn summarise_passes<'a>(
    names: &[impl AsRef<str>],
    frames: impl IntoIterator<Item = &'a [f64]>,
) -> Result<Option<PassSummaries>, PassTimesError> {
    let frames: Vec<&[f64]> = frames.into_iter().collect();
    if names.is_empty() || frames.is_empty() || frames.iter().any(|f| f.len() != names.len()) {
        return Ok(None);
    }
    let passes = names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let samples: Vec<f64> = frames.iter().map(|f| f[i]).collect();
            Summary::of(&samples)
                .map(|s| (name.as_ref().to_string(), s))
                .ok_or_else(|| PassTimesError::Pass(name.as_ref().to_string()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let totals: Vec<f64> = frames.iter().map(|f| f.iter().sum()).collect();
    let total = Summary::of(&totals).ok_or(PassTimesError::Total)?;
    Ok(Some(PassSummaries { passes, total }))
}

/// Percentile `p` (in `[0, 100]`) of `sorted`, which must be sorted
/// ascending, by linear interpolation between order statistics (see the module
/// docs for the formula).
///
/// `p` outside `[0, 100]` is clamped to the nearest end. Returns NaN for an
/// empty slice or a NaN `p`, since there is no meaningful value to return and
/// this function must not panic on caller data.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() || p.is_nan() {
        return f64::NAN;
    }
    let last = sorted.len() - 1;
    let h = last as f64 * (p.clamp(0.0, 100.0) / 100.0);
    // h is in [0, last], so the truncating cast is floor() and in range.
    let lo = (h.floor() as usize).min(last);
    let hi = (lo + 1).min(last);
    let frac = h - lo as f64;
    if frac == 0.0 {
        // Exact order statistic: avoids 0 * inf style artefacts and returns
        // the sample itself bit-for-bit.
        sorted[lo]
    } else {
        sorted[lo] + frac * (sorted[hi] - sorted[lo])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    #[test]
    fn empty_is_none() {
        assert_eq!(Summary::of(&[]), None);
    }

    #[test]
    fn non_finite_samples_are_rejected() {
        assert_eq!(Summary::of(&[1.0, f64::NAN, 3.0]), None);
        assert_eq!(Summary::of(&[1.0, f64::INFINITY]), None);
        assert_eq!(Summary::of(&[f64::NEG_INFINITY]), None);
    }

    #[test]
    fn single_sample() {
        let s = Summary::of(&[7.5]).unwrap();
        assert_eq!(s.count, 1);
        assert_eq!(
            (s.min, s.median, s.p95, s.max, s.mean),
            (7.5, 7.5, 7.5, 7.5, 7.5)
        );
        assert_eq!(s.std_dev, 0.0);
    }

    #[test]
    fn four_samples_by_hand() {
        // median: h = 3 * 0.5 = 1.5 -> 2 + 0.5 * (3 - 2) = 2.5
        // p95:    h = 3 * 0.95 = 2.85 -> 3 + 0.85 * (4 - 3) = 3.85
        // var = (2.25 + 0.25 + 0.25 + 2.25) / 3 = 5/3
        let s = Summary::of(&[4.0, 1.0, 3.0, 2.0]).unwrap();
        assert_eq!(s.count, 4);
        assert_eq!(s.min, 1.0);
        assert_eq!(s.max, 4.0);
        assert!(close(s.median, 2.5));
        assert!(close(s.p95, 3.85));
        assert!(close(s.mean, 2.5));
        assert!(close(s.std_dev, (5.0f64 / 3.0).sqrt()));
    }

    #[test]
    fn five_unsorted_samples_by_hand() {
        // sorted: 10 20 30 40 100
        // median: h = 2 -> 30; p95: h = 3.8 -> 40 + 0.8 * 60 = 88
        // mean = 40; deviations -30 -20 -10 0 60 -> ss = 900+400+100+0+3600 = 5000
        // var = 5000 / 4 = 1250
        let s = Summary::of(&[100.0, 30.0, 10.0, 40.0, 20.0]).unwrap();
        assert!(close(s.median, 30.0));
        assert!(close(s.p95, 88.0));
        assert!(close(s.mean, 40.0));
        assert!(close(s.std_dev, 1250.0f64.sqrt()));
    }

    #[test]
    fn two_samples() {
        // p95: h = 0.95 -> 1 + 0.95 * 2 = 2.9; var = (1 + 1) / 1 = 2
        let s = Summary::of(&[3.0, 1.0]).unwrap();
        assert!(close(s.median, 2.0));
        assert!(close(s.p95, 2.9));
        assert!(close(s.std_dev, 2.0f64.sqrt()));
    }

    #[test]
    fn percentile_edges() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(percentile(&v, 0.0), 1.0);
        assert_eq!(percentile(&v, 100.0), 5.0);
        assert_eq!(percentile(&v, 25.0), 2.0);
        assert!(close(percentile(&v, 10.0), 1.4));
        // Out-of-range p is clamped, not a panic.
        assert_eq!(percentile(&v, -5.0), 1.0);
        assert_eq!(percentile(&v, 250.0), 5.0);
        assert!(percentile(&v, f64::NAN).is_nan());
        assert!(percentile(&[], 50.0).is_nan());
        assert_eq!(percentile(&[42.0], 99.0), 42.0);
    }

    #[test]
    fn large_offset_is_numerically_stable() {
        // The naive sum-of-squares formula loses all digits here.
        let base = 1e9;
        let s = Summary::of(&[base + 4.0, base + 7.0, base + 13.0, base + 16.0]).unwrap();
        // deviations -6 -3 3 6 -> ss = 90, var = 30
        assert!((s.std_dev - 30.0f64.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn pass_summaries_by_hand() {
        let frames = [vec![1.0, 10.0], vec![3.0, 30.0], vec![2.0, 20.0]];
        let s = summarise_passes(&["opaque", "tonemap"], frames.iter().map(Vec::as_slice))
            .unwrap()
            .unwrap();
        let names: Vec<&str> = s.passes.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["opaque", "tonemap"]);
        assert_eq!(s.passes[0].1, Summary::of(&[1.0, 3.0, 2.0]).unwrap());
        assert_eq!(s.passes[1].1, Summary::of(&[10.0, 30.0, 20.0]).unwrap());
        assert_eq!(s.total, Summary::of(&[11.0, 33.0, 22.0]).unwrap());
    }

    #[test]
    fn pass_summaries_without_timestamps_are_none() {
        let none = |names: &[&str], frames: &[Vec<f64>]| {
            summarise_passes(names, frames.iter().map(Vec::as_slice)).unwrap()
        };
        // No timestamps: every frame empty.
        assert_eq!(none(&["opaque"], &[vec![], vec![]]), None);
        // A partial frame.
        assert_eq!(none(&["a", "b"], &[vec![1.0, 2.0], vec![1.0]]), None);
        assert_eq!(none(&["opaque"], &[]), None);
        assert_eq!(none(&[], &[vec![]]), None);
    }

    #[test]
    fn pass_summaries_name_a_non_finite_pass() {
        let frames = [vec![1.0, f64::NAN]];
        let e = summarise_passes(&["opaque", "tonemap"], frames.iter().map(Vec::as_slice));
        assert_eq!(e, Err(PassTimesError::Pass("tonemap".into())));
        let frames = [vec![f64::MAX, f64::MAX]];
        let e = summarise_passes(&["a", "b"], frames.iter().map(Vec::as_slice));
        assert_eq!(e, Err(PassTimesError::Total));
    }

    #[test]
    fn serde_round_trip() {
        let s = Summary::of(&[1.0, 2.0, 3.0]).unwrap();
        let json = serde_json::to_string(&s).unwrap();
        assert!(json.contains("\"p95\""));
        let back: Summary = serde_json::from_str(&json).unwrap();
        assert_eq!(s, back);
    }
}
