//! Screenshot regression suite: every scene in `assets/scenes/*.toml` is
//! rendered on the default device (lavapipe in CI) under the validation layer
//! (zero messages allowed) at 160x90 and compared with its reference,
//! `tests/reference/<scene-stem>.png`.
//!
//! # Pass/fail: FLIP mean <= 0.03, p99 <= 0.1, worst 12x12 window <= 0.3
//!
//! These are [`FLIP_DEFAULT_THRESHOLDS`], the defaults of `aerial compare`;
//! the measurements behind them are tabulated there. In short, measured on
//! these scenes at this size, what another GPU or driver plausibly does
//! passes: +-1 LSB rounding noise gives mean 0.011, a 1/20-pixel shift of
//! every edge p99 0.092 at most. Real regressions fail: a missing light gives
//! mean 0.07 and p99 0.31 or more, a missing object p99 0.20 or more, a 5 %
//! exposure change mean 0.035 or more, a 6x6 block inverted a worst-window
//! mean FLIP of 0.50 or more (while 1/20-pixel shifts stay below 0.21). On the driver that made the
//! references the render is bit-identical and every FLIP value is 0.
//!
//! # Bit-exact on the reference's driver, FLIP limits elsewhere
//!
//! The references record the device and driver that rendered them (PNG text
//! chunks written by `write_png` from `RenderRun::png_metadata`). When this
//! run's device and driver are the same, renders are deterministic, so any
//! pixel difference from the reference is a change in the output and fails,
//! however small its FLIP error (a 1 % exposure change passes the FLIP
//! limits). With another device or driver only the FLIP limits apply, and a
//! failure message says that the drivers differ. Either way the test says
//! on stderr whether the render is bit-identical
//! (`cargo test --test suite regression:: -- --nocapture`).
//!
//! # When it fails
//!
//! For each failing scene the test writes `<stem>.new.png` (this render) and
//! `<stem>.diff.png` (the FLIP error map: black is equal, bright is
//! different) next to the reference; both are git-ignored. If the change is
//! intended, regenerate (this overwrites every reference), look at the new
//! images, and commit them:
//!
//! ```text
//! AERIAL_UPDATE_REFERENCES=1 cargo test --test suite regression::
//! ```
//!
//! A scene without a reference fails the same way, with `<stem>.new.png`
//! written for review.
//!
//! # Why 160x90
//!
//! Five scenes at 160x90 render and compare in about a second on lavapipe,
//! and the scenes' shading, colours and layout are all visible at this size.
//! (FLIP, at its default 67 pixels per degree, spreads a small change over
//! more pixels of a small image, so p99 is if anything more sensitive here.)

use crate::common;

use aerial::image_io;
use aerial::report::{compare_files, write_diff_png, ImageDiff, Metric, FLIP_DEFAULT_THRESHOLDS};
use aerial::scene::Scene;
use std::path::{Path, PathBuf};

const WIDTH: u32 = 160;
const HEIGHT: u32 = 90;
const UPDATE_VAR: &str = "AERIAL_UPDATE_REFERENCES";
const REGENERATE: &str = "AERIAL_UPDATE_REFERENCES=1 cargo test --test suite regression::";

fn manifest_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn reference_dir() -> PathBuf {
    manifest_dir().join("tests/reference")
}

