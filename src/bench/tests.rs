//! Report round-trips and baseline comparison on hand-made reports (no
//! Vulkan needed).

use super::*;
use std::collections::BTreeMap;

fn summary(median: f64) -> Summary {
    Summary::of(&[median * 0.9, median, median * 1.2]).expect("finite")
}

fn row(name: &str, median: f64) -> PassReport {
    PassReport {
        name: name.into(),
        ms: summary(median),
        empty_pass_multiple: None,
    }
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
    let c = compare(&r, &r);
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
    let c = compare(&current, &baseline);
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
    let c = compare(&current, &baseline);
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
    let c = compare(&current, &baseline);
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
    let c = compare(&report(), &baseline);
    let tonemap = c.rows.iter().find(|r| r.key.pass == "tonemap").unwrap();
    assert_eq!(tonemap.ratio, None);
    assert!(c.exceeding(1.0).is_empty());
}

#[test]
fn sha256_matches_a_known_digest() {
    assert_eq!(
        sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
}
