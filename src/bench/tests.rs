//! Report round-trips and baseline comparison on hand-made reports (no
//! Vulkan needed).

use super::*;
use crate::bench::baseline::Verdict;
use std::collections::BTreeMap;

fn summary(median: f64) -> Summary {
    Summary::of(&[median * 0.9, median, median * 1.2]).expect("finite")
}

fn row(name: &str, median: f64) -> PassReport {
    PassReport::timed(name, &[], summary(median))
}

fn report() -> BenchReport {
    let resolution = Resolution {
        width: 64,
        height: 48,
    };
    BenchReport {
        format: FORMAT.into(),
        commit: "abc1234".into(),
        aerial_version: "0.1.0".into(),
        build: "release".into(),
        device: DeviceRecord {
            name: "llvmpipe".into(),
            driver_name: "llvmpipe".into(),
            driver_info: "Mesa".into(),
            driver_version: 1,
            api_version: "1.3.0".into(),
        },
        warmup: 1,
        frames: 3,
        validate: false,
        metrics: vec![Metric::Time],
        empty_passes: vec![EmptyPassReport {
            resolution,
            gpu: Some(row("empty", 0.5)),
            cpu_frame: row(CPU_FRAME, 0.7),
        }],
        scenes: vec![SceneReport {
            file: "a.toml".into(),
            sha256: "00".into(),
            resolution,
            triangles: 12,
            knobs: BTreeMap::from([("shading".to_string(), "phong".to_string())]),
            passes: vec![row("opaque", 2.0), row("tonemap", 1.0)],
            gpu_total: Some(row(GPU_TOTAL, 3.0)),
            cpu_frame: row(CPU_FRAME, 3.5),
            empty_pass_between_frames: Some(row("empty", 0.6)),
            asset_warnings: 1,
        }],
    }
}

#[test]
fn report_round_trips_through_json() {
    let r = report();
    let text = serde_json::to_string(&r).unwrap();
    let back = BenchReport::from_json(&text, Path::new("r.json")).unwrap();
    assert_eq!(r, back);
}

/// Reports written before the between-frames floor still load: their
/// multiples divided by the separate empty-pass run.
#[test]
fn reports_without_the_between_frames_floor_load() {
    let r = report();
    let mut value = serde_json::to_value(&r).unwrap();
    value["scenes"][0]
        .as_object_mut()
        .unwrap()
        .remove("empty_pass_between_frames");
    let back = BenchReport::from_json(&value.to_string(), Path::new("old.json")).unwrap();
    assert_eq!(back.scenes[0].empty_pass_between_frames, None);
    assert_eq!(back.scenes[0].passes, r.scenes[0].passes);
}

/// Reports written before asset warnings were counted still load, with 0.
#[test]
fn reports_without_the_asset_warning_count_load() {
    let r = report();
    let mut value = serde_json::to_value(&r).unwrap();
    assert_eq!(value["scenes"][0]["asset_warnings"], 1);
    value["scenes"][0]
        .as_object_mut()
        .unwrap()
        .remove("asset_warnings");
    let back = BenchReport::from_json(&value.to_string(), Path::new("old.json")).unwrap();
    assert_eq!(back.scenes[0].asset_warnings, 0);
    assert_eq!(back.scenes[0].passes, r.scenes[0].passes);
}

