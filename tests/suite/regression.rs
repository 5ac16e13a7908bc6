//! Screenshot regression suite: every scene in `assets/scenes/*.toml` is
//! rendered at 160x90 by `aerial render --validate` (the Khronos
//! validation layer in all its modes; any message fails the render), in a
//! process of its own with lavapipe's code generation pinned, and compared
//! with its reference, `tests/reference/<scene-stem>.png`.
//!
//! # The pin: `GALLIUM_OVERRIDE_CPU_CAPS=sse4.1`
//!
//! lavapipe compiles shaders with LLVM for the host CPU, so the same shader
//! rounds differently with AVX2, FMA or AVX-512, and references made on one
//! CPU differ by 1/255 on another. Mesa reads `GALLIUM_OVERRIDE_CPU_CAPS`
//! when the driver initialises; `sse4.1` makes it generate code without
//! AVX, FMA or AVX-512 (128-bit vectors) whatever the CPU, and the device
//! name says so: `llvmpipe (LLVM 15.0.6, 128 bits)`. Because the driver
//! reads it once per process, every render here runs in a child `aerial
//! render` with the variable set: the pin cannot leak into the other tests
//! of this process, and nothing they do changes it.
//!
//! # What must match: the key
//!
//! A reference records in PNG text chunks what made it: the device and
//! driver (`write_png` of `RenderRun::png_metadata`), the code generation
//! (`aerial:codegen`: under the pin, the pin and the architecture), the
//! CPU vendor (`aerial:cpu_vendor`) and the SHA-256 of the linear HDR
//! render before tone mapping (`aerial:hdr_sha256`). Rendering is
//! deterministic, so:
//!
//! - **Bit-exact**: same device, driver, code generation and CPU vendor.
//!   The PNG must be bit-identical and the HDR hash equal: any difference
//!   is a change in the output and fails, however small its FLIP error (a
//!   1 % exposure change passes the FLIP limits).
//! - **HDR bit-exact**: same device, driver and pinned code generation,
//!   another CPU vendor. The HDR hash must be equal, and the PNG within
//!   1/255 per channel and the FLIP limits. The 8-bit sRGB encode is the
//!   one step the pin does not fix: lavapipe computes it with `rsqrtps`, an
//!   approximation whose last bits the x86 manuals leave to each CPU design
//!   (they bound only its error).
//! - **FLIP only**: anything else (another GPU, driver, Mesa or LLVM
//!   version, a CPU that is not x86). Only the FLIP limits apply, and the
//!   test says loudly which part of the key differs.
//!
//! Each scene's line on stderr and the closing summary say which rule was
//! applied (`cargo test --test suite regression:: -- --nocapture`). A
//! lavapipe render on x86 whose device does not report 128-bit vectors
//! means the pin did not take effect, and fails: it would otherwise quietly
//! turn every scene into "FLIP only".
//!
//! # FLIP limits: mean <= 0.03, p99 <= 0.1, worst 12x12 window <= 0.3
//!
//! These are [`FLIP_DEFAULT_THRESHOLDS`], the defaults of `aerial compare`;
//! the measurements behind them are tabulated there. In short, measured on
//! these scenes at this size, what another GPU or driver plausibly does
//! passes: +-1 LSB rounding noise gives mean 0.011, a 1/20-pixel shift of
//! every edge p99 0.092 at most. Real regressions fail: a missing light gives
//! mean 0.07 and p99 0.31 or more, a missing object p99 0.20 or more, a 5 %
//! exposure change mean 0.035 or more, a 6x6 block inverted a worst-window
//! mean FLIP of 0.50 or more (while 1/20-pixel shifts stay below 0.21).
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
//! The scenes' shading, colours and layout are all visible at this size,
//! and a scene renders and compares in about a second. (FLIP, at its
//! default 67 pixels per degree, spreads a small change over more pixels
//! of a small image, so p99 is if anything more sensitive here.)

use crate::common;

