//! `aerial sweep --shard` and `aerial sweep merge` end to end: a tiny sweep
//! run at once and as 3 shards in separate processes (one per way of
//! choosing the shard), merged, and compared; and every refusal.

use crate::common;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const KNOBS: [&str; 3] = [
    "size=48x27",
    "tessellation=0.25,1",
    "hdr_format=rgba16f,rgba32f",
];
const ERROR_COLUMNS: [&str; 4] = ["rmse", "max_rel_error", "flip_mean", "flip_p99"];

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/shading_models.toml")
}

/// The tiny sweep (with `knobs`) into `out_dir`, one frame, under
/// validation; `set` adjusts the command (shard, environment).
fn sweep_with(knobs: &[&str], out_dir: &Path, set: impl FnOnce(&mut Command)) -> Output {
    let mut cmd = common::aerial();
    cmd.arg("sweep").arg(scene()).arg("--out-dir").arg(out_dir);
    for k in knobs {
        cmd.args(["--knob", k]);
    }
    cmd.args(["--frames", "1", "--warmup", "0", "--validate"]);
    set(&mut cmd);
    cmd.output().unwrap()
}

fn sweep(out_dir: &Path, set: impl FnOnce(&mut Command)) -> Output {
    sweep_with(&KNOBS, out_dir, set)
}

fn merge(dirs: &[&Path], out_dir: &Path) -> Output {
    common::aerial()
        .args(["sweep", "merge"])
        .args(dirs)
        .arg("--out-dir")
        .arg(out_dir)
        .output()
        .unwrap()
}

#[track_caller]
fn assert_ok(out: &Output) {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Asserts a clean refusal: failure, `expected` in the message, no panic.
#[track_caller]
fn assert_refused(out: &Output, expected: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "accepted; stderr: {stderr}");
    assert!(
        stderr.contains(expected),
        "expected '{expected}' in: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

fn read_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("sweep.json")).unwrap()).unwrap()
}

fn num(row: &HashMap<String, String>, column: &str) -> f64 {
    row[column]
        .parse()
        .unwrap_or_else(|e| panic!("{column} = {:?}: {e}", row[column]))
}

#[test]
fn three_shards_in_separate_processes_merge_into_the_unsharded_sweep() {
    let root = common::absent_dir("shards", "three");
    let whole = root.join("whole");
    assert_ok(&sweep(&whole, |_| {}));

    // Each way of choosing the shard once: explicit, a Kubernetes Indexed
    // Job's index, a Slurm array numbered from 1.
    let shards: Vec<PathBuf> = (0..3).map(|i| root.join(format!("shard{i}"))).collect();
    assert_ok(&sweep(&shards[0], |c| {
        c.args(["--shard", "0/3"]);
    }));
    assert_ok(&sweep(&shards[1], |c| {
        c.args(["--shard", "kubernetes/3"])
            .env("JOB_COMPLETION_INDEX", "1");
    }));
    assert_ok(&sweep(&shards[2], |c| {
        c.args(["--shard", "slurm"])
            .env("SLURM_ARRAY_TASK_ID", "3")
            .env("SLURM_ARRAY_TASK_MIN", "1")
            .env("SLURM_ARRAY_TASK_COUNT", "3");
    }));
    // Round-robin: shard 0 holds combinations 0 and 3, the others one each;
    // each shard says which it is and what sweep it belongs to.
    for (i, dir) in shards.iter().enumerate() {
        let json = read_json(dir);
        assert_eq!(json["shard"]["index"], i, "{}", dir.display());
        assert_eq!(json["shard"]["count"], 3);
        assert_eq!(json["combinations"], 4);
        assert_eq!(json["scene_hash"], read_json(&whole)["scene_hash"]);
        assert_eq!(json["axes"][2], "hdr_format=rgba16f,rgba32f");
        let indices: Vec<u64> = json["rows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["index"].as_u64().unwrap())
            .collect();
        assert_eq!(indices, if i == 0 { vec![0, 3] } else { vec![i as u64] });
    }

    // Given out of order.
    let merged = root.join("merged");
    let out = merge(&[&shards[2], &shards[0], &shards[1]], &merged);
    assert_ok(&out);
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        table.contains("x empty")
            && table.contains("(reference)")
            && table.contains("merged from 3 shards"),
        "{table}"
    );

    let w = common::read_csv(&whole.join("sweep.csv"));
    let m = common::read_csv(&merged.join("sweep.csv"));
    assert_eq!(m.len(), 4);
    let header = |dir: &Path| {
        let text = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
        text.lines().next().unwrap().to_string()
    };
    assert_eq!(header(&merged), header(&whole));
    for (mr, wr) in m.iter().zip(&w) {
        for column in [
            "size",
            "tessellation",
            "hdr_format",
            "reference",
            "is_reference",
        ] {
            assert_eq!(mr[column], wr[column], "{column}");
        }
        // The CSV writes errors in their shortest exact form: equal text
        // is equal bits.
        for column in ERROR_COLUMNS {
            assert_eq!(mr[column], wr[column], "{column} of {mr:?}");
        }
        // Times are each shard's own, with its floor.
        assert!(num(mr, "empty_median_ms") > 0.0);
    }
    // And bit for bit in the JSON.
    let (wj, mj) = (read_json(&whole), read_json(&merged));
    for (wr, mr) in wj["rows"]
        .as_array()
        .unwrap()
        .iter()
        .zip(mj["rows"].as_array().unwrap())
    {
        assert_eq!(wr["settings"], mr["settings"]);
        for column in ERROR_COLUMNS {
            let bits = |v: &serde_json::Value| v[column].as_f64().unwrap().to_bits();
            assert_eq!(bits(wr), bits(mr), "{column}");
        }
    }
    // Each row's multiple is its GPU median over its own floor (from the
    // JSON, at full precision: the CSV rounds both).
    for mr in mj["rows"].as_array().unwrap() {
        let x = mr["gpu_x_empty"].as_f64().unwrap();
        let ratio =
            mr["gpu_ms"]["median"].as_f64().unwrap() / mr["empty_median_ms"].as_f64().unwrap();
        assert!((x / ratio - 1.0).abs() < 1e-12, "{mr}");
    }
    assert!(mj["shard"].is_null());
    assert_eq!(mj["shards"].as_array().unwrap().len(), 3);
    assert_eq!(mj["time_axis"], "gpu_x_empty");
    assert_eq!(mj["passes"], wj["passes"]);

    // The merged front is over multiples of each shard's floor (from the
    // JSON: two multiples equal in the CSV's rounding may differ).
    let points: Vec<(f64, f64, bool)> = mj["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["gpu_x_empty"].as_f64().unwrap(),
                r["rmse"].as_f64().unwrap(),
                r["pareto"].as_bool().unwrap(),
            )
        })
        .collect();
    for (r, &(t, e, flag)) in m.iter().zip(&points) {
        let beaten = points
            .iter()
            .any(|&(t2, e2, _)| t2 <= t && e2 <= e && (t2 < t || e2 < e));
        assert_eq!(flag, !beaten, "{r:?}");
        assert_eq!(r["pareto"], flag.to_string(), "{r:?}");
    }
    let svg = std::fs::read_to_string(merged.join("sweep.svg")).unwrap();
    assert!(svg.contains("multiple of the empty pass"), "{svg}");
    assert!(svg.trim_end().ends_with("</svg>"));

    refusals(&root, &shards);
    std::fs::remove_dir_all(&root).ok();
}

