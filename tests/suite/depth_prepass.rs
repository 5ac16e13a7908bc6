//! The depth pre-pass (`[output] depth_prepass`, knob `depth_prepass`):
//! with it, the opaque surfaces are drawn depth-only first and the colour
//! pass shades each covered pixel once, the image unchanged; the frame
//! lists the pass only when it is on; bad values are errors naming the
//! field or knob. Every render is under validation.

use crate::common;

use aerial::render_run::{self, RenderRun, RenderSettings};
use aerial::scene::{DepthPrepass, Scene};
use std::path::Path;

/// Four spheres one behind another, each a pipeline group that sorts
/// before the nearer one's (Phong before toon, one-sided before
/// two-sided), so without the pre-pass every layer is shaded and then
/// covered: heavy overdraw, lit by eight lights.
fn layered_spheres(prepass: &str) -> Scene {
    let mut toml = format!(
        "ambient = [0.1, 0.1, 0.1]\nlight_cutoff = 0.0\n\
         [output]\nwidth = 96\nheight = 64\ndepth_prepass = \"{prepass}\"\n\
         [camera]\neye = [0.0, 0.0, 12.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 40.0\n\
         [[materials]]\nname = \"phong\"\nkd = [0.7, 0.5, 0.3]\nks = [0.4, 0.4, 0.4]\n\
         shininess = 20.0\n\
         [[materials]]\nname = \"toon\"\nkd = [0.3, 0.5, 0.7]\nshading = \"toon\"\n"
    );
    for i in 0..8 {
        let x = f64::from(i % 4) * 4.0 - 6.0;
        let y = if i < 4 { 4.0 } else { -4.0 };
        toml += &format!(
            "[[lights]]\ntype = \"point\"\nposition = [{x}, {y}, 6.0]\n\
             color = [0.3, 0.3, 0.3]\nattenuation = [1.0, 0.0, 0.01]\n"
        );
    }
    // Farthest first: (material, two-sided, z, radius).
    for (i, (material, two_sided, z, radius)) in [
        ("phong", false, -9.0, 4.0),
        ("phong", true, -6.0, 3.4),
        ("toon", false, -3.0, 2.8),
        ("toon", true, 0.0, 2.2),
    ]
    .into_iter()
    .enumerate()
    {
        toml += &format!(
            "[[objects]]\nname = \"layer {i}\"\nmaterial = \"{material}\"\n\
             two_sided = {two_sided}\nshape = {{ type = \"sphere\", radius = {radius} }}\n\
             tessellation = [48, 24]\ntranslate = [0.0, 0.0, {z}]\n"
        );
    }
    common::scene(&toml)
}

/// Renders `scene` under validation, counting each pass's work.
fn render_counted(scene: &Scene) -> RenderRun {
    let run = render_run::render(
        scene,
        &RenderSettings {
            count_work: true,
            ..common::validated_settings()
        },
    )
    .unwrap_or_else(|e| panic!("render failed: {e}"));
    common::assert_no_validation_messages(&run);
    run
}

/// Samples that passed the depth test in pass `name`.
fn depth_passed(run: &RenderRun, name: &str) -> u64 {
    let i = run
        .passes
        .iter()
        .position(|p| *p == name)
        .unwrap_or_else(|| panic!("no pass {name} in {:?}", run.passes));
    run.frames.last().unwrap().work[i].depth_passed
}

/// The pixels an object covers: those unlike the black background (the
/// ambient term makes every surface pixel brighter).
fn covered_pixels(run: &RenderRun) -> u64 {
    run.output
        .data
        .chunks_exact(4)
        .filter(|c| c[..3] != [0, 0, 0])
        .count() as u64
}

#[test]
fn the_prepass_shades_each_covered_pixel_once_and_changes_no_pixel() {
    let off = render_counted(&layered_spheres("off"));
    let on = render_counted(&layered_spheres("on"));
    assert!(!off.passes.contains(&"depth prepass"), "{:?}", off.passes);
    assert!(on.passes.contains(&"depth prepass"), "{:?}", on.passes);
    let covered = covered_pixels(&off);
    common::assert_not_blank(&off.output, 0.1);
    // Without the pre-pass the far layers are shaded and then covered.
    let shaded_off = depth_passed(&off, "opaque");
    assert!(
        shaded_off as f64 > 1.5 * covered as f64,
        "{shaded_off} shaded for {covered} covered pixels: not the overdraw this test needs"
    );
    // With it, each covered pixel once: the nearest surface's fragment
    // alone passes the EQUAL test (no helper invocation passes a depth
    // test, so none is counted).
    let shaded_on = depth_passed(&on, "opaque");
    assert!(
        shaded_on as f64 <= 1.15 * covered as f64 && shaded_on >= covered,
        "{shaded_on} shaded for {covered} covered pixels"
    );
    // The same image: the pre-pass wrote the depths the colour pass draws.
    let worst = off
        .output
        .data
        .iter()
        .zip(&on.output.data)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(worst <= 1, "pixels differ by up to {worst}/255");
}

