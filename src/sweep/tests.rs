//! The sweep on a stand-in renderer and hand-made results (no Vulkan
//! needed): combinations and references, the Pareto front, and every output.

use super::*;
use crate::render::{FrameTiming, Pixels};
use crate::scene::Scene;
use std::cell::RefCell;
use std::path::Path;

fn axes(args: &[&str]) -> Vec<Axis> {
    args.iter().map(|a| Axis::parse(a).unwrap()).collect()
}

fn summary(ms: f64) -> Summary {
    Summary::of(&[ms]).unwrap()
}

fn row(values: &[(&str, &str)], ms: f64, rmse: f64, pareto: bool) -> Row {
    let pairs = |v: &[(&str, &str)]| {
        v.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect::<Vec<_>>()
    };
    Row {
        index: 0,
        settings: pairs(values),
        reference: pairs(&[("tessellation", "1"), ("hdr_format", "rgba32f")]),
        is_reference: rmse == 0.0,
        pass_median_ms: vec![("opaque".into(), ms * 0.75), ("tonemap".into(), ms * 0.25)],
        gpu_ms: summary(ms),
        cpu_ms: summary(ms + 1.0),
        empty_median_ms: Some(ms / 8.0),
        gpu_x_empty: Some(8.0),
        rmse,
        max_rel_error: rmse * 4.0,
        flip_mean: rmse / 2.0,
        flip_p99: rmse,
        setup: Vec::new(),
        pareto,
    }
}

#[test]
fn pareto_front_by_hand() {
    // (time, error): a is fastest, d most accurate, b between them on
    // the front; c is dominated by b (slower and worse); e duplicates b.
    let points = [
        (1.0, 0.5),  // a
        (2.0, 0.2),  // b
        (3.0, 0.3),  // c: b is faster and better
        (4.0, 0.0),  // d
        (2.0, 0.2),  // e: same as b, neither dominates the other
        (4.0, 0.1),  // f: d is as fast and better
        (1.0, 0.6),  // g: a is as fast and better
        (0.5, 0.55), // h: fastest of all
    ];
    assert_eq!(
        pareto_front(&points),
        [true, true, false, true, true, false, false, true]
    );
    assert_eq!(pareto_front(&[]), Vec::<bool>::new());
    assert_eq!(pareto_front(&[(1.0, 1.0)]), [true]);
}

/// A result with no rows; tests fill in what they look at.
fn blank_result() -> SweepResult {
    SweepResult {
        aerial_version: "0.0.0".into(),
        scene: "s.toml".into(),
        scene_hash: "0123456789abcdef".into(),
        device: "dev".into(),
        frames: 1,
        warmup: 0,
        reference: ReferenceKind::GpuBest,
        knobs: Vec::new(),
        axes: Vec::new(),
        combinations: 0,
        shard: None,
        shards: Vec::new(),
        time_axis: TimeAxis::GpuMedianMs,
        passes: Vec::new(),
        setup: Vec::new(),
        asset_warnings: 0,
        rows: Vec::new(),
    }
}

#[test]
fn csv_has_a_header_and_one_line_per_row() {
    let result = SweepResult {
        scene: "s.toml".into(),
        device: "dev".into(),
        frames: 1,
        warmup: 0,
        reference: ReferenceKind::GpuBest,
        knobs: vec!["tessellation".into(), "hdr_format".into()],
        passes: vec!["opaque".into(), "tonemap".into(), "transparent".into()],
        setup: vec!["od_table_kib".into()],
        asset_warnings: 0,
        rows: vec![
            Row {
                setup: vec![("od_table_kib".into(), 256.0)],
                ..row(
                    &[("tessellation", "0.5"), ("hdr_format", "rgba16f")],
                    2.0,
                    0.25,
                    true,
                )
            },
            row(
                &[("tessellation", "1"), ("hdr_format", "rgba32f")],
                4.0,
                0.0,
                true,
            ),
        ],
        ..blank_result()
    };
    let csv = to_csv(&result).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines,
        [
            "tessellation,hdr_format,reference,is_reference,opaque_median_ms,\
                 tonemap_median_ms,transparent_median_ms,gpu_median_ms,gpu_p95_ms,\
                 cpu_median_ms,empty_median_ms,gpu_x_empty,rmse,max_rel_error,flip_mean,\
                 flip_p99,od_table_kib,pareto",
            "0.5,rgba16f,tessellation=1 hdr_format=rgba32f,false,\
                 1.5000,0.5000,,2.0000,2.0000,3.0000,0.2500,8.000,0.25,1,0.125,0.25,256,true",
            "1,rgba32f,tessellation=1 hdr_format=rgba32f,true,\
                 3.0000,1.0000,,4.0000,4.0000,5.0000,0.5000,8.000,0,0,0,0,,true",
        ]
    );
    assert!(csv.ends_with('\n'));
}

