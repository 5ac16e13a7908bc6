//! Hostile inputs and failure paths: every case must end with the right
//! exit code (2 for errors, 1 for a failed gate), a message naming the
//! file, field or object and the reason, and no output file created,
//! changed or left half-written. Renders run under `--validate`, so a
//! render that succeeds also had zero validation messages.
//!
//! Fixtures are in `tests/hostile/`; `tests/hostile/bad_scenes/*.toml`
//! start with `# expect: MESSAGE` (must fail with it) or `# renders`.

use crate::common;
use crate::common::Scratch;

use aerial::render::Pixels;
use aerial::scene::ToneMapOperator;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/hostile")
        .join(name)
}

/// Runs `aerial` with `args` and the extra environment `env`.
fn run_aerial(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = common::aerial();
    cmd.args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("aerial runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Asserts exit code `code` and that stderr contains every `needles`.
fn assert_fails(out: &Output, code: i32, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(code), "stderr:\n{err}");
    for n in needles {
        assert!(err.contains(n), "expected {n:?} in stderr:\n{err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(!err.contains("VUID"), "{err}");
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn an_unmatched_device_lists_the_devices_and_exits_2() {
    let dir = Scratch::new();
    let out = dir.path("out.png");
    for device in ["99", "-1", "no such device"] {
        let device = format!("--device={device}");
        for validate in [false, true] {
            let mut args = vec!["render", "--out", s(&out), &device];
            if validate {
                args.push("--validate");
            }
            assert_fails(&run_aerial(&args, &[]), 2, &["no Vulkan 1.2 device", "0: "]);
        }
    }
    let input = dir.path("in.exr");
    let pixels = Pixels {
        width: 2,
        height: 1,
        data: vec![0.5; 8],
    };
    aerial::image_io::write_exr(&input, &pixels).unwrap();
    let tonemap = run_aerial(
        &[
            "tonemap",
            s(&input),
            "--out",
            s(&out),
            "--device",
            "99",
            "--validate",
        ],
        &[],
    );
    assert_fails(&tonemap, 2, &["no Vulkan 1.2 device"]);
    assert_eq!(dir.entries(), ["in.exr"]);
}

#[test]
fn an_exr_whose_header_claims_a_huge_image_is_refused_before_reading() {
    let dir = Scratch::new();
    let out = dir.path("out.png");
    let result = run_aerial(
        &["tonemap", s(&fixture("huge_header.exr")), "--out", s(&out)],
        &[],
    );
    assert_fails(
        &result,
        2,
        &["huge_header.exr", "100000x100000", "1..=16384"],
    );
    assert!(dir.entries().is_empty());
}

#[test]
fn the_memory_budget_refuses_large_outputs_and_meshes_by_name() {
    let dir = Scratch::new();
    let out = dir.path("out.png");
    let budget = [("AERIAL_MEMORY_BUDGET", "64M")];
    let big = run_aerial(
        &[
            "render",
            "--width",
            "16384",
            "--height",
            "16384",
            "--out",
            s(&out),
        ],
        &budget,
    );
    assert_fails(
        &big,
        2,
        &[
            "output size 16384x16384",
            "AERIAL_MEMORY_BUDGET",
            "64.0 MiB",
        ],
    );
    let mesh = run_aerial(
        &[
            "render",
            s(&fixture("big_tessellation.toml")),
            "--out",
            s(&out),
        ],
        &budget,
    );
    assert_fails(
        &mesh,
        2,
        &[
            "objects[0] \"thing\"",
            "tessellation 4096x4096",
            "memory budget",
        ],
    );
    let bad = run_aerial(
        &["render", "--out", s(&out)],
        &[("AERIAL_MEMORY_BUDGET", "lots")],
    );
    assert_fails(&bad, 2, &["AERIAL_MEMORY_BUDGET=\"lots\""]);
    // The same size within the budget renders (small enough for a test).
    let ok = run_aerial(
        &[
            "render",
            "--width",
            "32",
            "--height",
            "16",
            "--validate",
            "--out",
            s(&out),
        ],
        &budget,
    );
    assert_eq!(ok.status.code(), Some(0), "{}", stderr(&ok));
    assert_eq!(dir.entries(), ["out.png"]);
}

/// The seed's 4096² optical-depth table is 256 MiB, held three times while
/// it is uploaded (the baked texels, the staging buffer and the image): refused by name
/// under a budget below that, before the (minutes long) bake starts.
#[test]
fn the_memory_budget_refuses_the_seeds_table_by_name() {
    let dir = Scratch::new();
    let scene = dir.path("seed.toml");
    std::fs::write(
        &scene,
        "[camera]\neye = [0.0, 2.0, 0.0]\nlook_at = [0.0, 2.0, -1.0]\n\
         [sun]\ndirection = [0.0, 1.0, 0.0]\n\
         [atmosphere]\nod_table_size = [4096, 4096]\nod_table_mapping = \"seed\"\n",
    )
    .unwrap();
    let out = dir.path("out.png");
    let started = std::time::Instant::now();
    let refused = run_aerial(
        &["render", s(&scene), "--out", s(&out)],
        &[("AERIAL_MEMORY_BUDGET", "600M")],
    );
    assert_fails(
        &refused,
        2,
        &[
            "optical-depth table 4096x4096",
            "768.0 MiB",
            "memory budget",
        ],
    );
    assert!(
        started.elapsed().as_secs() < 60,
        "refused only after baking"
    );
    assert_eq!(dir.entries(), ["seed.toml"]);
}

#[test]
fn textures_beyond_the_device_limits_are_refused_with_the_limit() {
    let dir = Scratch::new();
    let out = dir.path("out.png");
    let wide = run_aerial(
        &[
            "render",
            s(&fixture("texture_wide.toml")),
            "--validate",
            "--out",
            s(&out),
        ],
        &[],
    );
    assert_fails(
        &wide,
        2,
        &[
            "wide_16385x1.png",
            "16385x1",
            "maxImageDimension2D",
            "texture_wide.toml",
        ],
    );
    let huge = run_aerial(
        &["render", s(&fixture("texture_huge.toml")), "--out", s(&out)],
        &[],
    );
    assert_fails(&huge, 2, &["claims_16384.png", "16384x16384", "512.0 MiB"]);
    assert!(!stderr(&huge).contains("Memory limit exceeded"));
    assert!(dir.entries().is_empty());
}

#[test]
fn texture_formats_are_detected_from_the_content() {
    let dir = Scratch::new();
    for scene in ["texture_misnamed.toml", "texture_no_extension.toml"] {
        let out = dir.path(&format!("{scene}.png"));
        let run = run_aerial(
            &["render", s(&fixture(scene)), "--validate", "--out", s(&out)],
            &[],
        );
        assert_eq!(run.status.code(), Some(0), "{scene}: {}", stderr(&run));
        assert!(out.is_file());
    }
    let out = dir.path("jpeg.png");
    let jpeg = run_aerial(
        &["render", s(&fixture("texture_jpeg.toml")), "--out", s(&out)],
        &[],
    );
    assert_fails(&jpeg, 2, &["jpeg_texture.png", "not a readable JPEG file"]);
    assert!(!out.exists());
}

#[test]
fn outputs_are_never_renamed_over_non_regular_files() {
    let dir = Scratch::new();
    let run = run_aerial(
        &[
            "render",
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            "/dev/null",
        ],
        &[],
    );
    assert_fails(&run, 2, &["/dev/null", "not a regular file"]);
    let folder = dir.path("folder");
    std::fs::create_dir(&folder).unwrap();
    let run = run_aerial(
        &[
            "render",
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            s(&folder),
        ],
        &[],
    );
    assert_fails(&run, 2, &["it is a folder"]);
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let meta = std::fs::metadata("/dev/null").unwrap();
        assert!(meta.file_type().is_char_device());
    }
    assert_eq!(dir.entries(), ["folder"]);
}

#[test]
fn concurrent_renders_to_one_path_leave_one_whole_file() {
    let dir = Scratch::new();
    let out = dir.path("same.png");
    let children: Vec<_> = (0..4)
        .map(|i| {
            let (w, h) = (48 + 8 * i, 24 + 4 * i);
            Command::new(env!("CARGO_BIN_EXE_aerial"))
                .args([
                    "render",
                    "--width",
                    &w.to_string(),
                    "--height",
                    &h.to_string(),
                ])
                .args(["--out", s(&out)])
                .output()
        })
        .collect();
    for c in children {
        let c = c.unwrap();
        assert_eq!(c.status.code(), Some(0), "{}", stderr(&c));
    }
    // Whole: decodes to the end, and nothing follows the IEND chunk.
    aerial::image_io::read_png_text(&out).expect("a complete PNG");
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(&bytes[bytes.len() - 8..bytes.len() - 4], b"IEND");
    assert_eq!(dir.entries(), ["same.png"]);
}

#[test]
fn a_failed_run_leaves_none_of_its_outputs_and_keeps_old_files() {
    let dir = Scratch::new();
    let png = dir.path("a.png");
    let missing = dir.path("nodir/x.exr");
    // An 8x8 render of the default scene to `out` and `hdr`.
    let render = |out: &Path, hdr: &Path| {
        run_aerial(
            &[
                "render",
                "--width",
                "8",
                "--height",
                "8",
                "--out",
                s(out),
                "--hdr",
                s(hdr),
            ],
            &[],
        )
    };
    // A run that fails: the --hdr output's folder does not exist.
    let failing_run = || render(&png, &missing);
    let run = failing_run();
    assert_fails(&run, 2, &["nodir"]);
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());

    // An existing file is left as it was when the run fails.
    std::fs::write(&png, b"old").unwrap();
    let run = failing_run();
    assert_fails(&run, 2, &["nodir"]);
    assert_eq!(std::fs::read(&png).unwrap(), b"old");
    let same = render(&png, &png);
    assert_fails(&same, 2, &["same file"]);
    assert_eq!(dir.entries(), ["a.png"]);
}

/// A tiny benchmark report to gate against.
fn bench_report(dir: &Scratch) -> PathBuf {
    let base = dir.path("base.json");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench/triangle.toml");
    let run = run_aerial(
        &[
            "bench",
            s(&scene),
            "--frames",
            "1",
            "--warmup",
            "0",
            "--width",
            "16",
            "--height",
            "16",
            "--json",
            s(&base),
        ],
        &[],
    );
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    base
}

/// Rewrites every `"median"` in a report with `f(median)`.
fn with_medians(from: &Path, to: &Path, f: impl Fn(f64) -> f64 + Copy) {
    fn walk(v: &mut serde_json::Value, f: impl Fn(f64) -> f64 + Copy) {
        match v {
            serde_json::Value::Object(m) => {
                for (k, x) in m.iter_mut() {
                    if k == "median" {
                        if let Some(n) = x.as_f64() {
                            *x = serde_json::json!(f(n));
                        }
                    } else {
                        walk(x, f);
                    }
                }
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(|x| walk(x, f)),
            _ => {}
        }
    }
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(from).unwrap()).unwrap();
    walk(&mut v, f);
    std::fs::write(to, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

#[test]
fn the_bench_gate_fails_when_it_compared_nothing_and_exits_1_on_slowdowns() {
    let dir = Scratch::new();
    let base = bench_report(&dir);
    let before = std::fs::read(&base).unwrap();

    // Writing the run over the baseline it is compared with is refused.
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench/triangle.toml");
    let same = run_aerial(
        &[
            "bench",
            s(&scene),
            "--frames",
            "1",
            "--warmup",
            "0",
            "--width",
            "16",
            "--height",
            "16",
            "--json",
            s(&base),
            "--compare",
            s(&base),
            "--max-ratio",
            "1.5",
        ],
        &[],
    );
    assert_fails(&same, 2, &["--json and --compare name the same file"]);
    assert_eq!(std::fs::read(&base).unwrap(), before);

    // Zero and negative baseline medians: nothing compared, so no pass.
    for (name, f) in [("zero.json", 0.0), ("negative.json", -1.0)] {
        let bad = dir.path(name);
        with_medians(&base, &bad, |_| f);
        let gate = run_aerial(
            &[
                "bench",
                "--from-json",
                s(&base),
                "--compare",
                s(&bad),
                "--max-ratio",
                "1.5",
            ],
            &[],
        );
        assert_fails(&gate, 2, &["no usable baseline median", name]);
    }
    // A baseline 1000 times faster: a threshold failure, exit 1.
    let fast = dir.path("fast.json");
    with_medians(&base, &fast, |m| m / 1000.0);
    let gate = run_aerial(
        &[
            "bench",
            "--from-json",
            s(&base),
            "--compare",
            s(&fast),
            "--max-ratio",
            "1.5",
        ],
        &[],
    );
    assert_fails(&gate, 1, &["slower than --max-ratio 1.5"]);
    // Against itself: passes.
    let gate = run_aerial(
        &[
            "bench",
            "--from-json",
            s(&base),
            "--compare",
            s(&base),
            "--max-ratio",
            "1.5",
        ],
        &[],
    );
    assert_eq!(gate.status.code(), Some(0), "{}", stderr(&gate));
    assert_eq!(std::fs::read(&base).unwrap(), before);
}

#[test]
fn sweeps_check_the_output_folder_and_knob_values_before_rendering() {
    let dir = Scratch::new();
    let file = dir.path("FILE");
    std::fs::write(&file, b"keep").unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let run = run_aerial(
        &[
            "sweep",
            s(&scene),
            "--knob",
            "tessellation=0.5,1",
            "--out-dir",
            s(&file),
        ],
        &[],
    );
    assert_fails(&run, 2, &["FILE", "not a folder"]);
    // Failed before any render ("N combinations" is printed before them).
    assert!(!stderr(&run).contains("combinations"), "{}", stderr(&run));
    let run = run_aerial(
        &[
            "sweep",
            s(&scene),
            "--knob",
            "tessellation=1,1e9",
            "--out-dir",
            s(&dir.path("out")),
        ],
        &[],
    );
    assert_fails(&run, 2, &["tessellation=1e9", "at most 4096"]);
    assert_eq!(std::fs::read(&file).unwrap(), b"keep");
    assert_eq!(dir.entries(), ["FILE"]);
}

#[test]
fn bad_scene_values_are_rejected_with_the_field_and_reason_or_render() {
    let dir = Scratch::new();
    let out = dir.path("out.png");
    let mut count = 0;
    for entry in std::fs::read_dir(fixture("bad_scenes")).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let first = text.lines().next().unwrap();
        let run = run_aerial(&["render", s(&path), "--validate", "--out", s(&out)], &[]);
        if let Some(expect) = first.strip_prefix("# expect: ") {
            let name = path.file_name().unwrap().to_str().unwrap();
            assert_fails(&run, 2, &[name, expect]);
            assert!(!out.exists(), "{name}");
        } else {
            assert_eq!(
                run.status.code(),
                Some(0),
                "{}: {}",
                path.display(),
                stderr(&run)
            );
            std::fs::remove_file(&out).unwrap();
        }
        count += 1;
    }
    assert!(count >= 10);
}

#[test]
fn too_many_lights_name_the_scene_file_and_the_object() {
    let dir = Scratch::new();
    let mut scene = String::from(
        "light_cutoff = 0.0\n[output]\nwidth = 8\nheight = 8\n[camera]\neye = [0.0, 0.0, 5.0]\n\
         look_at = [0.0, 0.0, 0.0]\n[[materials]]\nname = \"m\"\nkd = [0.5, 0.5, 0.5]\n\
         [[objects]]\nname = \"crowded\"\nmaterial = \"m\"\nshape = { type = \"sphere\", radius = 1.0 }\n",
    );
    for i in 0..5000 {
        scene.push_str(&format!(
            "[[lights]]\ntype = \"point\"\nposition = [{}.0, 2.0, 0.0]\nintensity = 0.001\n",
            i % 7
        ));
    }
    let path = dir.path("many.toml");
    std::fs::write(&path, scene).unwrap();
    let out = dir.path("out.png");
    let run = run_aerial(&["render", s(&path), "--out", s(&out)], &[]);
    assert_fails(
        &run,
        2,
        &["many.toml", "objects[0] \"crowded\"", "5000 lights"],
    );
    assert_eq!(dir.entries(), ["many.toml"]);
}

fn tone_map(values: &[f32], operator: ToneMapOperator, exposure: f32) -> Vec<u8> {
    let grey: Vec<[f32; 4]> = values.iter().map(|&v| [v, v, v, 1.0]).collect();
    common::tone_map_on_gpu(&grey, operator, exposure)
        .iter()
        .map(|c| c[0])
        .collect()
}

#[test]
fn the_tone_curve_is_monotonic_for_every_finite_exposure() {
    let inputs = [
        0.0,
        1e-30,
        1e-10,
        1e-3,
        0.5,
        1.0,
        1e3,
        65504.0,
        1e30,
        f32::MAX,
    ];
    for operator in [ToneMapOperator::Reinhard, ToneMapOperator::Aces] {
        for exposure in [1e-30, 1e-6, 1.0, 1e6, 1e20, 1e30, 3e38, f32::MAX] {
            let out = tone_map(&inputs, operator, exposure);
            assert!(
                out.windows(2).all(|w| w[0] <= w[1]),
                "{operator:?} at exposure {exposure}: {out:?}"
            );
            if exposure >= 1.0 {
                assert_eq!(
                    *out.last().unwrap(),
                    255,
                    "{operator:?} {exposure}: {out:?}"
                );
            }
        }
    }
}
