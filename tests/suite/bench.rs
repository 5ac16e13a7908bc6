//! `aerial bench`: the JSON report, the baseline gate on hand-built
//! reports (its verdicts, and the baselines it refuses), a live run gated
//! against baselines far from any machine's times, the empty pass under
//! validation, the pass timings against the CPU frame time, and the
//! benchmark scenes in assets/bench.

use crate::common;

use aerial::bench::{self, BenchReport};
use aerial::render::empty_pass::{CONSTANT_RGBA8, PASS_NAME};
use aerial::render_run::{self, RenderSettings};
use aerial::scene::material_maps::MapKind;
use aerial::scene::{Light, Scene, KNOBS};
use std::path::{Path, PathBuf};
use std::process::Output;

fn bench_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/bench")
        .join(name)
}

/// `aerial bench` on the smallest scene, short and small so it is fast,
/// under validation like every render in the tests (any message fails it).
fn quick_bench(extra: &[&str]) -> Output {
    common::aerial()
        .arg("bench")
        .arg(bench_scene("triangle.toml"))
        .args([
            "--frames",
            "3",
            "--warmup",
            "1",
            "--width",
            "64",
            "--height",
            "48",
            "--validate",
        ])
        .args(extra)
        .output()
        .unwrap()
}

fn assert_success(out: &Output) {
    assert!(
        out.status.success(),
        "exit {:?}\nstdout: {}\nstderr: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn bench_json_has_every_field_and_round_trips() {
    let dir = common::fresh_dir("bench", "json");
    let json = dir.join("out.json");
    let out = quick_bench(&[
        "--knob",
        "shading=gouraud",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_success(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("opaque") && stdout.contains("x empty"),
        "{stdout}"
    );

    // Field names as written, so a rename is caught here.
    let value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for field in [
        "format",
        "commit",
        "aerial_version",
        "build",
        "device",
        "warmup",
        "frames",
        "validate",
        "empty_passes",
        "scenes",
    ] {
        assert!(value.get(field).is_some(), "missing {field}");
    }
    for field in [
        "name",
        "driver_name",
        "driver_info",
        "driver_version",
        "api_version",
    ] {
        assert!(
            value["device"].get(field).is_some(),
            "missing device.{field}"
        );
    }
    let scene = &value["scenes"][0];
    for field in [
        "file",
        "sha256",
        "resolution",
        "triangles",
        "knobs",
        "passes",
        "gpu_total",
        "cpu_frame",
        "empty_pass_between_frames",
    ] {
        assert!(scene.get(field).is_some(), "missing scenes[0].{field}");
    }
    for stat in ["count", "min", "median", "p95", "max", "mean", "std_dev"] {
        assert!(
            scene["passes"][0]["ms"].get(stat).is_some(),
            "missing {stat}"
        );
    }

    let report = BenchReport::load(&json).unwrap();
    assert_eq!(report.format, bench::FORMAT);
    assert_eq!(report.commit, bench::COMMIT);
    assert!(!report.commit.is_empty());
    assert!(!report.device.name.is_empty());
    assert_eq!((report.warmup, report.frames), (1, 3));
    assert_eq!(report.empty_passes.len(), 1);
    let empty = &report.empty_passes[0];
    assert_eq!((empty.resolution.width, empty.resolution.height), (64, 48));
    let s = &report.scenes[0];
    assert_eq!((s.resolution.width, s.resolution.height), (64, 48));
    assert_eq!(s.triangles, 12);
    let file_bytes = std::fs::read(bench_scene("triangle.toml")).unwrap();
    assert_eq!(s.sha256, bench::sha256_hex(&file_bytes));
    for knob in KNOBS {
        assert!(
            s.knobs.contains_key(knob.name),
            "knob {} missing",
            knob.name
        );
    }
    assert_eq!(s.knobs["shading"], "gouraud");
    assert_eq!(s.knobs["size"], "64x48");
    let names: Vec<&str> = s.passes.iter().map(|p| p.name.as_str()).collect();
    // An LDR scene: drawn straight into the sRGB output, no tone map.
    assert_eq!(names, ["opaque", "readback"]);
    for p in s.rows() {
        assert_eq!(p.ms.count, 3, "{}", p.name);
        assert!(p.ms.min > 0.0 && p.ms.min <= p.ms.median && p.ms.median <= p.ms.max);
    }
    // The multiples divide by the empty pass timed between this scene's
    // frames, EMPTY_PASSES_PER_FRAME after each measured one.
    let floor = s
        .empty_pass_between_frames
        .as_ref()
        .expect("empty pass timed between frames");
    assert_eq!(
        floor.ms.count,
        3 * aerial::render_run::EMPTY_PASSES_PER_FRAME
    );
    assert!(floor.ms.min > 0.0);
    for p in s.passes.iter().chain(&s.gpu_total) {
        let m = p.empty_pass_multiple.expect("a multiple");
        assert!(
            (m - p.ms.median / floor.ms.median).abs() <= 1e-9 * m,
            "{}: {m} is not median / floor",
            p.name
        );
    }

    // Save and load again: nothing lost.
    let again = dir.join("again.json");
    report.save(&again).unwrap();
    assert_eq!(BenchReport::load(&again).unwrap(), report);
    std::fs::remove_dir_all(&dir).ok();
}

/// A report built by hand: one scene `scene` (64x48) with `passes` (name
/// and every frame's time, in ms), its GPU total and CPU frame made from
/// them, and the empty pass at `empty` ms per frame, both the separate one
/// and the one between frames. Fixed numbers, so a gate over reports like
/// it gives the same verdict on any machine, however busy.
fn synthetic(scene: &str, passes: &[(&str, Vec<f64>)], empty: f64) -> BenchReport {
    use aerial::bench::{
        DeviceRecord, EmptyPassReport, Metric, PassReport, Resolution, SceneReport, CPU_FRAME,
        FORMAT, GPU_TOTAL,
    };
    use aerial::report::stats::Summary;
    let row = |name: &str, samples: &[f64]| {
        PassReport::timed(name, samples, Summary::of(samples).expect("finite"))
    };
    let frames = passes[0].1.len();
    let totals: Vec<f64> = (0..frames)
        .map(|i| passes.iter().map(|(_, t)| t[i]).sum())
        .collect();
    let cpu: Vec<f64> = totals.iter().map(|t| t * 1.25).collect();
    let floor = vec![empty; frames];
    let resolution = Resolution {
        width: 64,
        height: 48,
    };
    BenchReport {
        format: FORMAT.into(),
        commit: "0000000".into(),
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
        frames: frames as u32,
        validate: false,
        metrics: vec![Metric::Time],
        empty_passes: vec![EmptyPassReport {
            resolution,
            gpu: Some(row("empty", &floor)),
            cpu_frame: row(CPU_FRAME, &vec![empty * 2.0; frames]),
        }],
        scenes: vec![SceneReport {
            file: scene.into(),
            sha256: "00".into(),
            resolution,
            triangles: 12,
            knobs: Default::default(),
            passes: passes.iter().map(|(name, t)| row(name, t)).collect(),
            gpu_total: Some(row(GPU_TOTAL, &totals)),
            cpu_frame: row(CPU_FRAME, &cpu),
            empty_pass_between_frames: Some(row("empty", &floor)),
            asset_warnings: 0,
        }],
    }
}

/// Frame times around `centre`, `spread` apart at most (fixed, no noise).
fn frames_around(centre: f64, spread: f64) -> Vec<f64> {
    (0..9)
        .map(|i| centre * (1.0 + spread * (f64::from(i * 7 % 9) / 4.0 - 1.0)))
        .collect()
}

/// `bench --from-json current --compare baseline --max-ratio R` (plus
/// `extra`) on two reports written into `dir`.
fn gate(
    dir: &Path,
    current: &BenchReport,
    baseline: &BenchReport,
    max_ratio: &str,
    extra: &[&str],
) -> Output {
    let (c, b) = (dir.join("current.json"), dir.join("baseline.json"));
    current.save(&c).unwrap();
    baseline.save(&b).unwrap();
    common::aerial()
        .args(["bench", "--from-json"])
        .arg(&c)
        .arg("--compare")
        .arg(&b)
        .args(["--max-ratio", max_ratio])
        .args(extra)
        .output()
        .unwrap()
}

fn show(out: &Output) -> String {
    format!(
        "exit {:?}\nstdout: {}\nstderr: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The gate's three verdicts and its refusal, on hand-built reports: the
/// same on any machine, at any load (the gate once judged this on live
/// times, and a busy machine turned a failure into "inconclusive").
#[test]
fn the_gate_fails_a_slowdown_passes_an_equal_report_and_says_when_it_cannot_tell() {
    let dir = common::fresh_dir("bench", "gate-verdicts");
    let base = synthetic(
        "s.toml",
        &[
            ("opaque", frames_around(2.0, 0.05)),
            ("readback", frames_around(1.0, 0.05)),
        ],
        0.5,
    );
    // Twice as slow, every frame: exit 1, every ratio 2.
    let slow = synthetic(
        "s.toml",
        &[
            ("opaque", frames_around(4.0, 0.05)),
            ("readback", frames_around(2.0, 0.05)),
        ],
        0.5,
    );
    for limit in ["1.1", "1.5"] {
        let out = gate(&dir, &slow, &base, limit, &[]);
        assert_eq!(out.status.code(), Some(1), "{}", show(&out));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(&format!("slower than --max-ratio {limit}")),
            "{stderr}"
        );
        assert!(String::from_utf8_lossy(&out.stdout).contains("2.0000"));
    }
    // A report against itself, or an equal copy: every ratio exactly 1,
    // a pass at any limit of at least 1, time rows included.
    for limit in ["1", "1.02", "10"] {
        let out = gate(&dir, &base, &base, limit, &[]);
        assert_eq!(out.status.code(), Some(0), "{}", show(&out));
        assert!(String::from_utf8_lossy(&out.stdout).contains("ok: every ratio"));
    }
    let same = dir.join("same.json");
    base.save(&same).unwrap();
    let out = common::aerial()
        .args(["bench", "--from-json"])
        .arg(&same)
        .arg("--compare")
        .arg(&same)
        .args(["--max-ratio", "1.0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    // 25 % slower with frames 20 % apart: the interval straddles 1.25.
    let unsure = synthetic(
        "s.toml",
        &[
            ("opaque", frames_around(2.5, 0.2)),
            ("readback", frames_around(1.0, 0.05)),
        ],
        0.5,
    );
    let out = gate(&dir, &unsure, &base, "1.25", &[]);
    assert_eq!(out.status.code(), Some(3), "{}", show(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("inconclusive"));
    // Another scene and no empty pass: nothing matched, an error.
    let mut elsewhere = base.clone();
    elsewhere.scenes[0].file = "some/other/scene.toml".into();
    elsewhere.empty_passes.clear();
    let out = gate(&dir, &base, &elsewhere, "1000", &[]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nothing to compare"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Instruction counts are whole numbers in the comparison table, not
/// `1069849.0000`.
#[test]
fn instruction_counts_print_as_whole_numbers() {
    use aerial::bench::{CountReport, Metric};
    let dir = common::fresh_dir("bench", "gate-integers");
    let mut base = synthetic("s.toml", &[("opaque", frames_around(2.0, 0.05))], 0.5);
    base.metrics.push(Metric::Instructions);
    base.scenes[0].passes[0].instructions =
        CountReport::of(vec![10_698_490, 10_698_492, 10_698_491]);
    base.scenes[0].gpu_total.as_mut().unwrap().instructions =
        CountReport::of(vec![12_000_000, 12_000_001, 12_000_002, 12_000_004]);
    let out = gate(
        &dir,
        &base,
        &base,
        "1.02",
        &["--metric", "time,instructions"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let counts: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("s.toml") && l.contains("instructions"))
        .collect();
    assert_eq!(counts.len(), 2, "{stdout}");
    assert!(
        counts[0].contains(" 10698491 ") && !counts[0].contains("10698491."),
        "{stdout}"
    );
    // A median of an even number of frames (12000001.5), shown rounded.
    assert!(
        counts[1].contains(" 12000002 ") && !counts[1].contains("12000002."),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A live measurement through the gate, against baselines far enough
/// from any machine's times that the verdict cannot depend on the load:
/// one whose every time is 10 s (this run is far faster: a pass) and one
/// whose every time is 1 µs (a CPU frame alone takes longer: a failure).
#[test]
fn a_live_run_is_gated_against_a_stored_baseline() {
    let dir = common::fresh_dir("bench", "gate-live");
    let stored = dir.join("stored.json");
    assert_success(&quick_bench(&["--json", stored.to_str().unwrap()]));
    let report = BenchReport::load(&stored).unwrap();
    let scene = &report.scenes[0];
    let names: Vec<&str> = scene.passes.iter().map(|p| p.name.as_str()).collect();
    let constant = |scene_ms: f64, empty_ms: f64| {
        let passes: Vec<(&str, Vec<f64>)> = names.iter().map(|n| (*n, vec![scene_ms; 3])).collect();
        let mut r = synthetic(&scene.file, &passes, empty_ms);
        r.scenes[0].resolution = scene.resolution;
        r.empty_passes[0].resolution = scene.resolution;
        r
    };
    for (baseline, code) in [(constant(1e4, 1e3), 0), (constant(1e-3, 1e-3), 1)] {
        let path = dir.join("baseline.json");
        baseline.save(&path).unwrap();
        let out = quick_bench(&["--compare", path.to_str().unwrap(), "--max-ratio", "2"]);
        assert_eq!(out.status.code(), Some(code), "{}", show(&out));
        assert!(String::from_utf8_lossy(&out.stdout).contains("ratio"));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Baselines that once made the gate judge nothing and say "ok": medians
/// of 0, −1 or 1e-300 (of the scenes or of every row), negative, zero or
/// sub-nanosecond frames, an empty pass far slower than its frames or
/// slower than every pass. Against a run twice as slow, each is now an
/// error naming the file and the field or rows (exit 2), or the slowdown
/// (exit 1): the frame's GPU total and CPU time are judged whatever the
/// empty pass. Never "ok".
#[test]
fn hostile_baselines_are_errors_or_judge_the_frame() {
    let dir = common::fresh_dir("bench", "gate-hostile");
    let baseline = |empty: f64| {
        synthetic(
            "s.toml",
            &[
                ("opaque", frames_around(2.0, 0.05)),
                ("readback", frames_around(1.0, 0.05)),
            ],
            empty,
        )
    };
    let current = synthetic(
        "s.toml",
        &[
            ("opaque", frames_around(4.0, 0.05)),
            ("readback", frames_around(2.0, 0.05)),
        ],
        0.5,
    );
    // Every "median" in the JSON (or under the scenes) set to `to`.
    fn every_median(v: &mut serde_json::Value, to: f64) {
        match v {
            serde_json::Value::Object(map) => {
                if map.contains_key("median") {
                    map.insert("median".into(), serde_json::json!(to));
                }
                map.values_mut().for_each(|x| every_median(x, to));
            }
            serde_json::Value::Array(items) => items.iter_mut().for_each(|x| every_median(x, to)),
            _ => {}
        }
    }
    fn scene_medians(v: &mut serde_json::Value, to: f64) {
        every_median(&mut v["scenes"], to)
    }
    type Edit = Box<dyn Fn(&mut serde_json::Value)>;
    let unusable = "no usable baseline median";
    let slower = "slower than --max-ratio 1.5";
    let cases: Vec<(Edit, i32, &str)> = vec![
        (Box::new(|v| scene_medians(v, 0.0)), 2, unusable),
        (Box::new(|v| scene_medians(v, -1.0)), 2, unusable),
        (Box::new(|v| every_median(v, 0.0)), 2, unusable),
        (Box::new(|v| every_median(v, -1.0)), 2, unusable),
        (Box::new(|v| scene_medians(v, 1e-300)), 1, slower),
        (Box::new(|v| every_median(v, 1e-300)), 1, slower),
        (
            Box::new(|v| v["empty_passes"][0]["gpu"]["ms"]["median"] = serde_json::json!(1e300)),
            1,
            slower,
        ),
        (
            Box::new(|v| v["scenes"][0]["passes"][0]["samples_ms"][2] = serde_json::json!(-0.5)),
            2,
            "scenes[0].passes[0].samples_ms[2]: -0.5 is negative",
        ),
        (
            Box::new(|v| v["scenes"][0]["gpu_total"]["samples_ms"][0] = serde_json::json!(0.0)),
            2,
            "scenes[0].gpu_total.samples_ms[0]: 0",
        ),
        (
            Box::new(|v| v["scenes"][0]["cpu_frame"]["samples_ms"][4] = serde_json::json!(1e-300)),
            2,
            "scenes[0].cpu_frame.samples_ms[4]: 1e-300 ms is shorter than 1 ns",
        ),
    ];
    current.save(&dir.join("current.json")).unwrap();
    let check = |path: &Path, code: i32, expected: &str| {
        let out = common::aerial()
            .args(["bench", "--from-json"])
            .arg(dir.join("current.json"))
            .arg("--compare")
            .arg(path)
            .args(["--max-ratio", "1.5"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{expected}: {}", show(&out));
        assert!(
            stderr.contains(expected)
                && (code == 1 || stderr.contains(&path.display().to_string())),
            "expected '{expected}' in: {stderr}"
        );
        assert!(
            !stderr.contains("panicked") && !String::from_utf8_lossy(&out.stdout).contains("ok:")
        );
    };
    for (n, (edit, code, expected)) in cases.iter().enumerate() {
        let mut v = serde_json::to_value(baseline(0.5)).unwrap();
        edit(&mut v);
        let path = dir.join(format!("hostile{n}.json"));
        std::fs::write(&path, v.to_string()).unwrap();
        check(&path, *code, expected);
    }
    // Consistent frames, but the empty pass slower than every pass: the
    // passes are not judged, the frame is.
    let path = dir.join("slow-floor.json");
    baseline(1e6).save(&path).unwrap();
    check(&path, 1, slower);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_bench_input_fails_with_a_message_not_a_panic() {
    let dir = common::fresh_dir("bench", "bad");
    let not_json = dir.join("not-a-report.json");
    std::fs::write(&not_json, "{\"format\": \"aerial-bench/1\", \"commit\": 3}").unwrap();
    let missing = dir.join("missing.json");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["--knob".into(), "nope=1".into()],
            "unknown knob 'nope'",
        ),
        (vec!["--knob".into(), "lights=99".into()], "lights=99"),
        (vec!["--knob".into(), "shading".into()], "NAME=VALUE"),
        (vec!["--frames".into(), "0".into()], "--frames"),
        (
            vec![
                "--knob".into(),
                "tone_map=none".into(),
                "--knob".into(),
                "tone_map=reinhard".into(),
            ],
            "knob tone_map is given twice",
        ),
        // The same scene file under another spelling of its path.
        (
            vec![Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("assets/./bench/../bench/triangle.toml")
                .display()
                .to_string()],
            "given twice",
        ),
        (
            vec![
                "--compare".into(),
                not_json.display().to_string(),
                "--max-ratio".into(),
                "2".into(),
            ],
            "commit",
        ),
        (
            vec![
                "--compare".into(),
                missing.display().to_string(),
                "--max-ratio".into(),
                "2".into(),
            ],
            "missing.json",
        ),
        (
            vec![
                "--compare".into(),
                not_json.display().to_string(),
                "--max-ratio=0".into(),
            ],
            "--max-ratio",
        ),
    ];
    for (args, expected) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = quick_bench(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} was accepted");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn empty_pass_is_clean_under_validation_and_takes_time() {
    let run = render_run::run(
        render_run::RunSource::EmptyPass {
            width: 96,
            height: 64,
        },
        &RenderSettings {
            warmup: 1,
            frames: 3,
            ..common::validated_settings()
        },
        &mut || {},
    )
    .unwrap();
    common::assert_no_validation_messages(&run);
    assert_eq!(run.passes, [PASS_NAME]);
    assert_eq!(run.frames.len(), 3);
    for f in &run.frames {
        assert_eq!(f.pass_ms.len(), 1, "lavapipe has timestamps");
        assert!(f.pass_ms[0] > 0.0, "{f:?}");
        assert!(f.cpu_ms > 0.0);
    }
    // The triangle covered the whole attachment with the constant.
    let (w, h) = (run.output.width, run.output.height);
    assert_eq!((w, h), (96, 64));
    for (i, px) in run.output.data.chunks_exact(4).enumerate() {
        let close = px
            .iter()
            .zip(CONSTANT_RGBA8)
            .all(|(a, b)| a.abs_diff(b) <= 1);
        assert!(close, "pixel {i} is {px:?}, not {CONSTANT_RGBA8:?}");
    }
}

#[test]
fn empty_pass_rejects_a_zero_size() {
    let e = render_run::run(
        render_run::RunSource::EmptyPass {
            width: 0,
            height: 64,
        },
        &RenderSettings::default(),
        &mut || {},
    )
    .err()
    .expect("a 0x64 pass was accepted")
    .to_string();
    assert!(e.contains("0x64"), "{e}");
}

#[test]
fn bench_scenes_have_the_intended_load_and_render_cleanly() {
    let load = |name: &str| Scene::load(&bench_scene(name)).unwrap_or_else(|e| panic!("{e}"));
    let triangles = |s: &Scene| -> usize {
        (0..s.objects.len())
            .map(|i| s.object_mesh(i).triangle_count())
            .sum()
    };

    let many = load("many_lights.toml");
    assert_eq!(triangles(&many), 58_112);
    assert_eq!(many.lights.len(), 6);
    assert!(many.lights.iter().all(|l| matches!(l, Light::Point { .. })));
    assert!(many.objects.iter().all(|o| many.materials[o.material]
        .maps
        .get(MapKind::BaseColor)
        .is_some()));
    // No light culled: every object gets all six.
    for i in 0..many.objects.len() {
        assert_eq!(many.lights_reaching(i).len(), 6);
    }

    let tiny = load("triangle.toml");
    assert_eq!(tiny.objects.len(), 1);
    assert_eq!(triangles(&tiny), 12);

    let hdr = load("hdr.toml");
    let brightest = hdr
        .lights
        .iter()
        .map(|l| l.color().max_element())
        .fold(0.0, f32::max);
    assert!(brightest >= 10.0, "brightest light {brightest}");

    // The same six lights over one plane that covers every pixel.
    let plane = load("lights_on_a_plane.toml");
    assert_eq!(plane.objects.len(), 1);
    assert_eq!(triangles(&plane), 32);
    assert_eq!(plane.lights, many.lights);
    assert!(plane.materials[0].maps.is_empty());
    let mut small = plane.clone();
    small.set_output_size(Some(160), Some(90)).unwrap();
    let covered = common::render(&small, true).hdr.unwrap();
    assert!(
        covered.data.chunks_exact(4).all(|p| p[3] > 0.0),
        "the plane must cover every pixel"
    );

    for (name, mut scene) in [
        ("many_lights", many),
        ("hdr", hdr),
        ("triangle", tiny),
        ("lights_on_a_plane", plane),
    ] {
        scene.set_output_size(Some(160), Some(90)).unwrap();
        let run = common::render(&scene, false);
        let lit = run
            .output
            .data
            .chunks_exact(4)
            .filter(|p| p[..3] != [0, 0, 0]);
        assert!(lit.count() > 160 * 90 / 20, "{name} is nearly black");
    }
}

// Timings: the passes run inside the submission the CPU frame time spans
// (submit to fence), so their sum cannot exceed it. A timestamp period or
// mask applied wrongly (ticks read as milliseconds, garbage high bits)
// breaks this by orders of magnitude.

#[test]
fn the_sum_of_pass_times_does_not_exceed_the_cpu_frame_time() {
    let mut scene = aerial::scene::Scene::default_scene();
    scene.set_output_size(Some(160), Some(90)).unwrap();
    let run = aerial::render_run::render(
        &scene,
        &RenderSettings {
            warmup: 1,
            frames: 5,
            ..common::validated_settings()
        },
    )
    .unwrap();
    common::assert_no_validation_messages(&run);
    assert_eq!(run.frames.len(), 5);
    for (i, f) in run.frames.iter().enumerate() {
        assert_eq!(
            f.pass_ms.len(),
            run.passes.len(),
            "frame {i}: one time per pass"
        );
        let gpu: f64 = f.pass_ms.iter().sum();
        assert!(
            f.pass_ms.iter().all(|t| t.is_finite() && *t >= 0.0) && gpu > 0.0,
            "frame {i}: {:?}",
            f.pass_ms
        );
        assert!(
            gpu <= f.cpu_ms,
            "frame {i}: passes sum to {gpu} ms, more than the CPU frame time {} ms",
            f.cpu_ms
        );
    }
}