fn scenes() -> Vec<PathBuf> {
    let dir = manifest_dir().join("assets/scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    scenes
}

/// Set and not "0": regenerate the references instead of checking them.
fn updating() -> bool {
    std::env::var_os(UPDATE_VAR).is_some_and(|v| !v.is_empty() && v != "0")
}

/// "device; driver ...; code generation ..." from PNG text chunks or from
/// a run's metadata. The CPU features that change a CPU driver's code
/// (`aerial::app::host_codegen`: vendor, FMA, AVX-512) are part of it,
/// because lavapipe compiles shaders for the host and the same device and
/// driver strings give different pixels on CPUs that differ in those; the
/// rest of the CPU's flag list is not, so an unrelated extra flag keeps the
/// bit-exact check.
fn origin<K: AsRef<str>>(text: &[(K, String)]) -> Option<String> {
    let get = |key: &str| {
        text.iter()
            .find(|(k, _)| k.as_ref() == key)
            .map(|(_, v)| v.as_str())
    };
    Some(format!(
        "{}; driver {}; code generation {}",
        get("aerial:device")?,
        get("aerial:driver")?,
        get("aerial:codegen")?
    ))
}

/// The rule: bit-identical on the reference's device, driver and code
/// generation; within the FLIP limits elsewhere.
fn accepted(same_driver: bool, identical: bool, cmp: &ImageDiff) -> bool {
    if same_driver {
        identical
    } else {
        cmp.passes(&FLIP_DEFAULT_THRESHOLDS)
    }
}

/// Whether the render equals the reference bit for bit, and a description
/// of how far it is off otherwise.
fn bit_exactness(reference: &Path, render: &aerial::render::Pixels<u8>) -> (bool, String) {
    let img = match image::open(reference) {
        Ok(img) => img.to_rgba8(),
        Err(e) => return (false, format!("cannot decode for the bit-exact check: {e}")),
    };
    if img.dimensions() != (render.width, render.height) {
        return (false, "sizes differ".into());
    }
    let (mut pixels, mut largest) = (0usize, 0u8);
    for (a, b) in img
        .as_raw()
        .chunks_exact(4)
        .zip(render.data.chunks_exact(4))
    {
        if a != b {
            pixels += 1;
            for (x, y) in a.iter().zip(b) {
                largest = largest.max(x.abs_diff(*y));
            }
        }
    }
    if pixels == 0 {
        (true, "bit-identical to the reference".into())
    } else {
        let text = format!(
            "NOT bit-identical: {pixels} of {} pixels differ, by up to {largest}/255",
            render.width * render.height
        );
        (false, text)
    }
}

fn remove_if_present(path: &Path) {
    if let Err(e) = std::fs::remove_file(path) {
        if e.kind() != std::io::ErrorKind::NotFound {
            panic!("cannot remove {}: {e}", path.display());
        }
    }
}

/// One line of the summary table.
struct Row {
    stem: String,
    flip: Option<ImageDiff>,
    note: String,
}

fn row(stem: String, flip: Option<ImageDiff>, note: &str) -> Row {
    Row {
        stem,
        flip,
        note: note.to_string(),
    }
}

/// Renders one scene and checks (or, when updating, rewrites) its
/// reference: its summary row, and the failure message for the user if it
/// failed.
fn check_scene(path: &Path) -> (Row, Option<String>) {
    let stem = path
        .file_stem()
        .expect("scene files have names")
        .to_string_lossy()
        .into_owned();
    let mut scene = Scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    scene
        .set_output_size(Some(WIDTH), Some(HEIGHT))
        .unwrap_or_else(|e| panic!("{e}"));
    // Printed first, so a validation failure (which panics inside
    // common::render) is attributed to this scene.
    eprintln!("{stem}: rendering {WIDTH}x{HEIGHT} under validation");
    let run = common::render(&scene, false);
    let meta = run.png_metadata();
    let this_origin = origin(&meta);

    let dir = reference_dir();
    let reference = dir.join(format!("{stem}.png"));
    let new = dir.join(format!("{stem}.new.png"));
    let diff = dir.join(format!("{stem}.diff.png"));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    // The comparison reads files, so the render is written first; it is
    // removed again when the scene passes.
    image_io::write_png(&new, &run.output, &meta).unwrap_or_else(|e| panic!("{e}"));

    if !reference.exists() {
        if updating() {
            std::fs::rename(&new, &reference).unwrap_or_else(|e| panic!("{e}"));
            remove_if_present(&diff);
            eprintln!("{stem}: created {}", reference.display());
            return (row(stem, None, "created"), None);
        }
        let message = format!(
            "{stem}: no reference image {}.\n  This render is {}; look at it, and if it is \
             right, create the references with `{REGENERATE}` and commit them.",
            reference.display(),
            new.display()
        );
        return (row(stem, None, "FAIL: no reference"), Some(message));
    }

    let cmp = match compare_files(&reference, &new, Metric::Flip) {
        Ok(cmp) => cmp,
        Err(e) if updating() => {
            // A reference of another size or a corrupt one is exactly what
            // regenerating is for.
            std::fs::rename(&new, &reference).unwrap_or_else(|e| panic!("{e}"));
            remove_if_present(&diff);
            eprintln!(
                "{stem}: overwrote {} (could not compare with it: {e})",
                reference.display()
            );
            return (row(stem, None, "updated"), None);
        }
        Err(e) => {
            let message = format!(
                "{stem}: cannot compare with the reference: {e}\n  This render is {}. \
                 Regenerate with `{REGENERATE}` if the reference is broken.",
                new.display()
            );
            return (row(stem, None, "FAIL: cannot compare"), Some(message));
        }
    };
    let ref_origin = image_io::read_png_text(&reference)
        .ok()
        .and_then(|t| origin(&t));
    let same_driver = ref_origin.is_some() && ref_origin == this_origin;
    let (identical, exactness) = bit_exactness(&reference, &run.output);
    eprintln!(
        "{stem}: FLIP mean {:.6}, p99 {:.6}, worst 12x12 window {:.6}, max {:.6}; {exactness}",
        cmp.mean, cmp.p99, cmp.worst_window, cmp.max
    );
    let driver_note = if same_driver {
        format!(
            "the reference was rendered by the same device and driver ({}), so this is a \
             change in the output, not driver noise",
            this_origin.as_deref().unwrap_or("unknown")
        )
    } else {
        let show = |o: &Option<String>| o.clone().unwrap_or_else(|| "unknown".into());
        let note = format!(
            "a different device or driver made the reference, so bit-identity is not \
             expected (reference: {}. This run: {})",
            show(&ref_origin),
            show(&this_origin)
        );
        eprintln!("{stem}: {note}");
        note
    };

    if updating() {
        std::fs::rename(&new, &reference).unwrap_or_else(|e| panic!("{e}"));
        remove_if_present(&diff);
        eprintln!(
            "{stem}: overwrote {} (the numbers above are against the old one)",
            reference.display()
        );
        return (row(stem, Some(cmp), "updated"), None);
    }
    let passes = accepted(same_driver, identical, &cmp);
    if passes {
        // Leave nothing behind from this or an earlier failed run.
        remove_if_present(&new);
        remove_if_present(&diff);
        return (row(stem, Some(cmp), &exactness), None);
    }
    write_diff_png(&cmp, &diff).unwrap_or_else(|e| panic!("{e}"));
    let limits = FLIP_DEFAULT_THRESHOLDS;
    let rule = if same_driver {
        "is not bit-identical to it (required on the reference's device and driver)"
    } else {
        "is beyond the FLIP limits"
    };
    let message = format!(
        "{stem}: differs from {}: the render {rule}. FLIP mean {:.6} (limit {}), p99 {:.6} \
         (limit {}), worst 12x12 window {:.6} (limit {}), max {:.6}; {exactness}.\n  This render:   {}\n  FLIP diff map: {} \
         (black = equal, bright = different)\n  Note: {driver_note}.\n  If the change is \
         intended, regenerate the references with `{REGENERATE}`, look at them, and commit \
         them.",
        reference.display(),
        cmp.mean,
        limits.mean.unwrap_or(f64::INFINITY),
        cmp.p99,
        limits.p99.unwrap_or(f64::INFINITY),
        cmp.worst_window,
        limits.worst_window.unwrap_or(f64::INFINITY),
        cmp.max,
        new.display(),
        diff.display(),
    );
    (row(stem, Some(cmp), "FAIL"), Some(message))
}

/// References whose scene is gone (renamed or deleted) would otherwise sit
/// in the repository unchecked forever.
fn orphaned_references(scenes: &[PathBuf]) -> Vec<String> {
    let stems: Vec<String> = scenes
        .iter()
        .filter_map(|p| p.file_stem())
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let Ok(entries) = std::fs::read_dir(reference_dir()) else {
        return Vec::new();
    };
    let mut orphans: Vec<String> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| !name.ends_with(".new.png") && !name.ends_with(".diff.png"))
        .filter_map(|name| name.strip_suffix(".png").map(str::to_owned))
        .filter(|stem| !stems.contains(stem))
        .map(|stem| {
            format!(
                "{}: no scene assets/scenes/{stem}.toml renders to this reference; \
                 delete it (git rm) if the scene was removed or renamed",
                reference_dir().join(format!("{stem}.png")).display()
            )
        })
        .collect();
    orphans.sort();
    orphans
}