#[test]
fn other_formats_are_rejected_naming_the_field() {
    let mut r = report();
    r.format = "aerial-bench/0".into();
    let text = serde_json::to_string(&r).unwrap();
    let e = BenchReport::from_json(&text, Path::new("old.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("old.json") && e.contains("format"), "{e}");
    let e = BenchReport::from_json("{}", Path::new("x.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("x.json") && e.contains("format"), "{e}");
    let e = BenchReport::from_json("not json", Path::new("y.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("y.json") && e.contains("line 1"), "{e}");
}

#[test]
fn comparing_with_itself_gives_ratio_one_everywhere() {
    let r = report();
    let c = compare(&r, &r, &[Metric::Time]);
    assert_eq!(c.rows.len(), 2 + 4);
    assert!(c.rows.iter().all(|row| row.ratio == Some(1.0)));
    assert!(c.missing.is_empty() && c.new.is_empty() && c.warnings.is_empty());
    assert!(c.exceeding(1.0).is_empty());
}

#[test]
fn a_slower_pass_exceeds_the_ratio() {
    let baseline = report();
    let mut current = report();
    current.scenes[0].passes[0].ms = summary(3.0);
    let c = compare(&current, &baseline, &[Metric::Time]);
    let slow = c.exceeding(1.2);
    assert_eq!(slow.len(), 1);
    assert_eq!(slow[0].key.scene, "a.toml");
    assert_eq!(slow[0].key.pass, "opaque");
    assert!((slow[0].ratio.unwrap() - 1.5).abs() < 1e-12);
}

#[test]
fn missing_and_new_passes_are_listed() {
    let baseline = report();
    let mut current = report();
    current.scenes[0].passes[1].name = "transparent".into();
    let c = compare(&current, &baseline, &[Metric::Time]);
    let key = |pass: &str| RowKey {
        scene: "a.toml".into(),
        pass: pass.into(),
    };
    assert_eq!(c.missing, vec![key("tonemap")]);
    assert_eq!(c.new, vec![key("transparent")]);
}

#[test]
fn device_resolution_and_knob_changes_are_warnings() {
    let baseline = report();
    let mut current = report();
    current.device.name = "other gpu".into();
    current.scenes[0].resolution.width = 128;
    current.scenes[0]
        .knobs
        .insert("shading".into(), "toon".into());
    let c = compare(&current, &baseline, &[Metric::Time]);
    let all = c.warnings.join("\n");
    assert!(all.contains("device differs"), "{all}");
    assert!(all.contains("resolution differs"), "{all}");
    assert!(all.contains("knob shading differs"), "{all}");
    // Still compared: the rows match by scene and pass.
    assert_eq!(c.rows.len(), 6);
}

#[test]
fn a_zero_baseline_has_no_ratio_and_never_fails() {
    let mut baseline = report();
    baseline.scenes[0].passes[1].ms = Summary::of(&[0.0]).unwrap();
    let c = compare(&report(), &baseline, &[Metric::Time]);
    let tonemap = c.rows.iter().find(|r| r.key.pass == "tonemap").unwrap();
    assert_eq!(tonemap.ratio, None);
    assert!(c.exceeding(1.0).is_empty());
}

/// A row with these frame times.
fn sampled(name: &str, samples: &[f64]) -> PassReport {
    PassReport::timed(name, samples, Summary::of(samples).expect("finite"))
}

/// Frame times around `centre` with a ±`spread` fraction of wobble.
fn wobbly(centre: f64, spread: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| centre * (1.0 + spread * ((i * 7 % 11) as f64 / 5.0 - 1.0)))
        .collect()
}

#[test]
fn the_gate_decides_on_the_interval_not_the_point() {
    let mut baseline = report();
    baseline.scenes[0].passes[0] = sampled("opaque", &wobbly(2.0, 0.2, 30));
    let verdict = |current_samples: Vec<f64>| {
        let mut current = report();
        current.scenes[0].passes[0] = sampled("opaque", &current_samples);
        let c = compare(&current, &baseline, &[Metric::Time]);
        let row = c
            .rows
            .iter()
            .find(|r| r.key.pass == "opaque")
            .unwrap()
            .clone();
        (row.verdict(1.25), row)
    };
    // Twice as slow: the whole interval lies above 1.25.
    let (v, row) = verdict(wobbly(4.0, 0.2, 30));
    assert_eq!(v, Verdict::Fail, "{row:?}");
    // The same distribution: the interval holds 1 and stays below 1.25.
    let (v, row) = verdict(wobbly(2.0, 0.2, 30));
    assert_eq!(v, Verdict::Pass, "{row:?}");
    // 25 % slower with ±20 % wobble: the point is at the limit, the
    // interval straddles it.
    let (v, row) = verdict(wobbly(2.5, 0.2, 30));
    assert_eq!(v, Verdict::Inconclusive, "{row:?}");
    let i = row.interval.unwrap();
    assert!(i.low < 1.25 && 1.25 < i.high, "{i}");
}

#[test]
fn instruction_rows_are_compared_only_when_asked_for() {
    let mut baseline = report();
    let mut current = report();
    baseline.scenes[0].passes[0].instructions = CountReport::of(vec![10_000_000; 5]);
    current.scenes[0].passes[0].instructions = CountReport::of(vec![10_300_000; 5]);
    // A row too small to judge: its noise is larger than the gate.
    baseline.scenes[0].passes[1].instructions = CountReport::of(vec![1_000_000; 5]);
    current.scenes[0].passes[1].instructions = CountReport::of(vec![1_100_000; 5]);
    let time_only = compare(&current, &baseline, &[Metric::Time]);
    assert!(time_only.rows.iter().all(|r| r.metric == Metric::Time));
    let c = compare(&current, &baseline, &[Metric::Instructions]);
    assert_eq!(c.rows.len(), 2);
    let small = &c.rows[1];
    assert_eq!(
        small.not_judged,
        Some(crate::bench::baseline::NotJudged::FewInstructions)
    );
    assert_eq!(small.verdict(1.02), Verdict::Pass);
    let row = &c.rows[0];
    assert_eq!(row.not_judged, None);
    assert_eq!(row.metric, Metric::Instructions);
    assert!((row.ratio.unwrap() - 1.03).abs() < 1e-12);
    // Exact counts: the interval is the point, so a 2 % gate is decisive.
    assert_eq!(row.verdict(1.02), Verdict::Fail);
    assert_eq!(row.verdict(1.04), Verdict::Pass);
}

#[test]
fn reports_without_samples_or_metrics_still_load() {
    // A report as written before samples, intervals and metrics existed.
    let mut old = serde_json::to_value(report()).unwrap();
    old.as_object_mut().unwrap().remove("metrics");
    strip_key(&mut old, "median_ci");
    let r = BenchReport::from_json(&old.to_string(), std::path::Path::new("old.json")).unwrap();
    assert_eq!(r.metrics, vec![Metric::Time]);
    assert!(r.scenes[0].passes[0].ms.median_ci.is_none());
}

fn strip_key(v: &mut serde_json::Value, key: &str) {
    match v {
        serde_json::Value::Object(m) => {
            m.remove(key);
            m.values_mut().for_each(|x| strip_key(x, key));
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(|x| strip_key(x, key)),
        _ => {}
    }
}

#[test]
fn sha256_matches_a_known_digest() {
    assert_eq!(
        sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
}

/// A subpass faster than the empty pass is printed but not judged: on a
/// binning driver its timestamps can put the work in a neighbour, so one
/// frame times near zero and its ratio is unbounded. Passes at or above
/// the floor, the totals and the CPU frame are judged.
#[test]
fn time_rows_faster_than_the_empty_pass_are_not_judged() {
    let baseline = report();
    let mut current = report();
    current.scenes[0].passes[0] = row("opaque", 2.0);
    current.scenes[0].passes.push(row("readback", 40.0));
    let mut base = baseline.clone();
    base.scenes[0].passes.push(row("readback", 0.2));
    let c = compare(&current, &base, &[Metric::Time]);
    let find = |pass: &str| {
        c.rows
            .iter()
            .find(|r| r.key.scene == "a.toml" && r.key.pass == pass)
            .unwrap()
    };
    use crate::bench::baseline::NotJudged;
    assert_eq!(find("readback").not_judged, Some(NotJudged::BelowEmptyPass));
    // 200x slower, but under the floor in the baseline: not a verdict.
    assert_eq!(find("readback").verdict(1.02), Verdict::Pass);
    for judged in ["opaque", "tonemap", GPU_TOTAL, CPU_FRAME] {
        assert_eq!(find(judged).not_judged, None, "{judged}");
    }
}

/// A report naming a scene, an empty-pass resolution or a scene's pass
/// twice is refused on loading: a gate would otherwise match the first
/// entry and silently ignore the second.
#[test]
fn reports_with_duplicate_entries_are_refused() {
    let mut twice = report();
    twice.scenes.push(twice.scenes[0].clone());
    let text = serde_json::to_string(&twice).unwrap();
    let e = BenchReport::from_json(&text, Path::new("b.json"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("b.json") && e.contains("scenes[1]") && e.contains("a.toml"),
        "{e}"
    );

    let mut pass_twice = report();
    pass_twice.scenes[0].passes.push(row("opaque", 2.0));
    let text = serde_json::to_string(&pass_twice).unwrap();
    let e = BenchReport::from_json(&text, Path::new("b.json"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("scenes[0].passes[2]") && e.contains("opaque"),
        "{e}"
    );

    let mut empty_twice = report();
    empty_twice
        .empty_passes
        .push(empty_twice.empty_passes[0].clone());
    let text = serde_json::to_string(&empty_twice).unwrap();
    let e = BenchReport::from_json(&text, Path::new("b.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("empty_passes[1]") && e.contains("64x48"), "{e}");
}

/// A report with frames kept in every row, as `bench` writes them.
fn sampled_report() -> BenchReport {
    let mut r = report();
    let fill = |row: &mut PassReport, centre: f64| {
        *row = sampled(&row.name.clone(), &wobbly(centre, 0.3, 9));
    };
    fill(r.empty_passes[0].gpu.as_mut().unwrap(), 0.5);
    fill(&mut r.empty_passes[0].cpu_frame, 0.7);
    let s = &mut r.scenes[0];
    fill(&mut s.passes[0], 2.0);
    fill(&mut s.passes[1], 1.0);
    fill(s.gpu_total.as_mut().unwrap(), 3.0);
    fill(&mut s.cpu_frame, 3.5);
    fill(s.empty_pass_between_frames.as_mut().unwrap(), 0.6);
    r
}

/// A report compared with itself (or a copy) passes at any limit of at
/// least 1: the frames are one measurement on both sides, so each ratio
/// is exactly 1, not an interval of resampled noise around it.
#[test]
fn a_report_equal_to_its_baseline_passes() {
    let r = sampled_report();
    let mut counted = r.clone();
    counted.scenes[0].passes[0].instructions =
        CountReport::of(vec![10_000_000, 10_002_000, 9_998_000, 10_001_000]);
    let both = [Metric::Time, Metric::Instructions];
    for (r, metrics) in [
        (&r, &both[..1]),
        (&counted, &both[..1]),
        (&counted, &both[..]),
        (&counted, &both[1..]),
    ] {
        let c = compare(r, &r.clone(), metrics);
        assert!(!c.rows.is_empty());
        for row in &c.rows {
            assert_eq!(row.ratio, Some(1.0), "{row:?}");
            let i = row.interval.expect("an interval");
            assert_eq!((i.low, i.high), (1.0, 1.0), "{row:?}");
        }
        assert_eq!(c.verdict(1.0), Verdict::Pass);
        c.judgeable(metrics).unwrap();
    }
    // The same frames in another order are the same measurement.
    let r = sampled_report();
    let mut shuffled = r.clone();
    shuffled.scenes[0].passes[0].samples_ms.reverse();
    let c = compare(&shuffled, &r, &[Metric::Time]);
    assert_eq!(c.verdict(1.0), Verdict::Pass);
    // One frame changed: an interval again, which a limit of 1 straddles.
    let mut other = r.clone();
    other.scenes[0].passes[0].samples_ms[0] *= 1.01;
    let c = compare(&other, &r, &[Metric::Time]);
    let opaque = c.rows.iter().find(|r| r.key.pass == "opaque").unwrap();
    assert_eq!(opaque.verdict(1.0), Verdict::Inconclusive, "{opaque:?}");
}

/// Reports are checked on loading: frames no measurement gives are
/// refused, naming the file, the field and the row, however the report
/// was edited. (Medians are judged as stated; the gate refuses those it
/// cannot divide by: see the next tests.)
#[test]
fn reports_with_impossible_values_are_refused_naming_the_field() {
    type Edit = fn(&mut serde_json::Value);
    let cases: [(Edit, &str); 8] = [
        (
            |v| v["scenes"][0]["gpu_total"]["samples_ms"][3] = (-2.5).into(),
            "scenes[0].gpu_total.samples_ms[3]: -2.5 is negative",
        ),
        (
            |v| v["scenes"][0]["passes"][1]["samples_ms"][0] = (-1e-300).into(),
            "scenes[0].passes[1].samples_ms[0]: -1e-300 is negative",
        ),
        (
            |v| v["scenes"][0]["cpu_frame"]["samples_ms"][0] = 0.0.into(),
            "scenes[0].cpu_frame.samples_ms[0]: 0; this row always costs something",
        ),
        (
            |v| v["empty_passes"][0]["gpu"]["samples_ms"][8] = 0.0.into(),
            "empty_passes[0].gpu.samples_ms[8]: 0; this row always costs something",
        ),
        (
            |v| v["empty_passes"][0]["cpu_frame"]["samples_ms"][1] = 1e-9.into(),
            "empty_passes[0].cpu_frame.samples_ms[1]: 1e-9 ms is shorter than 1 ns",
        ),
        (
            |v| v["scenes"][0]["passes"][0]["ms"]["count"] = 4.into(),
            "scenes[0].passes[0].ms.count: 4, but samples_ms holds 9 values",
        ),
        (
            |v| v["scenes"][0]["passes"][0]["ms"]["count"] = 0.into(),
            "scenes[0].passes[0].ms.count: 0",
        ),
        (
            |v| v["scenes"][0]["passes"][0]["empty_pass_multiple"] = (-3.0).into(),
            "scenes[0].passes[0].empty_pass_multiple: -3 is negative",
        ),
    ];
    for (edit, expected) in cases {
        let mut v = serde_json::to_value(sampled_report()).unwrap();
        edit(&mut v);
        let e = BenchReport::from_json(&v.to_string(), Path::new("base.json"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("base.json: ") && e.contains(expected),
            "expected '{expected}' in: {e}"
        );
    }
    // Counts: negative ones are no u64, and 0 is refused where a row
    // always costs something.
    let mut counted = sampled_report();
    counted.scenes[0].gpu_total.as_mut().unwrap().instructions = CountReport::of(vec![0, 0, 0]);
    let e = BenchReport::from_json(
        &serde_json::to_string(&counted).unwrap(),
        Path::new("c.json"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("scenes[0].gpu_total.instructions.samples[0]: 0"),
        "{e}"
    );
    let mut v = serde_json::to_value(sampled_report()).unwrap();
    v["scenes"][0]["passes"][0]["instructions"] =
        serde_json::to_value(CountReport::of(vec![5, 6, 7])).unwrap();
    v["scenes"][0]["passes"][0]["instructions"]["samples"][1] = (-6).into();
    let e = BenchReport::from_json(&v.to_string(), Path::new("c.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("instructions.samples[1]"), "{e}");
    // A pass may count 0 (a difference of prefixes), and a report as
    // `bench` writes it loads.
    let mut fine = sampled_report();
    fine.scenes[0].passes[1].instructions = CountReport::of(vec![0, 0, 0]);
    let text = serde_json::to_string(&fine).unwrap();
    assert_eq!(
        BenchReport::from_json(&text, Path::new("f.json")).unwrap(),
        fine
    );
}

/// A gate must judge something of each metric it claims: a comparison
/// whose instruction rows are all too small to resolve, or that lacks the
/// metric altogether, is an error; so is one with a judged row it cannot
/// divide. A baseline's empty pass, however slow, never hides the frame:
/// the GPU total and the CPU frame are always judged.
#[test]
fn a_gate_that_cannot_judge_its_metric_is_an_error() {
    use crate::bench::baseline::{NotJudged, Unjudgeable};
    let current = sampled_report();
    // The baseline's empty pass slower than every pass of the scene.
    let mut slow_floor = sampled_report();
    *slow_floor.empty_passes[0].gpu.as_mut().unwrap() = sampled("empty", &wobbly(500.0, 0.1, 9));
    let c = compare(&current, &slow_floor, &[Metric::Time]);
    for row in c.rows.iter().filter(|r| r.key.scene == "a.toml") {
        let pass = row.key.pass.as_str();
        let judged = pass == GPU_TOTAL || pass == CPU_FRAME;
        let expected = (!judged).then_some(NotJudged::BelowEmptyPass);
        assert_eq!(row.not_judged, expected, "{row:?}");
    }
    c.judgeable(&[Metric::Time]).unwrap();
    // Instructions asked for, but no row has them on both sides.
    let c = compare(&current, &current, &[Metric::Time, Metric::Instructions]);
    let e = c
        .judgeable(&[Metric::Time, Metric::Instructions])
        .unwrap_err();
    assert!(matches!(e, Unjudgeable::MetricMissing { .. }), "{e}");
    assert!(e.to_string().contains("--metric instructions"), "{e}");
    // Instruction rows all under the resolvable size.
    let mut small = sampled_report();
    for p in &mut small.scenes[0].passes {
        p.instructions = CountReport::of(vec![1_000_000, 1_000_100, 1_000_050]);
    }
    let c = compare(&small, &small, &[Metric::Instructions]);
    let e = c.judgeable(&[Metric::Instructions]).unwrap_err();
    assert!(e.to_string().contains("under 3.5e6 instructions"), "{e}");
    // Nothing matched, or only the empty passes.
    let mut elsewhere = sampled_report();
    elsewhere.scenes[0].file = "b.toml".into();
    let c = compare(&current, &elsewhere, &[Metric::Time]);
    assert_eq!(
        c.judgeable(&[Metric::Time]),
        Err(Unjudgeable::OnlyEmptyPasses)
    );
    elsewhere.empty_passes.clear();
    let c = compare(&current, &elsewhere, &[Metric::Time]);
    assert_eq!(
        c.judgeable(&[Metric::Time]),
        Err(Unjudgeable::NothingMatched)
    );
    // Medians edited (frames kept), of the scenes or of every row, and
    // the floor's: a median of 0 or below is refused, any other is judged
    // as stated (the frame's total among them), never hidden under the
    // floor.
    fn scene_medians(r: &mut BenchReport, to: f64) {
        let s = &mut r.scenes[0];
        for row in s
            .passes
            .iter_mut()
            .chain(&mut s.gpu_total)
            .chain([&mut s.cpu_frame])
        {
            row.ms.median = to;
        }
    }
    fn every_median(r: &mut BenchReport, to: f64) {
        scene_medians(r, to);
        let e = &mut r.empty_passes[0];
        e.gpu.as_mut().unwrap().ms.median = to;
        e.cpu_frame.ms.median = to;
        let floor = r.scenes[0].empty_pass_between_frames.as_mut().unwrap();
        floor.ms.median = to;
    }
    fn floor_median(r: &mut BenchReport, to: f64) {
        r.empty_passes[0].gpu.as_mut().unwrap().ms.median = to;
    }
    type Edit = fn(&mut BenchReport, f64);
    for (edit, to) in [
        (scene_medians as Edit, 0.0),
        (scene_medians, -1.0),
        (every_median, 0.0),
        (every_median, -1.0),
    ] {
        let mut baseline = sampled_report();
        edit(&mut baseline, to);
        let c = compare(&current, &baseline, &[Metric::Time]);
        let e = c.judgeable(&[Metric::Time]).unwrap_err().to_string();
        assert!(e.contains("no usable baseline median"), "{to}: {e}");
        assert!(e.contains("a.toml / gpu total (baseline"), "{to}: {e}");
    }
    for (edit, to, verdict) in [
        (scene_medians as Edit, 1e-300, Verdict::Fail),
        (floor_median, 1e300, Verdict::Pass),
    ] {
        let mut baseline = sampled_report();
        edit(&mut baseline, to);
        let c = compare(&current, &baseline, &[Metric::Time]);
        c.judgeable(&[Metric::Time]).unwrap();
        let total = c.rows.iter().find(|r| r.key.pass == GPU_TOTAL).unwrap();
        assert_eq!(total.not_judged, None, "{to}");
        assert_eq!(c.verdict(1.5), verdict, "{to}");
    }
    // A median of this run below 0 (an edited report) is not compared.
    let mut odd = sampled_report();
    odd.scenes[0].passes[0].ms.median = -1.0;
    let c = compare(&odd, &current, &[Metric::Time]);
    let e = c.judgeable(&[Metric::Time]).unwrap_err();
    assert!(
        matches!(e, Unjudgeable::NoUsableCurrentMedian { .. }),
        "{e}"
    );
    assert!(
        e.to_string().contains("a.toml / opaque (this run -1)"),
        "{e}"
    );
    // A device without timestamps: CPU frame rows are all there is, and
    // they are judged.
    let mut no_timestamps = sampled_report();
    no_timestamps.empty_passes[0].gpu = None;
    no_timestamps.scenes[0].passes.clear();
    no_timestamps.scenes[0].gpu_total = None;
    no_timestamps.scenes[0].empty_pass_between_frames = None;
    let c = compare(&no_timestamps, &no_timestamps, &[Metric::Time]);
    c.judgeable(&[Metric::Time]).unwrap();
}