#[test]
fn csv_fields_are_quoted_when_needed() {
    // One knob per case; the value is the row's first fields.
    let cases = ["plain", "a,b", "say \"hi\"", "two\nlines"];
    let knobs: Vec<String> = (0..cases.len()).map(|i| format!("k{i}")).collect();
    let settings: Vec<(&str, &str)> = knobs
        .iter()
        .zip(cases)
        .map(|(k, v)| (k.as_str(), v))
        .collect();
    let result = SweepResult {
        scene: "s.toml".into(),
        device: "dev".into(),
        frames: 1,
        warmup: 0,
        reference: ReferenceKind::Cpu,
        knobs: knobs.clone(),
        passes: vec![],
        setup: vec![],
        asset_warnings: 0,
        rows: vec![row(&settings, 1.0, 0.5, true)],
        ..blank_result()
    };
    let csv = to_csv(&result).unwrap();
    let line = csv.split_once('\n').unwrap().1;
    assert!(
        line.starts_with("plain,\"a,b\",\"say \"\"hi\"\"\",\"two\nlines\",cpu,"),
        "{csv}"
    );
}

#[test]
fn json_keeps_knob_order_and_has_the_metrics() {
    let result = SweepResult {
        scene: "s.toml".into(),
        device: "dev".into(),
        frames: 1,
        warmup: 0,
        reference: ReferenceKind::GpuBest,
        knobs: vec!["tessellation".into(), "hdr_format".into()],
        passes: vec!["opaque".into()],
        setup: vec![],
        asset_warnings: 2,
        rows: vec![row(
            &[("tessellation", "1"), ("hdr_format", "rgba32f")],
            4.0,
            0.0,
            true,
        )],
        ..blank_result()
    };
    let json = serde_json::to_string(&result).unwrap();
    assert!(
        json.contains(r#""settings":{"tessellation":"1","hdr_format":"rgba32f"}"#),
        "{json}"
    );
    for key in [
        "\"rmse\":0.0",
        "\"pareto\":true",
        "\"gpu_ms\":{",
        "\"p95\":",
        "\"asset_warnings\":2",
    ] {
        assert!(json.contains(key), "{key} missing: {json}");
    }
}

#[test]
fn axis_parsing_errors_name_the_knob_and_value() {
    let msg = |arg: &str| Axis::parse(arg).unwrap_err().to_string();
    assert!(msg("nope=1,2").contains("nope"), "{}", msg("nope=1,2"));
    assert!(msg("tessellation").contains("tessellation"));
    assert!(msg("tessellation=1,,2").contains("empty value"));
    let dup = msg("tessellation=1,2,1");
    assert!(dup.contains("tessellation") && dup.contains("'1'"), "{dup}");
    let a = Axis::parse(" tessellation = 0.5, 1 ").unwrap();
    assert_eq!(
        (a.knob.name, a.values),
        ("tessellation", vec!["0.5".into(), "1".into()])
    );
}

#[test]
fn bad_sweeps_are_refused_before_rendering() {
    let scene = Scene::default_scene();
    let new = |args: &[&str], max| {
        Sweep::new(
            "default",
            scene.clone(),
            axes(args),
            SweepOptions {
                max_combinations: max,
                ..SweepOptions::default()
            },
        )
        .err()
        .map(|e| e.to_string())
    };
    let bad = new(&["tessellation=1,-2"], 256).unwrap();
    assert!(bad.contains("tessellation=-2"), "{bad}");
    let twice = new(&["tessellation=1", "tessellation=2"], 256).unwrap();
    assert!(
        twice.contains("tessellation") && twice.contains("twice"),
        "{twice}"
    );
    let many = new(&["tessellation=1,2,3", "hdr_format=rgba16f,rgba32f"], 5).unwrap();
    assert!(
        many.contains("6 combinations") && many.contains("--max-combinations"),
        "{many}"
    );
    assert!(new(&["tessellation=1,2,3", "hdr_format=rgba16f,rgba32f"], 6).is_none());
    assert!(new(&[], 256).unwrap().contains("nothing to sweep"));
}

#[test]
fn references_follow_best() {
    let sweep = Sweep::new(
        "default",
        Scene::default_scene(),
        axes(&[
            "size=64x32,32x16",
            "tessellation=0.5,2,1",
            "hdr_format=rgba32f,rgba16f",
        ]),
        SweepOptions::default(),
    )
    .unwrap();
    let c = sweep.combinations();
    assert_eq!(c.len(), 12);
    // Last axis fastest.
    assert_eq!(c[1].values, ["64x32", "0.5", "rgba16f"]);
    // Size unchanged, tessellation last listed (1, not the largest),
    // hdr_format fixed.
    assert_eq!(c[1].reference, ["64x32", "1", "rgba32f"]);
    assert_eq!(c[11].values, ["32x16", "1", "rgba16f"]);
    assert_eq!(c[11].reference, ["32x16", "1", "rgba32f"]);
    assert_eq!(c[10].values, c[10].reference);
}

/// A stand-in renderer: a flat image whose value depends on the
/// tessellation and format, and times that grow with tessellation.
fn fake_render(scene: &Scene, job: Job) -> Result<Rendered, String> {
    let tris: u32 = scene
        .objects
        .iter()
        .map(|o| o.tessellation.0 * o.tessellation.1)
        .sum();
    // The exact image is the limit of infinite tessellation, 1.
    let mut value = 1.0 - 1.0 / tris as f32;
    if job == Job::Reference {
        value = 1.0;
    } else if scene.output.hdr_format == crate::scene::HdrFormat::Rgba16F {
        value += 1e-6;
    }
    let (w, h) = (scene.output.width, scene.output.height);
    let n = (w * h) as usize;
    let frames = match job {
        Job::Timing { frames, .. } => frames,
        Job::Images | Job::Reference => 1,
    };
    Ok(Rendered {
        device: "fake".into(),
        passes: vec!["opaque".into(), "tonemap".into()],
        frames: (0..frames)
            .map(|i| FrameTiming {
                pass_ms: vec![tris as f64 / 100.0 + i as f64 * 0.01, 1.0],
                cpu_ms: 1.0,
                work: Vec::new(),
            })
            .collect(),
        output: Pixels {
            width: w,
            height: h,
            data: [(value * 200.0) as u8, 0, 0, 255].repeat(n),
        },
        hdr: (!matches!(job, Job::Timing { .. })).then(|| Pixels {
            width: w,
            height: h,
            data: [value, 0.0, 0.0, 1.0].repeat(n),
        }),
        setup: vec![("triangles".into(), tris as f64)],
        empty_pass_ms: match job {
            Job::Timing { frames, .. } => vec![0.5; frames as usize * 3],
            Job::Images | Job::Reference => Vec::new(),
        },
    })
}

#[test]
fn run_renders_each_reference_once_and_scores_it_zero() {
    let sweep = Sweep::new(
        "default",
        Scene::default_scene(),
        axes(&["size=32x16", "tessellation=0.5,1", "hdr_format=rgba16f"]),
        SweepOptions {
            frames: 3,
            warmup: 0,
            max_combinations: 4,
            reference: ReferenceKind::GpuBest,
        },
    )
    .unwrap();
    let jobs = RefCell::new(Vec::new());
    let result = sweep
        .run(
            |scene, job| {
                let key = (scene.output.hdr_format, scene.objects[0].tessellation);
                jobs.borrow_mut().push((key, job));
                fake_render(scene, job)
            },
            |_, _| {},
        )
        .unwrap();
    let jobs = jobs.into_inner();
    // 2 timed runs, 2 image runs, and the rgba32f reference (not in
    // the sweep) once, though both rows use it.
    assert_eq!(jobs.len(), 5, "{jobs:?}");
    assert_eq!(jobs.iter().filter(|(_, j)| *j == Job::Images).count(), 3);
    assert!(jobs.iter().all(|(_, j)| *j == Job::Images
        || *j
            == Job::Timing {
                warmup: 0,
                frames: 3
            }));
    assert_eq!(result.rows.len(), 2);
    assert!(result.rows.iter().all(|r| !r.is_reference));
    // Median of 3 frames: the middle one.
    let r = &result.rows[0];
    assert_eq!(r.gpu_ms.count, 3);
    assert!((r.gpu_ms.median - (r.pass_median_ms[0].1 + 1.0)).abs() < 1e-9);
    // Coarser is faster and worse: both on the front.
    assert!(result.rows[0].rmse > result.rows[1].rmse);
    assert!(result.rows[0].max_rel_error > result.rows[1].max_rel_error);
    // The timed run's setup measures reach the rows, by name.
    assert_eq!(result.setup, ["triangles"]);
    assert!(result.rows[0].setup[0].1 < result.rows[1].setup[0].1);
    assert!(result.rows[1].rmse > 0.0);
    assert!(result.rows.iter().all(|r| r.pareto));

    // Sweeping the reference itself: error exactly 0, rendered once
    // for its images.
    let sweep = Sweep::new(
        "default",
        Scene::default_scene(),
        axes(&["size=32x16", "tessellation=0.5,1"]),
        SweepOptions::default(),
    )
    .unwrap();
    let image_runs = RefCell::new(0);
    let result = sweep
        .run(
            |scene, job| {
                *image_runs.borrow_mut() += usize::from(job == Job::Images);
                fake_render(scene, job)
            },
            |_, _| {},
        )
        .unwrap();
    assert_eq!(image_runs.into_inner(), 2);
    assert!(result.rows[1].is_reference);
    assert_eq!((result.rows[1].rmse, result.rows[1].flip_mean), (0.0, 0.0));
    assert!(result.rows[0].rmse > 0.0);
}

#[test]
fn render_failures_name_the_combination() {
    let sweep = Sweep::new(
        "default",
        Scene::default_scene(),
        axes(&["size=32x16", "tessellation=0.5"]),
        SweepOptions::default(),
    )
    .unwrap();
    let err = sweep
        .run(|_, _| Err::<Rendered, _>("device lost"), |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("tessellation=0.5") && err.contains("device lost"),
        "{err}"
    );

    let err = sweep
        .run(
            |scene, job| {
                let mut r = fake_render(scene, job)?;
                r.frames.iter_mut().for_each(|f| f.pass_ms.clear());
                Ok::<_, String>(r)
            },
            |_, _| {},
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("no pass timings"), "{err}");
}

/// A phong sphere on a plane, every light reaching everything
/// (light_cutoff 0), so the light sets do not depend on tessellation.
const CPU_SCENE: &str = r#"
light_cutoff = 0.0
[camera]
eye = [0.0, 1.0, 4.0]
look_at = [0.0, 0.5, 0.0]
[[lights]]
type = "point"
position = [2.0, 3.0, 2.0]
intensity = 5.0
[[lights]]
type = "directional"
direction = [0.0, -1.0, -1.0]
[[materials]]
name = "m"
kd = [0.5, 0.4, 0.3]
ks = [0.2, 0.2, 0.2]
[[objects]]
name = "ball"
material = "m"
shape = { type = "sphere", radius = 0.5 }
translate = [0.0, 0.5, 0.0]
[[objects]]
name = "floor"
material = "m"
shape = { type = "plane", width = 4.0, depth = 4.0 }
"#;

fn cpu_sweep(args: &[&str]) -> Result<Sweep, SweepError> {
    let scene = Scene::from_toml(CPU_SCENE, "cpu.toml", Path::new(".")).unwrap();
    Sweep::new(
        "cpu.toml",
        scene,
        axes(args),
        SweepOptions {
            frames: 1,
            warmup: 0,
            reference: ReferenceKind::Cpu,
            ..SweepOptions::default()
        },
    )
}

#[test]
fn cpu_reference_is_per_scene_and_never_the_row_itself() {
    let sweep = cpu_sweep(&[
        "size=16x8",
        "tessellation=0.5,1",
        "hdr_format=rgba16f,rgba32f",
    ])
    .unwrap();
    let c = sweep.combinations();
    assert!(c.iter().all(|c| c.values == c.reference));
    let references = RefCell::new(0);
    let result = sweep
        .run(
            |scene, job| {
                *references.borrow_mut() += usize::from(job == Job::Reference);
                fake_render(scene, job)
            },
            |_, _| {},
        )
        .unwrap();
    // Neither tessellation nor format changes the exact image: one
    // reference for all four rows.
    assert_eq!(references.into_inner(), 1);
    assert_eq!(result.reference, ReferenceKind::Cpu);
    assert!(result.rows.iter().all(|r| !r.is_reference && r.rmse > 0.0));
    assert!(result.rows[0].rmse > result.rows[2].rmse);
    let csv = to_csv(&result).unwrap();
    assert!(
        csv.lines().skip(1).all(|l| l.contains(",cpu,false,")),
        "{csv}"
    );
    let json = serde_json::to_string(&result).unwrap();
    assert!(json.contains(r#""reference":"cpu""#), "{json}");
    assert!(to_table(&result).starts_with("errors against the exact CPU image"));
    let svg = to_svg(&result).unwrap();
    assert!(svg.contains("exact CPU image") && !svg.contains("(reference)"));

    // Fewer lights is another exact image: one reference per count.
    let sweep = cpu_sweep(&["size=16x8", "lights=1,2", "hdr_format=rgba16f,rgba32f"]).unwrap();
    let references = RefCell::new(0);
    sweep
        .run(
            |scene, job| {
                *references.borrow_mut() += usize::from(job == Job::Reference);
                fake_render(scene, job)
            },
            |_, _| {},
        )
        .unwrap();
    assert_eq!(references.into_inner(), 2);
}

#[test]
fn cpu_reference_refuses_unsupported_scenes_before_rendering() {
    let err = Sweep::new(
        "default",
        Scene::default_scene(),
        axes(&["tessellation=0.5,1"]),
        SweepOptions {
            reference: ReferenceKind::Cpu,
            ..SweepOptions::default()
        },
    )
    .err()
    .map(|e| e.to_string())
    .unwrap();
    assert!(
        err.contains("--reference cpu") && err.contains("'ring'") && err.contains("torus"),
        "{err}"
    );
    let err = cpu_sweep(&["shading=phong,toon"])
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("shading=toon") && err.contains("toon shading"),
        "{err}"
    );
}

#[test]
fn outputs_are_written_whole() {
    let dir = std::env::temp_dir().join(format!("aerial-sweep-unit-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let sweep = Sweep::new(
        "default",
        Scene::default_scene(),
        axes(&[
            "size=32x16",
            "tessellation=0.5,1",
            "hdr_format=rgba16f,rgba32f",
        ]),
        SweepOptions {
            frames: 2,
            ..SweepOptions::default()
        },
    )
    .unwrap();
    let result = sweep.run(fake_render, |_, _| {}).unwrap();
    let written = write_outputs(&result, &dir).unwrap();
    assert_eq!(written.len(), 3);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["sweep.csv", "sweep.json", "sweep.svg"]);
    let svg = std::fs::read_to_string(dir.join("sweep.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("0.5, rgba16f"), "labels use the varying knobs");
    assert!(
        !svg.contains("32x16, 0.5"),
        "fixed knobs are not in the labels"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The relative error against hand-made images: relative to each
/// reference pixel's brightest channel, with dark pixels measured against
/// a thousandth of the 99th-percentile brightness, not against themselves.
#[test]
fn max_relative_error_is_relative_with_a_floor_for_dark_pixels() {
    let image = |pixels: &[[f32; 3]]| Pixels {
        width: pixels.len() as u32,
        height: 1,
        data: pixels
            .iter()
            .flat_map(|p| [p[0], p[1], p[2], 1.0])
            .collect(),
    };
    // 200 sky pixels at 0.1, one sun pixel at 1e4, one black pixel.
    let mut reference = vec![[0.1f32, 0.05, 0.2]; 200];
    reference.push([1e4, 1e4, 1e4]);
    reference.push([0.0, 0.0, 0.0]);
    let same = image(&reference);
    assert_eq!(crate::sweep::max_relative_error(&same, &same), 0.0);
    // 1 % off in the green channel of one sky pixel: relative to its
    // brightest channel (0.2), not to the green itself.
    let mut test = reference.clone();
    test[7][1] += 0.002;
    let e = crate::sweep::max_relative_error(&same, &image(&test));
    assert!((e - 0.01).abs() < 1e-6, "{e}");
    // The black pixel lit to 1e-5: measured against 1e-3 of the 99th
    // percentile (0.2, not the sun's 1e4), so 1e-5 / 2e-4.
    let mut test = reference.clone();
    test[201] = [1e-5, 0.0, 0.0];
    let e = crate::sweep::max_relative_error(&same, &image(&test));
    assert!((e - 0.05).abs() < 1e-6, "{e}");
}

/// `--shard` with the given environment.
fn parse_shard(spec: &str, env: &[(&str, &str)]) -> Result<Shard, String> {
    Shard::parse(spec, |name| {
        env.iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| v.to_string())
    })
    .map_err(|e| e.to_string())
}

#[test]
fn shard_specs_and_their_errors() {
    let shard = |index, count| Ok(Shard { index, count });
    assert_eq!(parse_shard("0/3", &[]), shard(0, 3));
    assert_eq!(parse_shard("2/3", &[]), shard(2, 3));
    assert_eq!(
        parse_shard("kubernetes/4", &[("JOB_COMPLETION_INDEX", "3")]),
        shard(3, 4)
    );
    // Arrays numbered from 1 and from 0 both give 0-based shards.
    let slurm = |id, min, count| {
        parse_shard(
            "slurm",
            &[
                ("SLURM_ARRAY_TASK_ID", id),
                ("SLURM_ARRAY_TASK_MIN", min),
                ("SLURM_ARRAY_TASK_COUNT", count),
            ],
        )
    };
    assert_eq!(slurm("3", "1", "3"), shard(2, 3));
    assert_eq!(slurm("0", "0", "3"), shard(0, 3));
    for (spec, env, expected) in [
        ("3/3", &[][..], "shard index 3 is out of range for 3 shards"),
        ("0/0", &[], "at least 1 shard"),
        ("1", &[], "no '/'"),
        ("-1/3", &[], "I is not a whole number"),
        ("a/3", &[], "I is not a whole number"),
        ("0/x", &[], "N is not a whole number"),
        ("kubernetes/3", &[], "JOB_COMPLETION_INDEX is not set"),
        // A number from a scheduler's variable names the variable.
        (
            "kubernetes/3",
            &[("JOB_COMPLETION_INDEX", "3")],
            "shard index 3 (JOB_COMPLETION_INDEX 3) is out of range",
        ),
        (
            "kubernetes/3",
            &[("JOB_COMPLETION_INDEX", "one")],
            "JOB_COMPLETION_INDEX is 'one'",
        ),
        ("slurm", &[], "SLURM_ARRAY_TASK_ID is not set"),
    ] {
        let err = parse_shard(spec, env).unwrap_err();
        assert!(err.contains(expected), "{spec}: {err}");
    }
    assert!(slurm("0", "1", "3")
        .unwrap_err()
        .contains("below SLURM_ARRAY_TASK_MIN"));
    let e = slurm("4", "1", "3").unwrap_err();
    assert!(
        e.contains("out of range")
            && e.contains("SLURM_ARRAY_TASK_ID 4 - SLURM_ARRAY_TASK_MIN 1")
            && e.contains("SLURM_ARRAY_TASK_COUNT 3"),
        "{e}"
    );
    let e = slurm("1", "1", "0").unwrap_err();
    assert!(
        e.contains("at least 1 shard (SLURM_ARRAY_TASK_COUNT 0)"),
        "{e}"
    );
    // Given by hand, the numbers need no source.
    assert_eq!(Shard::source("3/4"), "");
    assert!(Shard::source("kubernetes/4").contains("JOB_COMPLETION_INDEX"));
    assert!(Shard::source(" slurm").contains("SLURM_ARRAY_TASK_COUNT"));
}

fn shard_sweep() -> Sweep {
    let mut sweep = Sweep::new(
        "default",
        Scene::default_scene(),
        axes(&[
            "size=32x16",
            "tessellation=0.25,0.5,1",
            "hdr_format=rgba16f,rgba32f",
        ]),
        SweepOptions {
            frames: 2,
            warmup: 0,
            ..SweepOptions::default()
        },
    )
    .unwrap();
    sweep.set_scene_hash(scene_hash(b"the scene"));
    sweep
}

/// Shard `index` of `count` of [`shard_sweep`], as `merge` reads it.
fn run_shard(index: usize, count: usize) -> (std::path::PathBuf, SweepResult) {
    let shard = Shard { index, count };
    let result = shard_sweep()
        .run_shard(Some(shard), fake_render, |_, _| {})
        .unwrap();
    (format!("s{index}/sweep.json").into(), result)
}

#[test]
fn shards_hold_round_robin_slices_and_render_their_own_references() {
    let shard = Shard { index: 1, count: 4 };
    assert_eq!(shard.combinations(6), [1, 5]);
    assert!(shard.holds(5) && !shard.holds(4));

    // Shard 0 of 4 holds combinations 0 and 4: (0.25, rgba16f) and
    // (1, rgba16f); both are compared with (1, rgba32f), which is no row
    // of this shard, so it renders that image itself.
    let jobs = RefCell::new(Vec::new());
    let result = shard_sweep()
        .run_shard(
            Some(Shard { index: 0, count: 4 }),
            |scene, job| {
                jobs.borrow_mut().push((
                    scene.output.hdr_format,
                    scene.objects[0].tessellation,
                    job,
                ));
                fake_render(scene, job)
            },
            |_, _| {},
        )
        .unwrap();
    let indices: Vec<usize> = result.rows.iter().map(|r| r.index).collect();
    assert_eq!(indices, [0, 4]);
    assert_eq!(result.shard, Some(Shard { index: 0, count: 4 }));
    assert_eq!(result.combinations, 6);
    assert_eq!(result.axes[1], "tessellation=0.25,0.5,1");
    let images = jobs
        .borrow()
        .iter()
        .filter(|(_, _, j)| *j == Job::Images)
        .count();
    assert_eq!(images, 3, "{:?}", jobs.borrow());
    assert!(result.rows.iter().all(|r| r.rmse > 0.0));
    // The fake floor is 0.5 ms.
    for r in &result.rows {
        assert_eq!(r.empty_median_ms, Some(0.5));
        assert_eq!(r.gpu_x_empty, Some(r.gpu_ms.median / 0.5));
    }

    let err = shard_sweep()
        .run_shard(Some(Shard { index: 0, count: 7 }), fake_render, |_, _| {})
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("only 6 combinations"), "{err}");
}

#[test]
fn merged_shards_are_the_whole_sweep() {
    let whole = shard_sweep().run(fake_render, |_, _| {}).unwrap();
    // Given in any order, through their JSON like the CLI reads them.
    let shards: Vec<_> = [2, 0, 1]
        .into_iter()
        .map(|i| {
            let (path, result) = run_shard(i, 3);
            let json = serde_json::to_string_pretty(&result).unwrap();
            (path, serde_json::from_str::<SweepResult>(&json).unwrap())
        })
        .collect();
    let merged = merge(shards).unwrap();
    assert_eq!(merged.rows.len(), whole.rows.len());
    assert_eq!(merged.knobs, whole.knobs);
    assert_eq!(merged.passes, whole.passes);
    assert_eq!(merged.setup, whole.setup);
    assert_eq!(merged.shard, None);
    assert_eq!(merged.time_axis, TimeAxis::GpuXEmpty);
    assert_eq!(merged.shards.len(), 3);
    for (m, w) in merged.rows.iter().zip(&whole.rows) {
        assert_eq!(m.index, w.index);
        assert_eq!(m.settings, w.settings);
        assert_eq!(m.reference, w.reference);
        assert_eq!(m.is_reference, w.is_reference);
        for (a, b) in [
            (m.rmse, w.rmse),
            (m.max_rel_error, w.max_rel_error),
            (m.flip_mean, w.flip_mean),
            (m.flip_p99, w.flip_p99),
        ] {
            assert_eq!(a.to_bits(), b.to_bits(), "{:?}", m.settings);
        }
    }
    // The front is recomputed over the whole sweep, by multiples of the
    // floor.
    let points: Vec<(f64, f64)> = merged
        .rows
        .iter()
        .map(|r| (r.gpu_x_empty.unwrap(), r.rmse))
        .collect();
    let front: Vec<bool> = merged.rows.iter().map(|r| r.pareto).collect();
    assert_eq!(front, pareto_front(&points));
    assert!(to_csv(&merged).is_ok() && to_svg(&merged).is_ok());
}

#[test]
fn merge_refuses_what_is_not_one_whole_sweep() {
    let err =
        |shards: Vec<(std::path::PathBuf, SweepResult)>| merge(shards).unwrap_err().to_string();
    let e = err(vec![run_shard(0, 3), run_shard(2, 3)]);
    assert_eq!(e, "1 of 3 shards missing: shard 1");
    let e = err(vec![run_shard(1, 3)]);
    assert_eq!(e, "2 of 3 shards missing: shards 0, 2");
    let e = err(vec![
        run_shard(0, 3),
        run_shard(1, 3),
        run_shard(1, 3),
        run_shard(2, 3),
    ]);
    assert!(e.contains("shard 1 is given twice"), "{e}");
    let e = err(vec![run_shard(0, 2), run_shard(1, 3)]);
    assert!(e.contains("shard count differs (3 against 2)"), "{e}");
    assert!(err(Vec::new()).contains("nothing to merge"));

    // Each identifying field, changed in one shard, is named.
    type Change = fn(&mut SweepResult);
    let changes: [(&str, Change); 6] = [
        ("scene_hash", |r| {
            r.scene_hash = scene_hash(b"another scene")
        }),
        ("axes", |r| r.axes[1] = "tessellation=0.25,0.5,2".into()),
        ("frames", |r| r.frames = 3),
        ("warmup", |r| r.warmup = 1),
        ("reference", |r| r.reference = ReferenceKind::Cpu),
        ("aerial_version", |r| r.aerial_version = "0.0.1".into()),
    ];
    for (field, change) in changes {
        let mut odd = run_shard(1, 3);
        change(&mut odd.1);
        let e = err(vec![run_shard(0, 3), odd, run_shard(2, 3)]);
        assert!(
            e.contains(&format!(
                "s1/sweep.json is a shard of a different sweep than s0/sweep.json: {field} differs"
            )),
            "{field}: {e}"
        );
    }

    // The same scene file kept elsewhere on another machine is the same
    // sweep.
    let mut moved = run_shard(1, 3);
    moved.1.scene = "elsewhere/default.toml".into();
    assert!(merge(vec![run_shard(0, 3), moved, run_shard(2, 3)]).is_ok());

    // A hand-edited shard that is no shard.
    for (index, count) in [(3, 3), (0, 0)] {
        let mut odd = run_shard(1, 3);
        odd.1.shard = Some(Shard { index, count });
        let e = err(vec![run_shard(0, 3), odd]);
        assert!(
            e.contains(&format!("shard {index} of {count} is no shard")),
            "{e}"
        );
    }

    // Rows that are not the shard's slice, and a whole sweep.
    let mut odd = run_shard(1, 3);
    odd.1.rows.pop();
    let e = err(vec![run_shard(0, 3), odd, run_shard(2, 3)]);
    assert!(
        e.contains("should hold combinations 1, 4 but holds 1"),
        "{e}"
    );
    let whole = (
        "w/sweep.json".into(),
        shard_sweep().run(fake_render, |_, _| {}).unwrap(),
    );
    let e = err(vec![run_shard(0, 3), whole]);
    assert!(
        e.contains("w/sweep.json is not the output of one shard"),
        "{e}"
    );
}

/// Rows are checked against the sweep they claim to belong to: a row
/// whose settings, reference or values contradict it is refused naming
/// the file, the row, the combination and the field, whichever way it was
/// changed.
#[test]
fn merge_refuses_rows_that_contradict_their_sweep() {
    type Change = fn(&mut SweepResult);
    let changes: [(Change, &str); 16] = [
        // Shard 1 of 3 holds combinations 1 and 4: their labels swapped.
        (
            |r| {
                let a = r.rows[0].settings.clone();
                r.rows[0].settings = r.rows[1].settings.clone();
                r.rows[1].settings = a;
            },
            "rows[0] (combination 1): settings: 'size=32x16 tessellation=1 hdr_format=rgba16f' \
             contradicts the row's index, which is 'size=32x16 tessellation=0.25 \
             hdr_format=rgba32f'",
        ),
        (
            |r| r.rows[1].settings[1].1 = "2".into(),
            "rows[1] (combination 4): settings",
        ),
        (
            |r| r.rows[1].settings[0].0 = "width".into(),
            "rows[1] (combination 4): settings",
        ),
        (
            |r| {
                r.rows[0].settings.pop();
            },
            "rows[0] (combination 1): settings",
        ),
        (
            |r| r.rows[0].reference[2].1 = "rgba16f".into(),
            "rows[0] (combination 1): reference",
        ),
        (
            |r| r.rows[0].is_reference = true,
            "rows[0] (combination 1): is_reference: true",
        ),
        (
            |r| r.rows[1].rmse = -1.0,
            "rows[1] (combination 4): rmse: -1 is not",
        ),
        (|r| r.rows[1].rmse = f64::NAN, "rmse: NaN is not"),
        (
            |r| r.rows[0].flip_mean = 1.5,
            "flip_mean: 1.5 is not a number from 0 to 1",
        ),
        (
            |r| r.rows[0].max_rel_error = f64::INFINITY,
            "max_rel_error: inf",
        ),
        (|r| r.rows[0].gpu_ms.median = -0.5, "gpu_ms.median: -0.5"),
        (|r| r.rows[0].cpu_ms.max = 0.0, "cpu_ms: min"),
        (
            |r| r.rows[0].pass_median_ms[0].1 = -2.0,
            "pass_median_ms.opaque: -2",
        ),
        (
            |r| r.rows[0].empty_median_ms = Some(0.0),
            "empty_median_ms: 0",
        ),
        (
            |r| r.rows[0].gpu_x_empty = Some(123.0),
            "gpu_x_empty: 123 is not gpu_ms.median",
        ),
        (|r| r.knobs.swap(0, 1), "knobs: "),
    ];
    for (change, expected) in changes {
        let mut odd = run_shard(1, 3);
        change(&mut odd.1);
        let e = merge(vec![run_shard(0, 3), odd, run_shard(2, 3)])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s1/sweep.json: ") && e.contains(expected),
            "expected '{expected}' in: {e}"
        );
    }
    // Unchanged, the same shards merge.
    assert!(merge(vec![run_shard(0, 3), run_shard(1, 3), run_shard(2, 3)]).is_ok());
}

/// A merged sweep with errors near the largest float still plots (the
/// plot's axes once looped forever past 1e305).
#[test]
fn merged_rows_with_huge_errors_plot() {
    let mut odd = run_shard(1, 3);
    odd.1.rows[0].rmse = 1e306;
    odd.1.rows[1].rmse = f64::MAX;
    let merged = merge(vec![run_shard(0, 3), odd, run_shard(2, 3)]).unwrap();
    let (send, receive) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = send.send(to_svg(&merged).map(|svg| svg.len()));
    });
    let svg = receive
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("the plot did not finish");
    assert!(svg.unwrap() > 0);
}