#[test]
fn every_scene_matches_its_reference() {
    let scenes = scenes();
    assert!(
        scenes.len() >= 5,
        "expected the example scenes, found {scenes:?}"
    );
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for path in &scenes {
        let (row, failure) = check_scene(path);
        rows.push(row);
        failures.extend(failure);
    }
    failures.extend(orphaned_references(&scenes));

    eprintln!(
        "\n{:<16} {:>10} {:>10} {:>10} {:>10}  note",
        "scene", "FLIP mean", "p99", "window", "max"
    );
    for row in &rows {
        match &row.flip {
            Some(c) => eprintln!(
                "{:<16} {:>10.6} {:>10.6} {:>10.6} {:>10.6}  {}",
                row.stem, c.mean, c.p99, c.worst_window, c.max, row.note
            ),
            None => eprintln!(
                "{:<16} {:>10} {:>10} {:>10} {:>10}  {}",
                row.stem, "-", "-", "-", "-", row.note
            ),
        }
    }
    assert!(
        failures.is_empty(),
        "{} screenshot regression failure(s):\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

/// A machine whose CPU has one more flag that does not change lavapipe's
/// code (here `avx512_vnni` and `sha_ni`, without `avx512f`) has the same
/// key as the reference's, so the check stays bit-exact there: a reference
/// pixel changed by one LSB fails, where the FLIP limits alone would pass
/// it. A CPU without FMA has another key (FLIP limits apply).
#[test]
fn an_unrelated_cpu_flag_keeps_the_bit_exact_check() {
    use aerial::app::codegen_key;
    let cpuinfo = "processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Some CPU\n\
                   flags\t\t: fpu sse sse2 ssse3 sse4_1 sse4_2 avx avx2 fma f16c\n";
    let extra = cpuinfo.replace("f16c", "f16c avx512_vnni sha_ni");
    let no_fma = cpuinfo.replace(" fma", "");
    assert_eq!(codegen_key(cpuinfo), codegen_key(&extra));
    assert_ne!(codegen_key(cpuinfo), codegen_key(&no_fma));
    assert_ne!(
        codegen_key(cpuinfo),
        codegen_key(&cpuinfo.replace("f16c", "f16c avx512f"))
    );

    // The reference's metadata, and a run's on the machine with the extra
    // flags (its full flag list differs).
    let reference = reference_dir().join("default.png");
    let mut text: Vec<(String, String)> = image_io::read_png_text(&reference).unwrap();
    let set = |text: &mut Vec<(String, String)>, key: &str, value: String| {
        text.retain(|(k, _)| k != key);
        text.push((key.to_string(), value));
    };
    set(&mut text, "aerial:codegen", codegen_key(cpuinfo));
    let mut there = text.clone();
    set(
        &mut there,
        "aerial:host_cpu",
        "Some CPU [avx avx2 avx512_vnni fma sha_ni]".into(),
    );
    set(&mut there, "aerial:codegen", codegen_key(&extra));
    let same_driver = origin(&text).is_some() && origin(&text) == origin(&there);
    assert!(same_driver, "{:?} vs {:?}", origin(&text), origin(&there));

    // One pixel of the reference off by one LSB.
    let img = image::open(&reference).unwrap().to_rgba8();
    let (width, height) = img.dimensions();
    let mut data = img.into_raw();
    data[4 * (width as usize * 45 + 80)] ^= 1;
    let changed = aerial::render::Pixels {
        width,
        height,
        data,
    };
    let dir = tempfile::tempdir().unwrap();
    let new = dir.path().join("changed.png");
    image::RgbaImage::from_raw(width, height, changed.data.clone())
        .unwrap()
        .save(&new)
        .unwrap();
    let cmp = compare_files(&reference, &new, Metric::Flip).unwrap();
    let (identical, _) = bit_exactness(&reference, &changed);
    assert!(!identical);
    assert!(
        cmp.passes(&FLIP_DEFAULT_THRESHOLDS),
        "a 1-LSB change is within the FLIP limits"
    );
    assert!(
        !accepted(same_driver, identical, &cmp),
        "the 1-LSB change passed"
    );
    // Keyed on another CPU, only the FLIP limits would apply.
    let mut other = there.clone();
    set(&mut other, "aerial:codegen", codegen_key(&no_fma));
    assert_ne!(origin(&text), origin(&other));
}

/// The default scene moved 10^6 and 10^9 m from the origin along every
/// axis is held to its reference with the same FLIP limits as a render on
/// another driver (translation changes rounding, so not bit-exactness).
#[test]
fn the_default_scene_far_from_the_origin_matches_its_reference() {
    let reference = reference_dir().join("default.png");
    let dir = tempfile::tempdir().unwrap();
    for x in [1e6, 1e9] {
        let mut scene = Scene::load(&manifest_dir().join("assets/scenes/default.toml")).unwrap();
        scene.set_output_size(Some(WIDTH), Some(HEIGHT)).unwrap();
        let scene = common::translated(scene, glam::DVec3::splat(x));
        let run = common::render(&scene, false);
        let new = dir.path().join(format!("default_at_{x:e}.png"));
        image::RgbaImage::from_raw(WIDTH, HEIGHT, run.output.data.clone())
            .unwrap()
            .save(&new)
            .unwrap();
        let cmp = compare_files(&reference, &new, Metric::Flip).unwrap();
        eprintln!(
            "default moved by {x:e}: FLIP mean {:.6}, p99 {:.6}, worst window {:.6}",
            cmp.mean, cmp.p99, cmp.worst_window
        );
        assert!(
            cmp.passes(&FLIP_DEFAULT_THRESHOLDS),
            "moved by {x:e}: {cmp:?}"
        );
    }
}
