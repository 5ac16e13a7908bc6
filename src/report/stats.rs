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
//! # Confidence intervals
//!
//! [`Summary::median_ci`] is a distribution-free 95 % interval for the
//! median: the order statistics `x[j]`, `x[k]` with the narrowest ranks
//! symmetric about the middle such that the number of samples below the
//! true median, Binomial(n, 1/2), falls in `j..k` with probability at least
//! 0.95. It assumes only that frames are independent draws of one
//! distribution; frame times are skewed and have outliers, where a normal
//! interval would mislead. Below 6 samples no such pair reaches 95 %; the
//! interval is then `[min, max]` and [`median_interval`] says its coverage.
//!
//! [`ratio_interval`] is the 95 % interval of a ratio of two medians, by a
//! percentile bootstrap (2,000 resamples of each side, a fixed seed, so the
//! same samples always give the same interval).
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
    /// 95 % confidence interval of the median (see the module docs);
    /// absent in reports written before it was added.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub median_ci: Option<Interval>,
}

/// A closed interval `[low, high]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    pub low: f64,
    pub high: f64,
}

impl Interval {
    /// The one-point interval.
    pub fn point(x: f64) -> Interval {
        Interval { low: x, high: x }
    }
}

impl std::fmt::Display for Interval {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[{:.4}, {:.4}]", self.low, self.high)
    }
}

/// The distribution-free interval for the median of `sorted` (ascending,
/// non-empty) and its exact coverage probability: the pair of order
/// statistics `x[j]`, `x[n-1-j]` with the largest `j` whose coverage,
/// P(j < B <= n-1-j) for B ~ Binomial(n, 1/2), is at least 0.95; `[min,
/// max]` (coverage 1 - 2^(1-n)) when even that falls short.
pub fn median_interval(sorted: &[f64]) -> (Interval, f64) {
    let n = sorted.len();
    // P(B <= i) for B ~ Binomial(n, 1/2), accumulated in f64: exact
    // enough for any frame count a benchmark takes (n <= 10^6).
    let mut pmf = vec![0.0f64; n + 1];
    let mut log_choose = 0.0f64;
    for (i, p) in pmf.iter_mut().enumerate() {
        if i > 0 {
            log_choose += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        *p = (log_choose - n as f64 * std::f64::consts::LN_2).exp();
    }
    let coverage = |j: usize| -> f64 {
        // Samples below the median in j+1..=n-1-j  <=>  x[j] <= m <= x[n-1-j].
        pmf[j + 1..n - j].iter().sum()
    };
    let mut best = 0;
    for j in 0..n / 2 {
        if n - 1 - j > j && coverage(j) >= 0.95 {
            best = j;
        } else {
            break;
        }
    }
    let interval = Interval {
        low: sorted[best],
        high: sorted[n - 1 - best],
    };
    let c = if n >= 2 { coverage(best) } else { 0.0 };
    (interval, c)
}

/// The 95 % percentile-bootstrap interval of median(`a`) / median(`b`),
/// with a fixed seed (see the module docs). `None` when either side is
/// empty or a resampled median of `b` is not positive.
pub fn ratio_interval(a: &[f64], b: &[f64]) -> Option<Interval> {
    const RESAMPLES: usize = 2000;
    if a.is_empty() || b.is_empty() {
        return None;
    }
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    // splitmix64: small, fast and good enough to pick indices.
    let mut next = move |n: usize| -> usize {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z % n as u64) as usize
    };
    let mut resample = |x: &[f64], buf: &mut Vec<f64>| -> f64 {
        buf.clear();
        buf.extend((0..x.len()).map(|_| x[next(x.len())]));
        buf.sort_unstable_by(f64::total_cmp);
        percentile(buf, 50.0)
    };
    let (mut ba, mut bb) = (Vec::new(), Vec::new());
    let mut ratios = Vec::with_capacity(RESAMPLES);
    for _ in 0..RESAMPLES {
        let ma = resample(a, &mut ba);
        let mb = resample(b, &mut bb);
        if mb.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        ratios.push(ma / mb);
    }
    ratios.sort_unstable_by(f64::total_cmp);
    Some(Interval {
        low: percentile(&ratios, 2.5),
        high: percentile(&ratios, 97.5),
    })
}

impl Summary {
    /// The statistics by the names a report's JSON gives them, for checks
    /// that go through each of them.
    pub fn named(&self) -> [(&'static str, f64); 6] {
        [
            ("min", self.min),
            ("median", self.median),
            ("p95", self.p95),
            ("max", self.max),
            ("mean", self.mean),
            ("std_dev", self.std_dev),
        ]
    }

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
            median_ci: Some(median_interval(&sorted).0),
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
    use super::{median_interval, ratio_interval};

    #[test]
    fn median_interval_ranks_match_the_binomial_table() {
        // n = 10: x(2)..x(9) (1-based), coverage 1 - 2 * 11/1024 = 0.97852;
        // the next pair in covers only 1 - 2 * 56/1024 = 0.89063.
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        let (ci, coverage) = median_interval(&x);
        assert_eq!((ci.low, ci.high), (1.0, 8.0));
        assert!((coverage - (1.0 - 22.0 / 1024.0)).abs() < 1e-12);
        // n = 5 cannot reach 95 %: [min, max] at 1 - 2/32.
        let (ci, coverage) = median_interval(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!((ci.low, ci.high), (1.0, 5.0));
        assert!((coverage - 0.9375).abs() < 1e-12);
    }

    #[test]
    fn median_interval_covers_the_true_median_as_often_as_it_says() {
        // Exponential samples (skewed, like frame times), true median ln 2.
        let mut state = 12345u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let n = 30;
        let trials = 4000;
        let mut hits = 0;
        let mut stated = 0.0;
        for _ in 0..trials {
            let mut x: Vec<f64> = (0..n).map(|_| -(1.0 - uniform()).ln()).collect();
            x.sort_unstable_by(f64::total_cmp);
            let (ci, c) = median_interval(&x);
            stated = c;
            if ci.low <= std::f64::consts::LN_2 && std::f64::consts::LN_2 <= ci.high {
                hits += 1;
            }
        }
        let observed = hits as f64 / trials as f64;
        assert!(stated >= 0.95);
        // Binomial standard error at 4000 trials is about 0.003.
        assert!((observed - stated).abs() < 0.015, "{observed} vs {stated}");
    }

    #[test]
    fn ratio_interval_holds_the_ratio_and_shrinks_to_a_point_for_constants() {
        let a: Vec<f64> = (0..40).map(|i| 2.0 + 0.01 * f64::from(i % 7)).collect();
        let b: Vec<f64> = (0..40).map(|i| 1.0 + 0.005 * f64::from(i % 5)).collect();
        let ci = ratio_interval(&a, &b).unwrap();
        assert!(ci.low < ci.high);
        assert!(ci.low <= 2.03 / 1.01 && 2.03 / 1.01 <= ci.high, "{ci}");
        let ci = ratio_interval(&[103.0; 5], &[100.0; 5]).unwrap();
        assert_eq!((ci.low, ci.high), (1.03, 1.03));
        assert!(ratio_interval(&[1.0], &[0.0]).is_none());
        assert!(ratio_interval(&[], &[1.0]).is_none());
        // Deterministic: the same samples give the same interval.
        assert_eq!(ratio_interval(&a, &b), ratio_interval(&a, &b));
    }

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