use aerial::image_io;
use aerial::render::Pixels;
use aerial::report::{compare_files, write_diff_png, ImageDiff, Metric, FLIP_DEFAULT_THRESHOLDS};
use aerial::scene::Scene;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

const WIDTH: u32 = 160;
const HEIGHT: u32 = 90;
const UPDATE_VAR: &str = "AERIAL_UPDATE_REFERENCES";
const REGENERATE: &str = "AERIAL_UPDATE_REFERENCES=1 cargo test --test suite regression::";

/// The variable Mesa's llvmpipe reads at initialisation to generate code
/// for fewer instruction-set extensions than the CPU has, and the value
/// every regression render runs with.
const PIN_VAR: &str = "GALLIUM_OVERRIDE_CPU_CAPS";
const PIN: &str = "sse4.1";
/// The extensions the pin leaves on, which the host must therefore have
/// for its code to be the reference's (Intel CPUs since 2008, AMD since 2011).
const PIN_KEEPS: [&str; 2] = ["sse4_1", "sse4_2"];

/// PNG text keys of the key (see the module docs).
const DEVICE: &str = "aerial:device";
const DRIVER: &str = "aerial:driver";
const CODEGEN: &str = "aerial:codegen";
const HOST_CPU: &str = "aerial:host_cpu";
const VENDOR: &str = "aerial:cpu_vendor";
const HDR_HASH: &str = "aerial:hdr_sha256";

type Text = Vec<(String, String)>;

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

fn get<'a>(text: &'a [(String, String)], key: &str) -> Option<&'a str> {
    text.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

fn set(text: &mut Text, key: &str, value: String) {
    text.retain(|(k, _)| k != key);
    text.push((key.to_string(), value));
}