/// The frame print (`render --frames 2`) lists the pre-pass only when it
/// is on, and the knob's bad value is an error naming the knob.
#[test]
fn the_frame_lists_the_prepass_only_when_on() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png");
    let print = |value: &str| {
        let run = common::succeed(
            common::aerial()
                .arg("render")
                .arg(&scene)
                .args([
                    "--frames",
                    "2",
                    "--width",
                    "64",
                    "--height",
                    "36",
                    "--validate",
                ])
                .arg(format!("--knob=depth_prepass={value}"))
                .arg("--out")
                .arg(&out),
        );
        // The pass table's rows start with the pass's name (the note
        // under it names every kind of subpass).
        let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
        stdout.lines().any(|l| l.starts_with("depth prepass"))
    };
    assert!(print("on"));
    // default.toml: three objects, few lights; auto keeps it off.
    for value in ["off", "auto"] {
        assert!(!print(value), "{value}");
    }
    let bad = common::aerial()
        .arg("render")
        .arg(&scene)
        .arg("--knob=depth_prepass=sometimes")
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("depth_prepass") && err.contains("sometimes") && err.contains("on"),
        "{err}"
    );
}

#[test]
fn the_scene_field_parses_and_a_bad_value_names_file_and_field() {
    let scene = |value: &str| {
        Scene::from_toml(
            &format!(
                "[output]\ndepth_prepass = \"{value}\"\n\
                 [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n"
            ),
            "prepass.toml",
            Path::new("."),
        )
    };
    for (value, expected) in [
        ("off", DepthPrepass::Off),
        ("on", DepthPrepass::On),
        ("auto", DepthPrepass::Auto),
    ] {
        assert_eq!(scene(value).unwrap().output.depth_prepass, expected);
    }
    // Left out, it is "auto".
    let default = common::scene("[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n");
    assert_eq!(default.output.depth_prepass, DepthPrepass::Auto);
    let err = scene("always").unwrap_err().to_string();
    for part in [
        "prepass.toml",
        "depth_prepass",
        "always",
        "off",
        "on",
        "auto",
    ] {
        assert!(err.contains(part), "'{part}' not in: {err}");
    }
}

/// Identical spheres (one instance batch) in rows one behind another,
/// some out of view: the pre-pass draws the batch's members in view from
/// the instance buffer, so the colour pass's EQUAL test finds every
/// surface it shades and the image is the one without the pre-pass.
#[test]
fn instance_batches_get_the_same_depths_in_the_prepass() {
    let scene = |prepass: &str| {
        let mut toml = format!(
            "ambient = [0.1, 0.1, 0.1]\n\
             [output]\nwidth = 96\nheight = 64\ndepth_prepass = \"{prepass}\"\n\
             [camera]\neye = [0.5, 1.0, 9.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 40.0\n\
             [[lights]]\ntype = \"point\"\nposition = [2.0, 4.0, 6.0]\ncolor = [1.0, 1.0, 1.0]\n\
             [[materials]]\nname = \"clay\"\nkd = [0.7, 0.5, 0.3]\nks = [0.3, 0.3, 0.3]\n"
        );
        for i in 0..12 {
            // Three rows of four, 1.5 apart in depth; the last two far
            // to the side, out of view.
            let (x, z) = match i {
                10 | 11 => (40.0 + f64::from(i), 0.0),
                _ => (f64::from(i % 4) - 1.5, -1.5 * f64::from(i / 4)),
            };
            toml += &format!(
                "[[objects]]\nname = \"ball {i}\"\nmaterial = \"clay\"\n\
                 shape = {{ type = \"sphere\", radius = 0.9 }}\n\
                 tessellation = [24, 12]\ntranslate = [{x:.2}, 0.0, {z:.2}]\n"
            );
        }
        common::scene(&toml)
    };
    let off = render_counted(&scene("off"));
    let on = render_counted(&scene("on"));
    assert!(on.passes.contains(&"depth prepass"), "{:?}", on.passes);
    common::assert_not_blank(&off.output, 0.1);
    let covered = covered_pixels(&off);
    let shaded_on = depth_passed(&on, "opaque");
    assert!(
        shaded_on >= covered && shaded_on as f64 <= 1.15 * covered as f64,
        "{shaded_on} shaded for {covered} covered pixels"
    );
    assert_eq!(
        off.output.data, on.output.data,
        "the pre-pass changed the image"
    );
}
