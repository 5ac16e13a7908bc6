//! Interrupts stop a run at a safe point, never in the middle of the
//! driver, and leave nothing half-written.
//!
//! - `aerial render` is sent a stop signal (SIGINT, SIGTERM, SIGQUIT,
//!   SIGUSR1, SIGHUP, SIGUSR2 in turn) at several moments of a large
//!   render (while rendering, while encoding, around the renames); whatever
//!   the moment, no temporary file remains and the outputs are either none
//!   or both, complete and decodable: exit 130 with none (interrupted
//!   before the commit) or with both (interrupted after it, before the
//!   process ended), or exit 0 with both. A 0-byte, partial or lone file is
//!   a failure, and so is a message naming a temporary file.
//! - Validated and unvalidated `render` and `bench` runs are interrupted
//!   (SIGINT or SIGTERM) at delays from 0.5 to 2.5 s, while the driver and
//!   the validation layer are busy: every trial must exit 130 (not crash
//!   with a signal), having stopped at a safe point (not ended by the
//!   grace-period fallback), with no output and no temporary file left.
//! - Without a Vulkan context (a CPU-only `mesh` run) an interrupt ends the
//!   run at once, with no output.

use crate::common;

use std::path::Path;
use std::process::{Child, Command, Output};
use std::time::{Duration, Instant};

fn leftovers(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn signal(child: &Child, signal: libc::c_int) {
    // SAFETY: kill(2) on our own child, which has not been waited for, so
    // its pid is still its own.
    unsafe { libc::kill(child.id() as libc::pid_t, signal) };
}

#[cfg(target_os = "linux")]
const SIGNALS: [(libc::c_int, &str); 6] = [
    (libc::SIGINT, "INT"),
    (libc::SIGTERM, "TERM"),
    (libc::SIGQUIT, "QUIT"),
    (libc::SIGUSR1, "USR1"),
    (libc::SIGHUP, "HUP"),
    (libc::SIGUSR2, "USR2"),
];

#[test]
#[cfg(target_os = "linux")]
fn a_stop_signal_at_any_moment_leaves_whole_outputs_or_none() {
    // How long an uninterrupted run takes, to spread the signals over it.
    let dir = tempfile::tempdir().unwrap();
    let run = |dir: &Path| {
        Command::new(env!("CARGO_BIN_EXE_aerial"))
            .args([
                "render",
                "--width",
                "1536",
                "--height",
                "1536",
                "--validate",
            ])
            .arg("--out")
            .arg(dir.join("out.png"))
            .arg("--hdr")
            .arg(dir.join("out.exr"))
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap()
    };
    let start = Instant::now();
    let out = run(dir.path()).wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let full = start.elapsed();

    let mut interrupted = 0;
    for (step, (sig, name)) in (1..=6u32).zip(SIGNALS) {
        let dir = tempfile::tempdir().unwrap();
        let child = run(dir.path());
        std::thread::sleep(full.mul_f64(f64::from(step) / 7.0));
        signal(&child, sig);
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        let files = leftovers(dir.path());
        let what = format!(
            "step {step}, SIG{name}: exit {:?}, files {files:?}, stderr:\n{err}",
            out.status
        );
        assert!(
            // Temporary files are named `.NAME.XXXXXX.tmp` next to the output.
            !err.contains(".out.png.") && !err.contains(".out.exr."),
            "a temporary name in the messages; {what}"
        );
        match out.status.code() {
            Some(130) if files.is_empty() => interrupted += 1,
            Some(0) | Some(130) => {
                assert_eq!(files, ["out.exr", "out.png"], "{what}");
                let png = image::open(dir.path().join("out.png")).unwrap();
                assert_eq!((png.width(), png.height()), (1536, 1536));
                aerial::image_io::read_exr(&dir.path().join("out.exr")).unwrap();
            }
            _ => panic!("{what}"),
        }
    }
    // Most of a run is rendering and encoding: some signals must land there.
    assert!(
        interrupted >= 3,
        "only {interrupted} of 6 runs were interrupted"
    );
}

/// One interrupted run: the command, how long after the start the signal
/// is sent, and which signal.
fn interrupted_run(mut command: Command, delay: Duration, sig: libc::c_int) -> Output {
    let child = command
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(delay);
    signal(&child, sig);
    child.wait_with_output().unwrap()
}

#[test]
#[cfg(target_os = "linux")]
fn an_interrupt_during_a_validated_run_exits_130_every_time() {
    use std::os::unix::process::ExitStatusExt as _;
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let mut failures = Vec::new();
    let trials = 16;
    for trial in 0..trials {
        let dir = tempfile::tempdir().unwrap();
        // 0.5 s to 2.5 s, spread over the trials.
        let delay = Duration::from_millis(500 + 2000 * trial / (trials - 1));
        let (sig, name) = if trial % 2 == 0 {
            (libc::SIGINT, "INT")
        } else {
            (libc::SIGTERM, "TERM")
        };
        // Bench and render, with validation on three trials of four. Enough
        // frames that no run ends before the signal.
        let validate = trial % 4 != 3;
        let mut command = common::aerial();
        let kind = if trial % 3 == 0 { "bench" } else { "render" };
        command
            .arg(kind)
            .arg(&scene)
            .args(["--width", "96", "--height", "54"]);
        if kind == "bench" {
            command
                .args(["--warmup", "0", "--frames", "100000", "--json"])
                .arg(dir.path().join("bench.json"));
        } else {
            command
                .args(["--frames", "100000", "--out"])
                .arg(dir.path().join("out.png"))
                .arg("--hdr")
                .arg(dir.path().join("out.exr"));
        }
        if validate {
            command.arg("--validate");
        }
        let started = Instant::now();
        let out = interrupted_run(command, delay, sig);
        let took = started.elapsed();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        let files = leftovers(dir.path());
        let ok = out.status.code() == Some(130)
            && err.contains("interrupted; no output written")
            && !err.contains(aerial::interrupt::FORCED_MESSAGE)
            && files.is_empty();
        if !ok {
            failures.push(format!(
                "trial {trial} ({kind}, validate {validate}, SIG{name} after {delay:?}): \
                 exit {:?} (signal {:?}) after {took:?}, files {files:?}, stderr:\n{err}",
                out.status.code(),
                out.status.signal()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {trials} trials failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Without a Vulkan context there is no driver to wait for: an interrupt
/// during a CPU-only command (`mesh` of a large model) ends it at once,
/// well within the grace period a GPU run gets, with no output.
#[test]
#[cfg(target_os = "linux")]
fn an_interrupt_without_a_device_ends_the_run_at_once() {
    use std::fmt::Write as _;
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("big.obj");
    let mut text = String::new();
    let n = 600_000u32;
    for i in 0..n {
        let t = f64::from(i);
        writeln!(text, "v {} {} {}", t.sin(), t.cos(), (t * 0.37).sin()).unwrap();
    }
    for i in (1..n - 2).step_by(3) {
        writeln!(text, "f {i} {} {}", i + 1, i + 2).unwrap();
    }
    std::fs::write(&model, text).unwrap();
    let json = dir.path().join("report.json");
    let mut command = common::aerial();
    command.arg("mesh").arg(&model).arg("--json").arg(&json);
    let child = command
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let sent = Instant::now();
    signal(&child, libc::SIGINT);
    let out = child.wait_with_output().unwrap();
    let took = sent.elapsed();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted; no output written"), "{err}");
    assert!(
        took < aerial::interrupt::GRACE / 4,
        "took {took:?} to stop after the signal"
    );
    assert!(!json.exists());
    assert_eq!(leftovers(dir.path()), ["big.obj"]);
}