/// SHA-256 of a linear image: its size, then every channel's bits.
fn hdr_sha256(hdr: &Pixels<f32>) -> String {
    let mut hash = Sha256::new();
    hash.update(hdr.width.to_le_bytes());
    hash.update(hdr.height.to_le_bytes());
    let bytes: Vec<u8> = hdr
        .data
        .iter()
        .flat_map(|v| v.to_bits().to_le_bytes())
        .collect();
    hash.update(&bytes);
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// A render's PNG text as the references record it, for a run on `arch`
/// with the pin set: on lavapipe on x86 the code generation becomes the pin
/// (the host's FMA, AVX2 and AVX-512 no longer matter) and the CPU vendor
/// is kept apart (only the 8-bit encode depends on it); the HDR image's
/// hash is added in every case. Elsewhere the pin does nothing, and the
/// host's code generation key stays. An error when lavapipe on x86 does
/// not report the pinned 128-bit vectors: the pin did not take effect.
fn keyed_text(mut text: Text, hdr_hash: String, arch: &str) -> Result<Text, String> {
    let device = get(&text, DEVICE).unwrap_or("unknown").to_string();
    let x86 = matches!(arch, "x86_64" | "x86");
    if x86 && device.starts_with("llvmpipe") {
        if !device.contains("128 bits") {
            return Err(format!(
                "the device is {device:?} although {PIN_VAR}={PIN} was set: the pin did not \
                 take effect (lavapipe reports 128 bits when it generates SSE4.1 code), so no \
                 render here could be compared bit for bit with the references"
            ));
        }
        // The host's key is "VENDOR +fma -avx512f" (aerial::render_run::codegen_key).
        let vendor = get(&text, CODEGEN)
            .and_then(|c| c.split_whitespace().next())
            .unwrap_or("unknown")
            .to_string();
        let flags: Vec<&str> = get(&text, HOST_CPU)
            .and_then(|c| c.rsplit_once('['))
            .map(|(_, f)| f.trim_end_matches(']').split_whitespace().collect())
            .unwrap_or_default();
        let missing: Vec<&str> = PIN_KEEPS
            .iter()
            .copied()
            .filter(|f| !flags.contains(f))
            .collect();
        let mut codegen = format!("{PIN_VAR}={PIN} on {arch}");
        if !missing.is_empty() {
            codegen.push_str(&format!(" on a CPU without {}", missing.join(", ")));
        }
        set(&mut text, CODEGEN, codegen);
        set(&mut text, VENDOR, vendor);
    }
    set(&mut text, HDR_HASH, hdr_hash);
    Ok(text)
}

/// What a render depends on, from PNG text (a reference's or a run's).
#[derive(Clone, Debug, PartialEq)]
struct Key {
    device: String,
    driver: String,
    codegen: String,
    /// Under the pin: the CPU vendor, which only the 8-bit encode depends
    /// on. `None` without the pin (the vendor is then part of `codegen`).
    vendor: Option<String>,
    hdr_sha256: Option<String>,
}

impl Key {
    fn of(text: &[(String, String)]) -> Option<Key> {
        Some(Key {
            device: get(text, DEVICE)?.to_string(),
            driver: get(text, DRIVER)?.to_string(),
            codegen: get(text, CODEGEN)?.to_string(),
            vendor: get(text, VENDOR).map(str::to_string),
            hdr_sha256: get(text, HDR_HASH).map(str::to_string),
        })
    }

    fn describe(&self) -> String {
        let mut s = format!(
            "{}; driver {}; code generation {}",
            self.device, self.driver, self.codegen
        );
        if let Some(v) = &self.vendor {
            s.push_str(&format!("; CPU vendor {v}"));
        }
        s
    }

    /// The fields (device, driver, code generation) in which `self` and
    /// `other` differ, each with both values: empty when the linear render
    /// is expected to be bit-identical.
    fn render_differences(&self, other: &Key) -> Vec<String> {
        let mut out = Vec::new();
        for (name, a, b) in [
            ("device", &self.device, &other.device),
            ("driver", &self.driver, &other.driver),
            ("code generation", &self.codegen, &other.codegen),
        ] {
            if a != b {
                out.push(format!("{name} {a:?} (reference) vs {b:?} (this run)"));
            }
        }
        out
    }
}

/// Which comparison a render gets against its reference.
#[derive(Clone, Debug, PartialEq)]
enum Rule {
    /// Same key: the PNG bit-identical, the HDR hash equal.
    BitExact,
    /// Same device, driver and pinned code generation, another CPU
    /// vendor: the HDR hash equal, the PNG within 1/255 and the FLIP
    /// limits.
    HdrExact { reference: String, this: String },
    /// Only the FLIP limits, because of `why`.
    FlipOnly { why: String },
}

impl Rule {
    fn of(reference: Option<&Key>, this: &Key) -> Rule {
        let Some(reference) = reference else {
            return Rule::FlipOnly {
                why: "the reference records no device, driver and code generation".into(),
            };
        };
        let differences = reference.render_differences(this);
        if !differences.is_empty() {
            return Rule::FlipOnly {
                why: differences.join("; "),
            };
        }
        if reference.vendor == this.vendor {
            return Rule::BitExact;
        }
        let show = |v: &Option<String>| v.clone().unwrap_or_else(|| "not recorded".into());
        if reference.hdr_sha256.is_none() {
            return Rule::FlipOnly {
                why: format!(
                    "CPU vendor {} (reference) vs {} (this run), and the reference records \
                     no HDR hash to check instead",
                    show(&reference.vendor),
                    show(&this.vendor)
                ),
            };
        }
        Rule::HdrExact {
            reference: show(&reference.vendor),
            this: show(&this.vendor),
        }
    }

    fn short(&self) -> &'static str {
        match self {
            Rule::BitExact => "bit-exact",
            Rule::HdrExact { .. } => "HDR bit-exact, 8-bit within 1/255",
            Rule::FlipOnly { .. } => "FLIP limits only",
        }
    }
}

/// How far an 8-bit render is from its reference's pixels.
struct PixelDiff {
    /// Pixels that differ in any channel.
    pixels: usize,
    /// Largest difference of one channel, in 1/255.
    largest: u8,
    description: String,
}

