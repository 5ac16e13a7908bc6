//! An interrupted run leaves nothing half-written. `aerial render` is sent
//! SIGINT at several moments of a large render (while rendering, while
//! encoding, around the renames); whatever the moment, no temporary file
//! remains and the outputs are either none or both, complete and
//! decodable: exit 130 with none (interrupted before the commit) or with
//! both (interrupted after it, before the process ended), or exit 0 with
//! both. A 0-byte, partial or lone file is a failure.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect()
}

#[test]
#[cfg(unix)]
fn sigint_at_any_moment_leaves_whole_outputs_or_none() {
    // How long an uninterrupted run takes, to spread the signals over it.
    let dir = tempfile::tempdir().unwrap();
    let run = |dir: &Path| {
        Command::new(env!("CARGO_BIN_EXE_aerial"))
            .args(["render", "--width", "1536", "--height", "1536"])
            .arg("--out")
            .arg(dir.join("out.png"))
            .arg("--hdr")
            .arg(dir.join("out.exr"))
            .spawn()
            .unwrap()
    };
    let start = Instant::now();
    let status = run(dir.path()).wait().unwrap();
    assert!(status.success());
    let full = start.elapsed();

    let mut interrupted = 0;
    for step in 1..=6u32 {
        let dir = tempfile::tempdir().unwrap();
        let mut child = run(dir.path());
        std::thread::sleep(full.mul_f64(f64::from(step) / 7.0));
        let _ = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status();
        let status = child.wait().unwrap();
        let files = leftovers(dir.path());
        match status.code() {
            Some(130) if files.is_empty() => interrupted += 1,
            Some(0) | Some(130) => {
                let mut names = files.clone();
                names.sort();
                assert_eq!(names, ["out.exr", "out.png"], "step {step}");
                let png = image::open(dir.path().join("out.png")).unwrap();
                assert_eq!((png.width(), png.height()), (1536, 1536));
                aerial::render::output::read_exr(&dir.path().join("out.exr")).unwrap();
            }
            other => panic!("step {step}: exit {other:?}, files {files:?}"),
        }
    }
    // Most of a run is rendering and encoding: some signals must land there.
    assert!(
        interrupted >= 3,
        "only {interrupted} of 6 runs were interrupted"
    );
}
