//! Every command's memory estimate bounds its measured peak. Each case runs
//! a command on a large input while reading its peak resident memory, then
//! runs it again with `AERIAL_MEMORY_BUDGET` set to that peak: the run
//! must be refused before any work, which holds only if the estimate the
//! command checks is at least the peak. Commands with a Vulkan device
//! (`bench`, `sweep`) are measured above the same run at 1x1, since the
//! driver's own memory is what the budget leaves room for (see
//! `aerial::budget`); commands without one (`mesh`, `scene`, `normalmap`)
//! are held to their whole peak. `render`, `tonemap` and `compare` have
//! theirs in `hostile_io.rs`.

use crate::common;

use std::ffi::{OsStr, OsString};
use std::fmt::Write as _;
use std::path::Path;

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `args` with the memory budget set to `budget` bytes and checks it
/// is refused for its memory before any work, leaving nothing in `dir`
/// but `inputs`.
fn refused_at(args: &[OsString], budget: u64, dir: &Path, inputs: &[&str]) {
    let out = common::aerial()
        .args(args)
        .env("AERIAL_MEMORY_BUDGET", budget.to_string())
        .output()
        .unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?} under {budget}: {err}");
    assert!(err.contains("memory budget"), "{args:?}: {err}");
    assert!(
        !err.contains("device:"),
        "{args:?}: the work started: {err}"
    );
    let mut left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    let mut expected: Vec<String> = inputs.iter().map(|s| s.to_string()).collect();
    expected.sort();
    assert_eq!(left, expected, "{args:?} left files behind");
}

/// `args` as owned strings, the paths among them as given.
fn args(parts: &[&dyn AsRef<OsStr>]) -> Vec<OsString> {
    parts.iter().map(|p| p.as_ref().to_owned()).collect()
}

/// The peak of `args`, which must succeed.
fn peak(args: &[OsString]) -> u64 {
    let refs: Vec<&OsStr> = args.iter().map(OsString::as_os_str).collect();
    let (out, peak) = common::peak_memory(&refs);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
    peak
}

/// A wavy `n` x `n` grid of quads with texture coordinates (each corner
/// shared by four quads), as an exporter writes a terrain.
fn grid_obj(path: &Path, n: u32) {
    let mut text = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
            let y = 0.1 * (7.0 * x).sin() * (5.0 * z).cos();
            writeln!(text, "v {x:.6} {y:.6} {z:.6}\nvt {x:.6} {z:.6}").unwrap();
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            let (b, c, d) = (a + 1, a + n + 2, a + n + 1);
            writeln!(text, "f {a}/{a} {b}/{b} {c}/{c} {d}/{d}").unwrap();
        }
    }
    std::fs::write(path, text).unwrap();
}

/// `n` separate triangles, each with its own positions, UVs and normals:
/// nothing to share, the most per triangle for the loader to keep.
fn soup_obj(path: &Path, n: u32) {
    let mut text = String::new();
    for t in 0..n {
        let s = f64::from(t);
        let (x, y, z) = (
            (s * 0.618).fract(),
            (s * 0.414).fract(),
            (s * 0.732).fract(),
        );
        for k in 0..3 {
            let k = f64::from(k);
            writeln!(
                text,
                "v {:.5} {:.5} {:.5}\nvt {:.3} {:.3}\nvn 0 {k} 1",
                x + 0.01 * k,
                y + 0.013 * k * k,
                z + 0.007 * (k - 1.0),
                0.3 * k,
                0.25 * k * k
            )
            .unwrap();
        }
        let b = 3 * t + 1;
        writeln!(
            text,
            "f {b}/{b}/{b} {}/{}/{} {}/{}/{}",
            b + 1,
            b + 1,
            b + 1,
            b + 2,
            b + 2,
            b + 2
        )
        .unwrap();
    }
    std::fs::write(path, text).unwrap();
}