/// Merges that must fail, on the shards of the test above; none writes
/// anything.
fn refusals(root: &Path, shards: &[PathBuf]) {
    let out_dir = root.join("refused");
    let (s0, s1, s2) = (&shards[0], &shards[1], &shards[2]);

    assert_refused(
        &merge(&[s0, s2], &out_dir),
        "1 of 3 shards missing: shard 1",
    );
    assert_refused(
        &merge(&[s1], &out_dir),
        "2 of 3 shards missing: shards 0, 2",
    );

    let copy = root.join("shard1-copy");
    std::fs::create_dir_all(&copy).unwrap();
    std::fs::copy(s1.join("sweep.json"), copy.join("sweep.json")).unwrap();
    assert_refused(
        &merge(&[s0, s1, &copy, s2], &out_dir),
        "shard 1 is given twice",
    );

    // Shard 1 of a sweep with other tessellation values.
    let other = root.join("other");
    assert_ok(&sweep_with(
        &[
            "size=48x27",
            "tessellation=0.5,1",
            "hdr_format=rgba16f,rgba32f",
        ],
        &other,
        |c| {
            c.args(["--shard", "1/3"]);
        },
    ));
    assert_refused(
        &merge(&[s0, &other, s2], &out_dir),
        "is a shard of a different sweep than",
    );
    assert_refused(&merge(&[s0, &other, s2], &out_dir), "axes differs");

    // A sweep run at once is not a shard.
    assert_refused(
        &merge(&[s0, &root.join("whole"), s2], &out_dir),
        "is not the output of one shard",
    );
    // Nor is a folder without one.
    assert_refused(
        &merge(&[s0, &root.join("nowhere"), s2], &out_dir),
        "nowhere",
    );
    assert!(
        !out_dir.exists(),
        "a failed merge wrote {}",
        out_dir.display()
    );

    // Merging into a shard's own folder would lose that shard.
    let before = std::fs::read(s1.join("sweep.json")).unwrap();
    assert_refused(&merge(&[s0, s1, s2], s1), "one of the shards' folders");
    assert_eq!(std::fs::read(s1.join("sweep.json")).unwrap(), before);
}

#[test]
fn bad_shard_values_are_refused_before_rendering() {
    for (spec, env, expected) in [
        ("3/3", &[][..], "shard index 3 is out of range for 3 shards"),
        ("0/0", &[], "at least 1 shard"),
        ("1", &[], "no '/'"),
        ("x/3", &[], "I is not a whole number"),
        ("kubernetes/3", &[], "JOB_COMPLETION_INDEX is not set"),
        // Numbers from a scheduler's variables name the variables.
        (
            "kubernetes/3",
            &[("JOB_COMPLETION_INDEX", "7")],
            "shard index 7 (JOB_COMPLETION_INDEX 7) is out of range",
        ),
        ("slurm", &[], "SLURM_ARRAY_TASK_ID is not set"),
        (
            "slurm",
            &[
                ("SLURM_ARRAY_TASK_ID", "9"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
            ],
            "shard index 8 (SLURM_ARRAY_TASK_ID 9 - SLURM_ARRAY_TASK_MIN 1) is out of range \
             for 3 shards (SLURM_ARRAY_TASK_COUNT 3)",
        ),
        (
            "slurm",
            &[
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "0"),
            ],
            "at least 1 shard (SLURM_ARRAY_TASK_COUNT 0)",
        ),
        // 4 combinations cannot fill 5 shards.
        ("4/5", &[], "only 4 combinations"),
        (
            "slurm",
            &[
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "6"),
            ],
            "6 shards (I from SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN, N from \
             SLURM_ARRAY_TASK_COUNT), but the sweep has only 4 combinations",
        ),
    ] {
        let dir = common::absent_dir("shards", "bad");
        let out = sweep(&dir, |c| {
            c.args(["--shard", spec]).envs(env.iter().copied());
        });
        assert_refused(&out, expected);
        assert!(!dir.exists(), "--shard {spec}: output written");
    }
}