fn pixel_diff(reference: &Path, render: &Pixels<u8>) -> PixelDiff {
    let unknown = |description: String| PixelDiff {
        pixels: usize::MAX,
        largest: u8::MAX,
        description,
    };
    let img = match image::open(reference) {
        Ok(img) => img.to_rgba8(),
        Err(e) => return unknown(format!("cannot decode for the bit-exact check: {e}")),
    };
    if img.dimensions() != (render.width, render.height) {
        return unknown("sizes differ".into());
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
    let description = if pixels == 0 {
        "8-bit image bit-identical to the reference".into()
    } else {
        format!(
            "8-bit image NOT bit-identical: {pixels} of {} pixels differ, by up to {largest}/255",
            render.width * render.height
        )
    };
    PixelDiff {
        pixels,
        largest,
        description,
    }
}

/// One scene rendered for the suite.
struct Render {
    pixels: Pixels<u8>,
    /// Its PNG text, keyed as the references are ([`keyed_text`]).
    text: Text,
}

impl Render {
    fn metadata(&self) -> Vec<(&str, String)> {
        self.text
            .iter()
            .map(|(k, v)| (k.as_str(), v.clone()))
            .collect()
    }
}

/// Renders `scene` at the suite's size in a child `aerial render` under
/// validation, with the pin set; the PNG and the HDR image go to a
/// temporary folder and are read back.
fn render_pinned(scene: &Path) -> Result<Render, String> {
    let dir = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let png = dir.path().join("render.png");
    let exr = dir.path().join("render.exr");
    let output = common::aerial()
        .arg("render")
        .arg(scene)
        .args([
            "--width",
            &WIDTH.to_string(),
            "--height",
            &HEIGHT.to_string(),
        ])
        .arg("--out")
        .arg(&png)
        .arg("--hdr")
        .arg(&exr)
        .arg("--validate")
        .env(PIN_VAR, PIN)
        .output()
        .map_err(|e| format!("cannot run aerial: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "`aerial render --validate` with {PIN_VAR}={PIN} failed ({}):\n{}",
            output.status,
            String::from_utf8_lossy(&output.stderr).trim_end()
        ));
    }
    let pixels = image::open(&png)
        .map_err(|e| format!("{}: {e}", png.display()))?
        .to_rgba8();
    let (width, height) = pixels.dimensions();
    let pixels = Pixels {
        width,
        height,
        data: pixels.into_raw(),
    };
    let hdr = image_io::read_exr(&exr).map_err(|e| e.to_string())?;
    let text = image_io::read_png_text(&png).map_err(|e| e.to_string())?;
    let text = keyed_text(text, hdr_sha256(&hdr), std::env::consts::ARCH)?;
    Ok(Render { pixels, text })
}

/// A render judged against its reference.
struct Verdict {
    passes: bool,
    rule: Rule,
    cmp: ImageDiff,
    /// The PNG's and the HDR image's exactness, for the log.
    exactness: String,
}

/// Judges `render` (already written to `new` with its text) against
/// `reference` by the rule its key and the reference's give.
fn judge(reference: &Path, new: &Path, render: &Render) -> Result<Verdict, String> {
    let cmp = compare_files(reference, new, Metric::Flip).map_err(|e| e.to_string())?;
    let reference_text = image_io::read_png_text(reference).unwrap_or_default();
    let reference_key = Key::of(&reference_text);
    let this = Key::of(&render.text).ok_or("the render records no key")?;
    let rule = Rule::of(reference_key.as_ref(), &this);
    let diff = pixel_diff(reference, &render.pixels);
    let hdr_equal = match reference_key.as_ref().and_then(|k| k.hdr_sha256.as_ref()) {
        Some(hash) => Some(Some(hash) == this.hdr_sha256.as_ref()),
        None => None,
    };
    let hdr = match hdr_equal {
        Some(true) => "HDR image bit-identical (same SHA-256)",
        Some(false) => "HDR image NOT bit-identical (SHA-256 differs)",
        None => "the reference records no HDR hash",
    };
    let flip_ok = cmp.passes(&FLIP_DEFAULT_THRESHOLDS);
    let passes = match &rule {
        Rule::BitExact => diff.pixels == 0 && hdr_equal != Some(false),
        Rule::HdrExact { .. } => hdr_equal == Some(true) && diff.largest <= 1 && flip_ok,
        Rule::FlipOnly { .. } => flip_ok,
    };
    Ok(Verdict {
        passes,
        rule,
        cmp,
        exactness: format!("{}; {hdr}", diff.description),
    })
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
    rule: Option<Rule>,
    note: String,
}

