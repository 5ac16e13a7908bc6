//! `aerial sweep` end to end: a tiny sweep under validation, checked through
//! the files it writes, and the errors for bad knobs.

use crate::common;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Output;

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/shading_models.toml")
}

fn sweep(out_dir: &Path, knobs: &[&str], extra: &[&str]) -> Output {
    let mut cmd = common::aerial();
    cmd.arg("sweep").arg(scene()).arg("--out-dir").arg(out_dir);
    for k in knobs {
        cmd.args(["--knob", k]);
    }
    cmd.args(extra).output().unwrap()
}

fn num(row: &HashMap<String, String>, column: &str) -> f64 {
    row[column]
        .parse()
        .unwrap_or_else(|e| panic!("{column} = {:?}: {e}", row[column]))
}

/// Each row of `dir/sweep.json` as (GPU median, rmse, pareto flag), at
/// full precision: the CSV rounds times to 0.1 us, and two times equal
/// there may differ in the front's computation.
fn json_points(dir: &Path) -> Vec<(f64, f64, bool)> {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sweep.json")).unwrap()).unwrap();
    json["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["gpu_ms"]["median"].as_f64().unwrap(),
                r["rmse"].as_f64().unwrap(),
                r["pareto"].as_bool().unwrap(),
            )
        })
        .collect()
}

/// A row is on the front unless another row is no slower (GPU median) and
/// no less accurate (RMSE), and strictly better in one of them. Returns how
/// many rows are off the front.
fn assert_pareto_flag_is_the_front(points: &[(f64, f64, bool)]) -> usize {
    let mut dominated = 0;
    for &(t, e, flag) in points {
        let beaten = points
            .iter()
            .any(|&(t2, e2, _)| t2 <= t && e2 <= e && (t2 < t || e2 < e));
        dominated += beaten as usize;
        assert_eq!(flag, !beaten, "row ({t}, {e}) of {points:?}");
    }
    dominated
}

#[test]
fn a_dominated_row_is_off_the_front() {
    // texture_filter changes nothing in a scene without textures, so both
    // rows have error 0 and the faster one dominates the slower one.
    let dir = common::absent_dir("sweep", "dominated");
    let out = sweep(
        &dir,
        &["size=48x27", "texture_filter=nearest,trilinear"],
        &["--frames", "3", "--warmup", "0", "--validate"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = common::read_csv(&dir.join("sweep.csv"));
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| num(r, "rmse") == 0.0), "{rows:?}");
    let points = json_points(&dir);
    // Equal times (possible, if unlikely, on any machine) dominate
    // neither: then both are on the front.
    let expected = usize::from(points[0].0 != points[1].0);
    assert_eq!(
        assert_pareto_flag_is_the_front(&points),
        expected,
        "{points:?}"
    );
    // The CSV says the same as the JSON.
    for (r, p) in rows.iter().zip(&points) {
        assert_eq!(r["pareto"], p.2.to_string());
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn tiny_sweep_under_validation() {
    let dir = common::absent_dir("sweep", "tiny");
    let out = sweep(
        &dir,
        &[
            "size=96x54",
            "tessellation=0.25,1",
            "hdr_format=rgba16f,rgba32f",
        ],
        &["--frames", "2", "--warmup", "0", "--validate"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "stderr: {stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("(reference)"), "table: {stdout}");

    let rows = common::read_csv(&dir.join("sweep.csv"));
    assert_eq!(rows.len(), 4);
    let find = |tess: &str, format: &str| {
        rows.iter()
            .find(|r| r["tessellation"] == tess && r["hdr_format"] == format)
            .unwrap_or_else(|| panic!("no row {tess} {format}"))
    };

    // The reference is tessellation 1 (last listed) and rgba32f (fixed).
    let reference = find("1", "rgba32f");
    assert_eq!(reference["is_reference"], "true");
    assert_eq!(
        reference["reference"],
        "size=96x54 tessellation=1 hdr_format=rgba32f"
    );
    assert_eq!(num(reference, "rmse"), 0.0);
    assert_eq!(num(reference, "flip_mean"), 0.0);
    assert_eq!(
        rows.iter().filter(|r| r["is_reference"] == "true").count(),
        1
    );

    // Coarse spheres are further from the reference than anything at full
    // tessellation, and half floats add a little error of their own.
    for format in ["rgba16f", "rgba32f"] {
        let coarse = find("0.25", format);
        assert!(num(coarse, "rmse") > num(find("1", "rgba16f"), "rmse"));
        assert!(num(coarse, "flip_mean") > 0.0);
    }
    assert!(num(find("1", "rgba16f"), "rmse") > 0.0);

    // Times are positive, and the Pareto column is exactly the front
    // recomputed from the CSV's own times and errors.
    for r in &rows {
        assert!(num(r, "gpu_median_ms") > 0.0);
        assert!(num(r, "gpu_p95_ms") >= num(r, "gpu_median_ms"));
        assert!(num(r, "opaque_median_ms") > 0.0);
    }
    assert_pareto_flag_is_the_front(&json_points(&dir));

    // JSON and SVG are there and complete.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["rows"].as_array().unwrap().len(), 4);
    assert_eq!(json["knobs"][1], "tessellation");
    let svg = std::fs::read_to_string(dir.join("sweep.svg")).unwrap();
    assert!(svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("1, rgba32f (reference)"), "{svg}");

    // Nothing but the three files (no temporary leftovers).
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["sweep.csv", "sweep.json", "sweep.svg"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_knobs_fail_naming_the_knob_and_write_nothing() {
    for (knobs, expected) in [
        (&["sharpness=1,2"][..], "sharpness"),
        (&["tessellation=0.5,zero"][..], "tessellation=zero"),
        (&["hdr_format=rgba8"][..], "hdr_format=rgba8"),
        (&["tessellation"][..], "tessellation"),
        (
            &["tessellation=1,2", "tessellation=3"][..],
            "tessellation is given twice",
        ),
        (
            &["tessellation=1,2,3,4,5,6,7,8,9", "size=8x8,9x9,10x10"][..],
            "27 combinations",
        ),
    ] {
        let dir = common::absent_dir("sweep", "bad");
        let out = sweep(&dir, knobs, &["--max-combinations", "20"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{knobs:?} was accepted");
        assert!(
            stderr.contains(expected),
            "{knobs:?}: expected '{expected}' in: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{knobs:?}: {stderr}");
        assert!(!dir.exists(), "{knobs:?}: output written");
    }
}
