//! Automatic exposure (`[tone_map] exposure = "auto"`, knob `exposure`):
//! the exposure pass measures the log-average luminance of the HDR image
//! between the render pass that draws it and the one that tone-maps it,
//! and the tone map applies 0.18 / Lavg. The measured value matches the
//! same average computed on the CPU from the HDR image; the frame holds
//! the pass (and two render passes) only when asked; bad values are
//! errors naming the file, the field and the reason. Every render is
//! under validation (synchronization included).

use crate::common;

use aerial::render::passes::exposure::sample_step;
use aerial::render::passes::{atmosphere, exposure, tonemap};
use aerial::render::{FramePlan, Pixels, SceneGeometry};
use aerial::render_run::{self, RenderRun, RenderSettings};
use aerial::scene::{Exposure, Scene, KNOBS};
use std::path::Path;

fn earth_noon(width: u32, height: u32) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/earth_noon.toml");
    let mut scene = Scene::load(&path).expect("earth_noon.toml loads");
    scene.output.width = width;
    scene.output.height = height;
    scene
}

/// A lit sphere on a dark background: a frame without an atmosphere.
fn sphere_scene(width: u32, height: u32, exposure: &str) -> Scene {
    common::scene(&format!(
        "ambient = [0.05, 0.05, 0.05]\n\
         [output]\nwidth = {width}\nheight = {height}\n\
         [tone_map]\nexposure = {exposure}\n\
         [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         [[lights]]\ntype = \"point\"\nposition = [2.0, 3.0, 4.0]\nintensity = 3.0\n\
         [[materials]]\nname = \"m\"\nkd = [0.8, 0.5, 0.3]\n\
         [[objects]]\nname = \"ball\"\nmaterial = \"m\"\n\
         shape = {{ type = \"sphere\", radius = 1.5 }}\n"
    ))
}

fn render_validated(scene: &Scene, keep_hdr: bool) -> RenderRun {
    let run = render_run::render(
        scene,
        &RenderSettings {
            keep_hdr,
            ..common::validated_settings()
        },
    )
    .unwrap_or_else(|e| panic!("render failed: {e}"));
    common::assert_no_validation_messages(&run);
    run
}

/// The exposure the pass should measure, in f64: 0.18 over the
/// log-average Rec. 709 luminance of every `step`-th pixel in x and y,
/// black (below 1e-4) and non-finite samples skipped, clamped to
/// [1e-6, 1e6].
fn cpu_exposure(hdr: &Pixels<f32>) -> f64 {
    let step = sample_step(hdr.width, hdr.height) as usize;
    let (mut sum, mut count) = (0.0f64, 0u64);
    for y in (0..hdr.height).step_by(step) {
        for x in (0..hdr.width).step_by(step) {
            let p = common::pixel(hdr, x, y);
            let l = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            // Black (below 1e-4) and non-finite samples are skipped.
            if l.is_finite() && l >= 1e-4 {
                sum += l.ln();
                count += 1;
            }
        }
    }
    assert!(count > 0, "no lit HDR sample");
    (0.18 / (sum / count as f64).exp()).clamp(1e-6, 1e6)
}

/// Renders `auto` (a scene with `exposure = "auto"`) keeping its HDR
/// image, computes the expected exposure from it on the CPU, renders the
/// same scene with that fixed exposure and compares the 8-bit outputs.
///
/// Tolerance 1/255 per channel: the GPU sums the logarithms in f32 in
/// another order than the CPU's f64, so its exposure differs from the
/// oracle's in the last few bits (relative ~1e-6); through a monotonic
/// curve that can move a value across one rounding boundary of the 8-bit
/// output, never by two.
fn check_against_cpu_oracle(mut auto: Scene) {
    assert_eq!(auto.tone_map.exposure, Exposure::Auto);
    let measured = render_validated(&auto, true);
    assert!(measured.passes.contains(&exposure::PASS.name()));
    let hdr = measured.hdr.as_ref().expect("the HDR image was kept");
    let expected = cpu_exposure(hdr);
    common::assert_not_blank(&measured.output, 0.05);
    auto.tone_map.exposure = Exposure::Fixed(expected as f32);
    let fixed = render_validated(&auto, false);
    assert!(!fixed.passes.contains(&exposure::PASS.name()));
    let worst = measured
        .output
        .data
        .iter()
        .zip(&fixed.output.data)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap_or(0);
    assert!(
        worst <= 1,
        "auto exposure differs from the fixed exposure {expected} by {worst}/255"
    );
}