fn row(stem: String, flip: Option<ImageDiff>, rule: Option<Rule>, note: &str) -> Row {
    Row {
        stem,
        flip,
        rule,
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
    eprintln!("{stem}: rendering {WIDTH}x{HEIGHT} under validation with {PIN_VAR}={PIN}");
    let render = match render_pinned(path) {
        Ok(render) => render,
        Err(e) => {
            return (
                row(stem.clone(), None, None, "FAIL: render"),
                Some(format!("{stem}: {e}")),
            )
        }
    };

    let dir = reference_dir();
    let reference = dir.join(format!("{stem}.png"));
    let new = dir.join(format!("{stem}.new.png"));
    let diff = dir.join(format!("{stem}.diff.png"));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    // The comparison reads files, so the render is written first; it is
    // removed again when the scene passes.
    image_io::write_png(&new, &render.pixels, &render.metadata()).unwrap_or_else(|e| panic!("{e}"));

    if !reference.exists() {
        if updating() {
            std::fs::rename(&new, &reference).unwrap_or_else(|e| panic!("{e}"));
            remove_if_present(&diff);
            eprintln!("{stem}: created {}", reference.display());
            return (row(stem, None, None, "created"), None);
        }
        let message = format!(
            "{stem}: no reference image {}.\n  This render is {}; look at it, and if it is \
             right, create the references with `{REGENERATE}` and commit them.",
            reference.display(),
            new.display()
        );
        return (row(stem, None, None, "FAIL: no reference"), Some(message));
    }

    let verdict = match judge(&reference, &new, &render) {
        Ok(verdict) => verdict,
        Err(e) if updating() => {
            // A reference of another size or a corrupt one is exactly what
            // regenerating is for.
            std::fs::rename(&new, &reference).unwrap_or_else(|e| panic!("{e}"));
            remove_if_present(&diff);
            eprintln!(
                "{stem}: overwrote {} (could not compare with it: {e})",
                reference.display()
            );
            return (row(stem, None, None, "updated"), None);
        }
        Err(e) => {
            let message = format!(
                "{stem}: cannot compare with the reference: {e}\n  This render is {}. \
                 Regenerate with `{REGENERATE}` if the reference is broken.",
                new.display()
            );
            return (row(stem, None, None, "FAIL: cannot compare"), Some(message));
        }
    };
    let cmp = verdict.cmp.clone();
    eprintln!(
        "{stem}: FLIP mean {:.6}, p99 {:.6}, worst 12x12 window {:.6}, max {:.6}; {}; checked: {}",
        cmp.mean,
        cmp.p99,
        cmp.worst_window,
        cmp.max,
        verdict.exactness,
        verdict.rule.short()
    );
    let rule_note = match &verdict.rule {
        Rule::BitExact => format!(
            "the reference was made with the same key ({}), so any difference is a change in \
             the output, not driver noise",
            Key::of(&render.text)
                .map(|k| k.describe())
                .unwrap_or_default()
        ),
        Rule::HdrExact { reference, this } => {
            let note = format!(
                "the reference was made on a CPU from {reference} and this run is on one from \
                 {this}, with the same device, driver and pinned code generation: the linear HDR image \
                 must be bit-identical, and the 8-bit image within 1/255 (the driver's sRGB \
                 encode uses the CPU's approximate rsqrtps)"
            );
            eprintln!("{stem}: note: {note}");
            note
        }
        Rule::FlipOnly { why } => {
            let note =
                format!("the bit-exact check did NOT run: {why}. Only the FLIP limits apply");
            eprintln!("{stem}: *** {note} ***");
            note
        }
    };

    if updating() {
        std::fs::rename(&new, &reference).unwrap_or_else(|e| panic!("{e}"));
        remove_if_present(&diff);
        eprintln!(
            "{stem}: overwrote {} (the numbers above are against the old one)",
            reference.display()
        );
        return (row(stem, Some(cmp), Some(verdict.rule), "updated"), None);
    }
    if verdict.passes {
        // Leave nothing behind from this or an earlier failed run.
        remove_if_present(&new);
        remove_if_present(&diff);
        return (row(stem, Some(cmp), Some(verdict.rule), "pass"), None);
    }
    write_diff_png(&cmp, &diff).unwrap_or_else(|e| panic!("{e}"));
    let limits = FLIP_DEFAULT_THRESHOLDS;
    let rule = match &verdict.rule {
        Rule::BitExact => "is not bit-identical to it (required with the reference's key)",
        Rule::HdrExact { .. } => {
            "is not within what another CPU vendor may change (the HDR image bit-identical, \
             the 8-bit image within 1/255 and the FLIP limits)"
        }
        Rule::FlipOnly { .. } => "is beyond the FLIP limits",
    };
    let message = format!(
        "{stem}: differs from {}: the render {rule}. FLIP mean {:.6} (limit {}), p99 {:.6} \
         (limit {}), worst 12x12 window {:.6} (limit {}), max {:.6}; {}.\n  This render:   {}\n  FLIP diff map: {} \
         (black = equal, bright = different)\n  Note: {rule_note}.\n  If the change is \
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
        verdict.exactness,
        new.display(),
        diff.display(),
    );
    (
        row(stem, Some(cmp), Some(verdict.rule), "FAIL"),
        Some(message),
    )
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
        "\n{:<16} {:>10} {:>10} {:>10} {:>10}  {:<34} result",
        "scene", "FLIP mean", "p99", "window", "max", "checked"
    );
    for row in &rows {
        let rule = row.rule.as_ref().map_or("-", Rule::short);
        match &row.flip {
            Some(c) => eprintln!(
                "{:<16} {:>10.6} {:>10.6} {:>10.6} {:>10.6}  {:<34} {}",
                row.stem, c.mean, c.p99, c.worst_window, c.max, rule, row.note
            ),
            None => eprintln!(
                "{:<16} {:>10} {:>10} {:>10} {:>10}  {:<34} {}",
                row.stem, "-", "-", "-", "-", rule, row.note
            ),
        }
    }
    let count = |f: fn(&Rule) -> bool| {
        rows.iter()
            .filter(|r| r.rule.as_ref().is_some_and(f))
            .count()
    };
    let exact = count(|r| matches!(r, Rule::BitExact));
    let hdr = count(|r| matches!(r, Rule::HdrExact { .. }));
    let flip: Vec<&str> = rows
        .iter()
        .filter(|r| matches!(r.rule, Some(Rule::FlipOnly { .. })))
        .map(|r| r.stem.as_str())
        .collect();
    eprintln!(
        "\nbit-exact check ran on {exact} of {} scenes ({PIN_VAR}={PIN}); HDR bit-exact with \
         the 8-bit image within 1/255 (a reference from another CPU vendor) on {hdr}; FLIP \
         limits only on {}",
        rows.len(),
        flip.len()
    );
    if !flip.is_empty() {
        eprintln!(
            "*** the bit-exact check did NOT run on: {} (the reason is on each scene's line \
             above) ***",
            flip.join(", ")
        );
    }
    assert!(
        failures.is_empty(),
        "{} screenshot regression failure(s):\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

/// The PNG text of a pinned lavapipe render on a host with `host_cpu`
/// (model and extensions, as `aerial::render_run::host_cpu` writes it) and the
/// host code generation key `codegen`, keyed for `arch`.
fn pinned_run(host_cpu: &str, codegen: &str, arch: &str) -> Result<Key, String> {
    let text: Text = [
        (DEVICE, "llvmpipe (LLVM 15.0.6, 128 bits)"),
        (
            DRIVER,
            "llvmpipe Mesa 22.3.6 (LLVM 15.0.6) (driverVersion 0x1)",
        ),
        (HOST_CPU, host_cpu),
        (CODEGEN, codegen),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    let text = keyed_text(text, "00".into(), arch)?;
    Ok(Key::of(&text).expect("keyed text has a key"))
}

/// Under the pin the host CPU's extensions (FMA, AVX2, AVX-512) are no
/// part of the key, so a reference made on one x86-64 CPU is bit-exact on
/// another of the same vendor, and HDR bit-exact on one of another vendor.
/// A CPU without what the pin keeps, a render whose pin did not take, and
/// a CPU that is not x86 are told apart.
#[test]
fn the_pinned_key_ignores_the_cpu_s_extensions_but_not_its_vendor() {
    let amd = pinned_run(
        "AMD EPYC [avx avx2 f16c fma sse sse2 sse4_1 sse4_2 sse4a]",
        "AuthenticAMD +fma -avx512f",
        "x86_64",
    )
    .unwrap();
    let amd_avx512 = pinned_run(
        "AMD EPYC 9004 [avx avx2 avx512f avx512bw f16c fma sse sse2 sse4_1 sse4_2 sse4a]",
        "AuthenticAMD +fma +avx512f",
        "x86_64",
    )
    .unwrap();
    assert_eq!(amd.codegen, format!("{PIN_VAR}={PIN} on x86_64"));
    assert_eq!(Rule::of(Some(&amd), &amd_avx512), Rule::BitExact);
    let old_amd = pinned_run(
        "AMD Opteron [sse sse2 sse4a]",
        "AuthenticAMD -fma -avx512f",
        "x86_64",
    )
    .unwrap();
    assert!(
        matches!(Rule::of(Some(&amd), &old_amd), Rule::FlipOnly { why } if why.contains("without sse4_1, sse4_2")),
        "{old_amd:?}"
    );
    let intel = pinned_run(
        "Intel Xeon [avx avx2 avx512f fma sse sse2 sse4_1 sse4_2]",
        "GenuineIntel +fma +avx512f",
        "x86_64",
    )
    .unwrap();
    assert_eq!(
        Rule::of(Some(&amd), &intel),
        Rule::HdrExact {
            reference: "AuthenticAMD".into(),
            this: "GenuineIntel".into()
        }
    );
    // Not x86: the pin does nothing, the host's key stays.
    let arm = pinned_run("unknown []", "aarch64 -fma -avx512f", "aarch64").unwrap();
    assert_eq!(arm.codegen, "aarch64 -fma -avx512f");
    assert!(matches!(Rule::of(Some(&amd), &arm), Rule::FlipOnly { .. }));
    // lavapipe on x86 that still reports 256-bit vectors ignored the pin.
    let text: Text = [
        (DEVICE, "llvmpipe (LLVM 15.0.6, 256 bits)"),
        (
            DRIVER,
            "llvmpipe Mesa 22.3.6 (LLVM 15.0.6) (driverVersion 0x1)",
        ),
        (CODEGEN, "GenuineIntel +fma -avx512f"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    let err = keyed_text(text, "00".into(), "x86_64").unwrap_err();
    assert!(err.contains("did not take effect"), "{err}");
}

/// Writes `pixels` with `text` as a PNG reference at `path`.
fn write_reference(path: &Path, pixels: &Pixels<u8>, text: &[(String, String)]) {
    let metadata: Vec<(&str, String)> = text.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    image_io::write_png(path, pixels, &metadata).unwrap_or_else(|e| panic!("{e}"));
}

/// `pixels` with one channel of one pixel moved by `by` (down where it
/// would pass 255).
fn nudged(pixels: &Pixels<u8>, by: u8) -> Pixels<u8> {
    let mut data = pixels.data.clone();
    let i = 4 * (pixels.width as usize * (pixels.height as usize / 2) + pixels.width as usize / 2);
    data[i] = if data[i] > 255 - by {
        data[i] - by
    } else {
        data[i] + by
    };
    Pixels {
        width: pixels.width,
        height: pixels.height,
        data,
    }
}

/// A reference one channel of one pixel off by 1/255 fails the suite's
/// judgement, where the FLIP limits alone pass it; so does a different HDR
/// hash. Checked on a reference made here and now (so on any host), and on
/// a copy of the committed `default.png` when this host's key is its key.
/// The committed references are not touched.
#[test]
fn a_one_lsb_change_to_a_reference_fails() {
    let scene = manifest_dir().join("assets/scenes/default.toml");
    let render = render_pinned(&scene).unwrap_or_else(|e| panic!("{e}"));
    let dir = tempfile::tempdir().unwrap();
    let new = dir.path().join("render.png");
    write_reference(&new, &render.pixels, &render.text);
    let judged =
        |reference: &Path| judge(reference, &new, &render).unwrap_or_else(|e| panic!("{e}"));

    // A reference made by this very render, then nudged by one LSB.
    let own = dir.path().join("own.png");
    write_reference(&own, &render.pixels, &render.text);
    let verdict = judged(&own);
    assert!(
        verdict.passes && verdict.rule == Rule::BitExact,
        "{}",
        verdict.exactness
    );
    write_reference(&own, &nudged(&render.pixels, 1), &render.text);
    let verdict = judged(&own);
    assert_eq!(verdict.rule, Rule::BitExact);
    assert!(
        verdict.cmp.passes(&FLIP_DEFAULT_THRESHOLDS),
        "a 1-LSB change is within the FLIP limits: {:?}",
        verdict.cmp
    );
    assert!(
        !verdict.passes,
        "a 1-LSB change passed: {}",
        verdict.exactness
    );

    // The same reference as if made on a CPU of another vendor (only under
    // the pin, where the key records the vendor apart): the HDR image is
    // held bit for bit, the 8-bit image to 1/255.
    if get(&render.text, VENDOR).is_some() {
        let mut other = render.text.clone();
        set(&mut other, VENDOR, "OtherVendor".into());
        write_reference(&own, &render.pixels, &other);
        let verdict = judged(&own);
        assert!(matches!(verdict.rule, Rule::HdrExact { .. }));
        assert!(verdict.passes, "{}", verdict.exactness);
        write_reference(&own, &nudged(&render.pixels, 2), &other);
        assert!(!judged(&own).passes, "a 2-LSB change passed");
        let mut other_hdr = other.clone();
        set(&mut other_hdr, HDR_HASH, "0".repeat(64));
        write_reference(&own, &render.pixels, &other_hdr);
        assert!(!judged(&own).passes, "another HDR image passed");
    }

    // A copy of the committed reference, nudged.
    let committed = reference_dir().join("default.png");
    let copy = dir.path().join("default.png");
    std::fs::copy(&committed, &copy).unwrap_or_else(|e| panic!("{}: {e}", committed.display()));
    let verdict = judged(&copy);
    if verdict.rule != Rule::BitExact {
        eprintln!(
            "*** the committed default.png was not made with this host's key ({:?}), so its \
             1-LSB check ran only on the reference made here ***",
            verdict.rule
        );
        return;
    }
    assert!(verdict.passes, "{}", verdict.exactness);
    let text = image_io::read_png_text(&copy).unwrap();
    let img = image::open(&copy).unwrap().to_rgba8();
    let (width, height) = img.dimensions();
    let pixels = Pixels {
        width,
        height,
        data: img.into_raw(),
    };
    write_reference(&copy, &nudged(&pixels, 1), &text);
    let verdict = judged(&copy);
    assert!(verdict.cmp.passes(&FLIP_DEFAULT_THRESHOLDS));
    assert!(
        !verdict.passes,
        "the committed reference nudged by 1 LSB passed: {}",
        verdict.exactness
    );
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