/// `aerial mesh` (both tangent methods) and `aerial scene` on a large
/// terrain and a large triangle soup: the loader's estimate (the file's
/// bytes and its triangles) is at least the whole process's peak.
#[test]
fn mesh_and_scene_estimates_bound_their_peaks() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    grid_obj(&d.join("grid.obj"), 250);
    soup_obj(&d.join("soup.obj"), 60_000);
    let scene = d.join("s.toml");
    for model in ["grid.obj", "soup.obj"] {
        let path = d.join(model);
        for run in [
            args(&[&"mesh", &path]),
            args(&[&"mesh", &path, &"--tangents", &"mikktspace"]),
            args(&[&"scene", &path, &"--out", &scene]),
        ] {
            let peak = peak(&run);
            eprintln!("{run:?}: peak {peak} bytes");
            let _ = std::fs::remove_file(&scene);
            refused_at(&run, peak, d, &["grid.obj", "soup.obj"]);
        }
    }
}

/// `aerial normalmap` of a 4096x4096 16-bit height map and a 2048x2048
/// 8-bit one: the decoded image, the f32 heights and normals and the RGBA8
/// result are counted, and bound the whole process's peak.
#[test]
fn normalmap_estimate_bounds_its_peak() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let height = |x: u32, y: u32| {
        let wave = (f64::from(x) / 37.0).sin() * (f64::from(y) / 23.0).cos();
        ((wave + 1.0) * 30000.0) as u16 + ((x * 7 + y * 13) % 997) as u16
    };
    image::ImageBuffer::<image::Luma<u16>, _>::from_fn(4096, 4096, |x, y| {
        image::Luma([height(x, y)])
    })
    .save(d.join("h16.png"))
    .unwrap();
    image::GrayImage::from_fn(2048, 2048, |x, y| image::Luma([(height(x, y) >> 8) as u8]))
        .save(d.join("h8.png"))
        .unwrap();
    let out = d.join("n.png");
    for input in ["h16.png", "h8.png"] {
        let run = args(&[&"normalmap", &d.join(input), &"--out", &out]);
        let peak = peak(&run);
        eprintln!("normalmap {input}: peak {peak} bytes");
        std::fs::remove_file(&out).unwrap();
        refused_at(&run, peak, d, &["h16.png", "h8.png"]);
    }
}

/// `aerial bench` at 1024x1024 and 1x1: the scene's estimate counts the
/// empty pass timed between its frames on the same device (its attachment
/// and read-back buffer, 8 bytes per pixel, were missing), and the empty
/// pass's own run is estimated from what it allocates.
#[test]
fn bench_estimate_bounds_its_peak() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let run = |side: &str| {
        args(&[
            &"bench",
            &scene,
            &"--width",
            &side,
            &"--height",
            &side,
            &"--frames",
            &"1",
            &"--warmup",
            &"0",
        ])
    };
    let base = peak(&run("1"));
    let above = peak(&run("1024")) - base;
    eprintln!("bench 1024x1024: peak {above} bytes above a 1x1 run's");
    refused_at(&run("1024"), above, dir.path(), &[]);
}

/// `aerial sweep` at 1024x1024: the sweep's estimate counts the reference
/// images it keeps for later rows and the comparison of each image with its
/// reference, besides each render's own estimate.
#[test]
fn sweep_estimate_bounds_its_peak() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let out = dir.path().join("sweep");
    let run = |size: &str| {
        args(&[
            &"sweep",
            &scene,
            &"--knob",
            &format!("size={size}"),
            &"--knob",
            &"tessellation=0.5,1",
            &"--frames",
            &"1",
            &"--warmup",
            &"0",
            &"--out-dir",
            &out,
        ])
    };
    let base = peak(&run("1x1"));
    std::fs::remove_dir_all(&out).unwrap();
    let above = peak(&run("1024x1024")) - base;
    eprintln!("sweep 1024x1024: peak {above} bytes above a 1x1 sweep's");
    std::fs::remove_dir_all(&out).unwrap();
    refused_at(&run("1024x1024"), above, dir.path(), &[]);
}