#[test]
fn auto_exposure_matches_the_cpu_log_average_on_earth_noon() {
    let mut scene = earth_noon(96, 64);
    scene.tone_map.exposure = Exposure::Auto;
    check_against_cpu_oracle(scene);
}

#[test]
fn auto_exposure_matches_the_cpu_log_average_on_a_sampled_grid() {
    // 400x200 pixels: more than 65536, so every second pixel is sampled.
    assert_eq!(sample_step(400, 200), 2);
    check_against_cpu_oracle(sphere_scene(400, 200, "\"auto\""));
}

#[test]
fn the_grid_keeps_at_most_about_65k_samples() {
    assert_eq!(sample_step(1, 1), 1);
    assert_eq!(sample_step(256, 256), 1);
    assert_eq!(sample_step(257, 256), 2);
    assert_eq!(sample_step(1280, 720), 4);
    for (w, h) in [(1280, 720), (1920, 1080), (4096, 4096), (7, 100_000)] {
        let s = sample_step(w, h);
        let samples = u64::from(w.div_ceil(s)) * u64::from(h.div_ceil(s));
        assert!(samples <= 65536 + u64::from(w.max(h)), "{w}x{h}: {samples}");
    }
}

fn plan_of(scene: &Scene) -> FramePlan {
    FramePlan::new(scene, &SceneGeometry::new(scene).unwrap(), false)
}

#[test]
fn only_auto_frames_hold_the_exposure_pass_and_a_second_render_pass() {
    let fixed = plan_of(&sphere_scene(64, 48, "1.0"));
    assert!(!fixed.has(exposure::PASS));
    assert_eq!(fixed.render_pass_count(), 1);
    let auto = plan_of(&sphere_scene(64, 48, "\"auto\""));
    let names = auto.pass_names();
    let at = |name: &str| names.iter().position(|n| *n == name).unwrap();
    assert_eq!(at("exposure") + 1, at(tonemap::PASS.name()), "{names:?}");
    assert!(at("opaque") < at("exposure"), "{names:?}");
    assert_eq!(auto.render_pass_count(), 2);

    let mut sky = earth_noon(32, 24);
    assert_eq!(plan_of(&sky).render_pass_count(), 1);
    sky.tone_map.exposure = Exposure::Auto;
    let plan = plan_of(&sky);
    let names = plan.pass_names();
    let at = |name: &str| names.iter().position(|n| *n == name).unwrap();
    assert_eq!(at(atmosphere::PASS.name()) + 1, at("exposure"), "{names:?}");
    assert_eq!(at("exposure") + 1, at(tonemap::PASS.name()), "{names:?}");
    assert_eq!(plan.render_pass_count(), 2);
}

#[test]
fn bad_exposures_name_the_file_the_field_and_the_reason() {
    for (value, reason) in [
        ("\"sometimes\"", "\"auto\""),
        ("0.0", "greater than 0"),
        ("-2.0", "greater than 0"),
        ("nan", "finite"),
    ] {
        let toml = format!(
            "[tone_map]\nexposure = {value}\n\
             [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n"
        );
        let err = Scene::from_toml(&toml, "bad_exposure.toml", Path::new("."))
            .err()
            .unwrap_or_else(|| panic!("exposure = {value} loaded"))
            .to_string();
        for part in ["bad_exposure.toml", "tone_map.exposure", reason] {
            assert!(
                err.contains(part),
                "exposure = {value}: '{err}' lacks '{part}'"
            );
        }
    }
}

#[test]
fn the_exposure_knob_takes_auto_or_a_positive_number() {
    let knob = KNOBS.iter().find(|k| k.name == "exposure").unwrap();
    let mut scene = sphere_scene(16, 16, "1.0");
    (knob.apply)(&mut scene, "auto").unwrap();
    assert_eq!(scene.tone_map.exposure, Exposure::Auto);
    assert_eq!((knob.read)(&scene), "auto");
    (knob.apply)(&mut scene, "2.5").unwrap();
    assert_eq!(scene.tone_map.exposure, Exposure::Fixed(2.5));
    for bad in ["sometimes", "0", "-1", "NaN", "inf"] {
        assert!(
            (knob.apply)(&mut scene, bad).is_err(),
            "knob exposure={bad}"
        );
    }
}
