//! Hostile use of `bench` and `sweep`, one test per class of failure, each
//! trying several spellings of it: endless or blocking inputs, children
//! left running after an interrupt or a hang, another build than the one
//! named, shard rows that contradict their sweep or break the plot,
//! outputs that can only fail after the work, and messages that name
//! temporary files. No verdict here depends on the machine's speed: a
//! deadline only turns a hang into a failure.

use crate::common;
use aerial::report::stats::Summary;
use aerial::sweep::{ReferenceKind, Row, Shard, ShardSource, SweepResult, TimeAxis};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The environment variable that marks every process a test starts, and
/// so every process those start in turn.
const MARKER: &str = "AERIAL_HOSTILE_BENCH_TEST";

fn triangle() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench/triangle.toml")
}

/// The smallest `bench` run of the triangle, with `extra` arguments.
fn tiny_bench(extra: &[&str]) -> Command {
    let mut c = common::aerial();
    c.arg("bench")
        .arg(triangle())
        .args([
            "--frames", "1", "--warmup", "0", "--width", "32", "--height", "18",
        ])
        .args(extra);
    c
}

/// Runs `command` to its end, or kills it after `limit` and fails: an
/// input that blocks or never ends must not hang the test run.
fn output_within(command: &mut Command, limit: Duration, what: &str) -> Output {
    let mut child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            let _ = child.wait();
            panic!("{what}: still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn text(out: &Output) -> String {
    format!(
        "exit {:?}\nstdout: {}\nstderr: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Asserts exit 2 with every needle in standard error and no panic.
#[track_caller]
fn assert_refused(out: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{}", text(out));
    for n in needles {
        assert!(stderr.contains(n), "expected {n:?} in: {}", text(out));
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// The processes whose environment holds `MARKER=value`.
fn marked(value: &str) -> Vec<(u32, String)> {
    let needle = format!("{MARKER}={value}");
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            std::fs::read(format!("/proc/{pid}/environ"))
                .is_ok_and(|env| env.split(|&b| b == 0).any(|v| v == needle.as_bytes()))
        })
        .map(|pid| {
            let comm = std::fs::read_to_string(format!("/proc/{pid}/comm")).unwrap_or_default();
            (pid, comm.trim().to_string())
        })
        .collect()
}

/// Waits until no process carries `value` (a killed process needs a
/// moment to be torn down); returns those still there at the deadline.
fn wait_until_none_marked(value: &str) -> Vec<(u32, String)> {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let left = marked(value);
        if left.is_empty() || Instant::now() > deadline {
            return left;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Waits until a process other than `parent` carries `value` and
/// `wanted` accepts its name.
fn wait_for_child(parent: &mut Child, value: &str, wanted: impl Fn(&str) -> bool) {
    let deadline = Instant::now() + Duration::from_secs(300);
    loop {
        if marked(value)
            .iter()
            .any(|(pid, comm)| *pid != parent.id() && wanted(comm))
        {
            return;
        }
        if let Some(status) = parent.try_wait().unwrap() {
            panic!("{value}: bench ended ({status}) before its child was seen");
        }
        assert!(Instant::now() < deadline, "{value}: no child after 300 s");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A shell script at `path`, executable.
fn script(path: &Path, body: &str) {
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::write(path, format!("#!/bin/sh\n{body}")).unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// A stand-in for another aerial build: answers `--version` as aerial
/// does, and for anything else starts a sleeper in the background and
/// sleeps itself, so it never finishes.
fn hanging_build(path: &Path) {
    script(
        path,
        "if [ \"$1\" = --version ]; then echo 'aerial 0.0.1'; exit 0; fi\n\
         sleep 300 &\nsleep 300\n",
    );
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Class 2: every file `bench` and `sweep` read has a bound, and a device,
/// FIFO or folder is refused before it is opened: `/dev/zero` and links
/// to it, a FIFO nobody writes, a regular file past the bound, a folder;
/// as a scene, `--from-json`, `--compare`, a scene of `sweep` and a
/// shard's `sweep.json`. Each is an error naming the file and the bound,
/// within seconds, where it once read gigabytes or blocked forever.
#[test]
fn every_input_of_bench_and_sweep_is_bounded_and_never_blocks() {
    let dir = common::fresh_dir("hostile-bench", "inputs");
    let link = dir.join("zero-link.toml");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    let chain = dir.join("zero-chain.json");
    std::os::unix::fs::symlink(&link, &chain).unwrap();
    let fifo = dir.join("fifo.json");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo reads the NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let large = dir.join("large.json");
    std::fs::File::create(&large)
        .unwrap()
        .set_len((64 << 20) + 1)
        .unwrap();
    let folder = dir.join("folder.toml");
    std::fs::create_dir(&folder).unwrap();
    let good = dir.join("good.json");
    std::fs::write(
        &good,
        r#"{"format": "aerial-bench/1", "commit": "0", "aerial_version": "0.1.0",
            "build": "release", "device": {"name": "d", "driver_name": "", "driver_info": "",
            "driver_version": 0, "api_version": "1.3.0"}, "warmup": 0, "frames": 1,
            "validate": false, "empty_passes": [], "scenes": []}"#,
    )
    .unwrap();
    let out_dir = dir.join("out");
    let bad: [&Path; 6] = [
        Path::new("/dev/zero"),
        &link,
        &chain,
        &fifo,
        &large,
        &folder,
    ];
    for input in bad {
        let shown = input.display().to_string();
        // The shard folder whose sweep.json is this input.
        let shard = dir.join(format!(
            "shard-{}",
            input.file_name().unwrap().to_string_lossy()
        ));
        std::fs::create_dir_all(&shard).unwrap();
        let json = shard.join("sweep.json");
        let _ = std::fs::remove_file(&json);
        std::os::unix::fs::symlink(input, &json).unwrap();
        let runs: Vec<(Command, String)> = vec![
            (
                {
                    let mut c = common::aerial();
                    c.arg("bench").arg(input);
                    c
                },
                shown.clone(),
            ),
            (
                {
                    let mut c = common::aerial();
                    c.args(["bench", "--from-json"]).arg(input);
                    c
                },
                shown.clone(),
            ),
            (
                {
                    let mut c = common::aerial();
                    c.args(["bench", "--from-json"])
                        .arg(&good)
                        .arg("--compare")
                        .arg(input)
                        .args(["--max-ratio", "2"]);
                    c
                },
                shown.clone(),
            ),
            (
                {
                    let mut c = common::aerial();
                    c.arg("sweep")
                        .arg(input)
                        .args(["--knob", "size=8x8", "--out-dir"])
                        .arg(&out_dir);
                    c
                },
                shown.clone(),
            ),
            (
                {
                    let mut c = common::aerial();
                    c.args(["sweep", "merge"])
                        .arg(&shard)
                        .arg("--out-dir")
                        .arg(&out_dir);
                    c
                },
                json.display().to_string(),
            ),
        ];
        for (mut command, named) in runs {
            let what = format!("{command:?}");
            let out = output_within(&mut command, Duration::from_secs(120), &what);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_refused(&out, &[&named, "64.0 MiB"]);
            assert!(!stderr.contains("ok:"), "{what}: {stderr}");
        }
        assert!(!out_dir.exists(), "{}: wrote {}", shown, out_dir.display());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Class 3: an interrupt (SIGINT or SIGTERM) to `bench` stops every child
/// it started, whatever it was doing: valgrind counting instructions, the
/// other build of `--against` (with what it started), this build's own
/// round. The run exits 130 and leaves no process and no temporary folder
/// behind.
#[test]
fn interrupts_leave_no_child_and_no_temporary_folder() {
    let dir = common::fresh_dir("hostile-bench", "interrupts");
    let other = dir.join("other-build");
    hanging_build(&other);
    let tmp = dir.join("tmp");
    std::fs::create_dir_all(&tmp).unwrap();
    type Wanted = fn(&str) -> bool;
    let cases: [(&str, Vec<String>, Wanted); 3] = [
        (
            "valgrind",
            vec!["--metric".into(), "instructions".into()],
            |comm| comm.contains("grind"),
        ),
        (
            "other-build",
            vec![
                "--against".into(),
                other.display().to_string(),
                "--rounds".into(),
                "1".into(),
            ],
            |comm| comm == "sleep",
        ),
        (
            "round-child",
            vec![
                "--against".into(),
                env!("CARGO_BIN_EXE_aerial").into(),
                "--rounds".into(),
                "1000".into(),
            ],
            |comm| comm == "aerial",
        ),
    ];
    for (name, args, wanted) in cases {
        for signal in [libc::SIGINT, libc::SIGTERM] {
            let value = format!("{name}-{signal}-{}", std::process::id());
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let mut parent = tiny_bench(&args)
                .env(MARKER, &value)
                .env("TMPDIR", &tmp)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            wait_for_child(&mut parent, &value, wanted);
            // SAFETY: kill sends a signal to the process this test started.
            assert_eq!(unsafe { libc::kill(parent.id() as libc::pid_t, signal) }, 0);
            let start = Instant::now();
            while parent.try_wait().unwrap().is_none() {
                assert!(
                    start.elapsed() < Duration::from_secs(60),
                    "{value}: bench still running 60 s after the signal"
                );
                std::thread::sleep(Duration::from_millis(20));
            }
            let out = parent.wait_with_output().unwrap();
            assert_eq!(out.status.code(), Some(130), "{value}: {}", text(&out));
            assert_eq!(wait_until_none_marked(&value), Vec::new(), "{value}");
            assert_eq!(entries(&tmp), Vec::<String>::new(), "{value}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Whether signal `signal` is still pending for process `pid` (sent but not
/// yet taken by one of its threads): `ShdPnd` in its status. False once the
/// process is gone.
fn signal_pending(pid: u32, signal: libc::c_int) -> bool {
    let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else {
        return false;
    };
    status
        .lines()
        .filter_map(|l| l.strip_prefix("ShdPnd:"))
        .filter_map(|mask| u64::from_str_radix(mask.trim(), 16).ok())
        .any(|mask| mask & (1 << (signal - 1)) != 0)
}

/// A second interrupt while `bench` is stopping its children after the
/// first ends the process at once, and still leaves nothing behind: the
/// child's process group is killed and waited for, and the temporary
/// folder removed, before it exits. Before, the folder (valgrind's, or the
/// rounds' reports) stayed in `TMPDIR`. The second signal is sent as soon
/// as the first has been taken (no longer pending), so the two never merge
/// into one; that is a condition, not a delay, and the deadlines only turn
/// a hang into a failure.
#[test]
fn a_second_interrupt_during_cleanup_leaves_nothing_behind() {
    let dir = common::fresh_dir("hostile-bench", "second-interrupt");
    let other = dir.join("other-build");
    hanging_build(&other);
    let tmp = dir.join("tmp");
    std::fs::create_dir_all(&tmp).unwrap();
    type Wanted = fn(&str) -> bool;
    let cases: [(&str, Vec<String>, Wanted); 2] = [
        (
            "valgrind",
            vec!["--metric".into(), "instructions".into()],
            |comm| comm.contains("grind"),
        ),
        (
            "other-build",
            vec![
                "--against".into(),
                other.display().to_string(),
                "--rounds".into(),
                "1".into(),
            ],
            |comm| comm == "sleep",
        ),
    ];
    for (name, args, wanted) in cases {
        let value = format!("twice-{name}-{}", std::process::id());
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let mut parent = tiny_bench(&args)
            .env(MARKER, &value)
            .env("TMPDIR", &tmp)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        wait_for_child(&mut parent, &value, wanted);
        let pid = parent.id();
        // SAFETY: kill sends a signal to the process this test started.
        assert_eq!(unsafe { libc::kill(pid as libc::pid_t, libc::SIGINT) }, 0);
        let start = Instant::now();
        while signal_pending(pid, libc::SIGINT) {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "{value}: the first SIGINT still pending after 60 s"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
        // SAFETY: as above; the process may have ended already, but it is
        // not reaped, so the id is still its own.
        unsafe { libc::kill(pid as libc::pid_t, libc::SIGINT) };
        while parent.try_wait().unwrap().is_none() {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "{value}: bench still running 60 s after the signals"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        let out = parent.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(130), "{value}: {}", text(&out));
        assert!(text(&out).contains("no output written"), "{}", text(&out));
        assert_eq!(wait_until_none_marked(&value), Vec::new(), "{value}");
        assert_eq!(
            entries(&tmp),
            Vec::<String>::new(),
            "{value}: {}",
            text(&out)
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Class 3, hangs: another build that never answers `--version`, or never
/// finishes its round, is stopped after `--round-timeout` with everything
/// it started, and the run fails saying so, instead of waiting forever.
#[test]
fn a_hung_other_build_is_stopped_after_the_round_timeout() {
    let dir = common::fresh_dir("hostile-bench", "hang");
    let tmp = dir.join("tmp");
    std::fs::create_dir_all(&tmp).unwrap();
    let mute = dir.join("mute-build");
    script(&mute, "sleep 300 &\nsleep 300\n");
    let stuck = dir.join("stuck-build");
    hanging_build(&stuck);
    for (build, timeout) in [(&mute, "2"), (&stuck, "5")] {
        let value = format!("hang-{timeout}-{}", std::process::id());
        let mut command = tiny_bench(&["--rounds", "1", "--round-timeout", timeout]);
        command
            .arg("--against")
            .arg(build)
            .env(MARKER, &value)
            .env("TMPDIR", &tmp);
        let out = output_within(&mut command, Duration::from_secs(120), &value);
        // Which build runs out of time, this one or the stand-in, depends
        // on the machine; that one does and is stopped does not.
        assert_refused(
            &out,
            &[&format!(
                "did not finish within {timeout} s (--round-timeout); it was stopped"
            )],
        );
        if build == &mute {
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(stderr.contains("answering --version"), "{stderr}");
        }
        assert_eq!(wait_until_none_marked(&value), Vec::new(), "{value}");
        assert_eq!(entries(&tmp), Vec::<String>::new(), "{value}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Class 4: `--against NAME` runs the file it checked, `./NAME`, never a
/// program of that name found in `PATH`; under every spelling of the path
/// (bare, `./`, `sub/..`, absolute, a link). A name that exists only in
/// `PATH` is refused, and the program there is not run.
#[test]
fn against_runs_exactly_the_file_it_checked() {
    let dir = common::fresh_dir("hostile-bench", "which-build");
    let here = dir.join("here");
    let on_path = dir.join("on-path");
    std::fs::create_dir_all(here.join("sub")).unwrap();
    std::fs::create_dir_all(&on_path).unwrap();
    // Each says which ran by leaving a file next to itself; neither is
    // aerial, so the run stops at the check of its `--version`.
    let body = "touch \"$(dirname \"$0\")/ran\"\necho 'not aerial'\n";
    script(&here.join("other"), body);
    script(&on_path.join("other"), body);
    script(&on_path.join("only-on-path"), body);
    std::os::unix::fs::symlink(here.join("other"), here.join("link")).unwrap();
    let path = format!(
        "{}:{}",
        on_path.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let absolute = here.join("other").display().to_string();
    for spelling in ["other", "./other", "sub/../other", &absolute, "link"] {
        let _ = std::fs::remove_file(here.join("ran"));
        let _ = std::fs::remove_file(on_path.join("ran"));
        let out = tiny_bench(&["--against", spelling])
            .current_dir(&here)
            .env("PATH", &path)
            .output()
            .unwrap();
        assert_refused(&out, &["not an aerial build", "not aerial"]);
        assert!(here.join("ran").exists(), "{spelling}: ./other did not run");
        assert!(
            !on_path.join("ran").exists(),
            "{spelling}: the program in PATH ran"
        );
    }
    let out = tiny_bench(&["--against", "only-on-path"])
        .current_dir(&here)
        .env("PATH", &path)
        .output()
        .unwrap();
    assert_refused(&out, &["--against only-on-path", "not looked up in PATH"]);
    assert!(!on_path.join("ran").exists(), "the program in PATH ran");
    std::fs::remove_dir_all(&dir).ok();
}

/// Class 11: what `--against` prints never names its temporary files: a
/// failing other build's messages are shown with the temporary folder left
/// out, and a missing or broken report is named by what it is.
#[test]
fn against_names_no_temporary_file() {
    let dir = common::fresh_dir("hostile-bench", "temporary-names");
    let tmp = dir.join("tmp");
    std::fs::create_dir_all(&tmp).unwrap();
    let answer = "if [ \"$1\" = --version ]; then echo 'aerial 0.0.1'; exit 0; fi\n";
    let failing = dir.join("failing-build");
    script(
        &failing,
        &format!("{answer}for a; do echo \"cannot write $a in $TMPDIR\" >&2; done\nexit 1\n"),
    );
    let silent = dir.join("silent-build");
    script(&silent, &format!("{answer}exit 0\n"));
    let garbled = dir.join("garbled-build");
    script(
        &garbled,
        &format!(
            "{answer}for a; do case $a in --json=*) echo '{{' > \"${{a#--json=}}\";; esac; done\n"
        ),
    );
    for (build, expected) in [
        (&failing, "bench failed"),
        (&silent, "file not found"),
        (&garbled, "EOF while parsing"),
    ] {
        let mut command = tiny_bench(&["--rounds", "1"]);
        command.arg("--against").arg(build).env("TMPDIR", &tmp);
        let out = output_within(&mut command, Duration::from_secs(300), "against");
        assert_refused(&out, &[expected, "the other build"]);
        let all = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            !all.contains(&tmp.display().to_string()) && !all.contains(".tmp"),
            "a temporary path was printed: {all}"
        );
        if build == &failing {
            assert!(all.contains("(temporary folder)"), "{all}");
        }
        assert_eq!(entries(&tmp), Vec::<String>::new());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// One row of the hand-made two-combination sweep below.
fn sweep_row(index: usize) -> Row {
    let tessellation = ["0.25", "1"][index];
    let pairs = |t: &str| {
        vec![
            ("size".to_string(), "8x8".to_string()),
            ("tessellation".to_string(), t.to_string()),
        ]
    };
    let own = index == 1;
    let error = if own { 0.0 } else { 0.1 };
    let gpu = Summary::of(&[2.0, 2.1, 2.2]).unwrap();
    Row {
        index,
        settings: pairs(tessellation),
        reference: pairs("1"),
        is_reference: own,
        pass_median_ms: vec![("opaque".into(), 1.5), ("readback".into(), 0.6)],
        gpu_ms: gpu,
        cpu_ms: Summary::of(&[2.5, 2.6, 2.7]).unwrap(),
        empty_median_ms: Some(0.5),
        gpu_x_empty: Some(gpu.median / 0.5),
        rmse: error,
        max_rel_error: error,
        flip_mean: error,
        flip_p99: error,
        setup: Vec::new(),
        pareto: true,
    }
}

/// Shard `index` of 2 of a sweep over `tessellation=0.25,1` at 8x8: one
/// row each, as `sweep --shard` writes them.
fn sweep_shard(index: usize) -> SweepResult {
    SweepResult {
        aerial_version: "0.1.0".into(),
        scene: "s.toml".into(),
        scene_hash: "0123456789abcdef".into(),
        device: "llvmpipe".into(),
        frames: 3,
        warmup: 0,
        reference: ReferenceKind::GpuBest,
        knobs: vec!["size".into(), "tessellation".into()],
        axes: vec!["size=8x8".into(), "tessellation=0.25,1".into()],
        combinations: 2,
        shard: Some(Shard { index, count: 2 }),
        shards: vec![ShardSource {
            index,
            device: "llvmpipe".into(),
        }],
        time_axis: TimeAxis::GpuMedianMs,
        passes: vec!["opaque".into(), "readback".into()],
        setup: Vec::new(),
        asset_warnings: 0,
        rows: vec![sweep_row(index)],
    }
}

/// Writes both shards into `dir` (after `change` on shard 0) and merges
/// them into `dir/merged`.
fn merge_shards(dir: &Path, change: impl FnOnce(&mut SweepResult)) -> Output {
    let mut first = sweep_shard(0);
    change(&mut first);
    for (i, shard) in [first, sweep_shard(1)].iter().enumerate() {
        let d = dir.join(format!("s{i}"));
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(
            d.join("sweep.json"),
            serde_json::to_string_pretty(shard).unwrap(),
        )
        .unwrap();
    }
    let mut command = common::aerial();
    command
        .args(["sweep", "merge"])
        .arg(dir.join("s0"))
        .arg(dir.join("s1"))
        .arg("--out-dir")
        .arg(dir.join("merged"));
    output_within(&mut command, Duration::from_secs(120), "sweep merge")
}

/// Class 7: a merged sweep whose errors or times reach the largest floats
/// (or the smallest) is plotted like any other, where the plot once
/// looped forever from an error of 1e305 on.
#[test]
fn merged_sweeps_with_huge_or_tiny_values_are_plotted() {
    let dir = common::fresh_dir("hostile-bench", "huge-values");
    type Change = fn(&mut SweepResult);
    let changes: [Change; 6] = [
        |r| r.rows[0].rmse = 1e305,
        |r| r.rows[0].rmse = f64::MAX,
        |r| r.rows[0].rmse = 5e-324,
        |r| r.rows[0].max_rel_error = 1e308,
        |r| {
            let row = &mut r.rows[0];
            row.empty_median_ms = Some(1e-300);
            row.gpu_x_empty = Some(row.gpu_ms.median / 1e-300);
        },
        |r| {
            let row = &mut r.rows[0];
            row.gpu_ms = Summary::of(&[1e300, 1e300, 1e300]).unwrap();
            row.gpu_x_empty = Some(1e300 / 0.5);
        },
    ];
    for (n, change) in changes.into_iter().enumerate() {
        let out = merge_shards(&dir, change);
        assert_eq!(out.status.code(), Some(0), "change {n}: {}", text(&out));
        let svg = std::fs::read_to_string(dir.join("merged/sweep.svg")).unwrap();
        assert!(svg.trim_end().ends_with("</svg>"), "change {n}");
        std::fs::remove_dir_all(dir.join("merged")).unwrap();
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Class 8: `sweep merge` checks every row against the sweep it claims to
/// be part of: settings that contradict the row's index (another label),
/// a wrong reference or reference flag, and values no measurement gives
/// are refused naming the file, the row and the field, and nothing is
/// written.
#[test]
fn merge_refuses_rows_that_contradict_their_sweep() {
    let dir = common::fresh_dir("hostile-bench", "contradicting-rows");
    type Change = fn(&mut SweepResult);
    let changes: [(Change, &str); 10] = [
        (
            |r| r.rows[0].settings[1].1 = "1".into(),
            "settings: 'size=8x8 tessellation=1' contradicts the row's index, which is \
             'size=8x8 tessellation=0.25'",
        ),
        (
            |r| r.rows[0].settings.reverse(),
            "settings: 'tessellation=0.25 size=8x8' contradicts",
        ),
        (
            |r| r.rows[0].settings[0].1 = "16x16".into(),
            "settings: 'size=16x16 tessellation=0.25'",
        ),
        (
            |r| r.rows[0].reference[1].1 = "0.25".into(),
            "reference: 'size=8x8 tessellation=0.25', but this combination's reference",
        ),
        (|r| r.rows[0].is_reference = true, "is_reference: true"),
        (|r| r.rows[0].rmse = -0.1, "rmse: -0.1 is not"),
        (
            |r| r.rows[0].flip_p99 = 2.0,
            "flip_p99: 2 is not a number from 0 to 1",
        ),
        (
            |r| r.rows[0].pass_median_ms[1].1 = -1.0,
            "pass_median_ms.readback: -1 is not",
        ),
        (
            |r| r.rows[0].gpu_x_empty = Some(1.0),
            "gpu_x_empty: 1 is not gpu_ms.median / empty_median_ms",
        ),
        (
            |r| r.rows[0].empty_median_ms = Some(0.0),
            "empty_median_ms: 0",
        ),
    ];
    let file = dir.join("s0").join("sweep.json").display().to_string();
    for (change, expected) in changes {
        let out = merge_shards(&dir, change);
        assert_refused(
            &out,
            &[&format!("{file}: rows[0] (combination 0): "), expected],
        );
        assert!(!dir.join("merged").exists(), "{expected}: output written");
    }
    // Unchanged, they merge.
    let out = merge_shards(&dir, |_| {});
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    std::fs::remove_dir_all(&dir).ok();
}

/// Class 9: outputs that could only fail after the work are refused
/// before it: `sweep --out-dir` (and `sweep merge --out-dir`) at a
/// symbolic link to a missing target, through one, or naming an existing
/// file with a trailing slash; `bench --json` naming a folder by its
/// spelling (`o.json/`, `o.json/.`).
#[test]
fn outputs_that_can_only_fail_later_are_refused_before_the_work() {
    let dir = common::fresh_dir("hostile-bench", "late-outputs");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let dangling = dir.join("dangling");
    std::os::unix::fs::symlink(dir.join("missing/target"), &dangling).unwrap();
    let chained = dir.join("chained");
    std::os::unix::fs::symlink(&dangling, &chained).unwrap();
    let file = dir.join("o.png");
    std::fs::write(&file, b"keep").unwrap();
    let with_slash = format!("{}/", file.display());
    let outs: [(PathBuf, &str); 5] = [
        (dangling.clone(), "symbolic link to a missing target"),
        (chained.clone(), "symbolic link to a missing target"),
        (dangling.join("sub"), "symbolic link to a missing target"),
        (PathBuf::from(&with_slash), "exists and is not a folder"),
        (file.join("sub/"), "is not a folder"),
    ];
    for (out_dir, expected) in &outs {
        let out = common::aerial()
            .arg("sweep")
            .arg(&scene)
            .args(["--knob", "tessellation=0.5,1", "--out-dir"])
            .arg(out_dir)
            .output()
            .unwrap();
        assert_refused(&out, &["--out-dir", expected]);
        // Before any render: "N combinations" is printed before them.
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.contains("combinations"), "{stderr}");
        let merge = common::aerial()
            .args(["sweep", "merge"])
            .arg(dir.join("no-shard"))
            .arg("--out-dir")
            .arg(out_dir)
            .output()
            .unwrap();
        assert_refused(&merge, &["--out-dir", expected]);
    }
    assert!(!dir.join("missing").exists());
    assert_eq!(std::fs::read(&file).unwrap(), b"keep");
    for json in ["o.json/", "o.json/.", "sub/.."] {
        let out = tiny_bench(&["--json", &format!("{}/{json}", dir.display())])
            .output()
            .unwrap();
        assert_refused(&out, &["--json"]);
        // Refused before measuring: no report was printed.
        assert!(out.stdout.is_empty(), "{json}: {}", text(&out));
    }
    assert_eq!(entries(&dir), ["chained", "dangling", "o.png"]);
    std::fs::remove_dir_all(&dir).ok();
}
