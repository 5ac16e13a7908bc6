//! The GPU tone-map subpass against the operators' formulas, at several
//! exposures and through `aerial tonemap`, and its behaviour on values a
//! renderer can produce by accident (Inf, NaN, negatives). Every run is
//! under validation with zero messages.
//!
//! The subpass encodes sRGB itself into a UNORM output, so the CPU side
//! applies the sRGB transfer function too. For the curves the tolerance is
//! one 8-bit step (the shader evaluates them in f32, which can round a
//! value at a step's midpoint either way); the encode alone is held to
//! half a step.

use crate::common;

use aerial::render::Pixels;
use aerial::render_run::{self, RenderSettings, RunSource};
use aerial::scene::{Exposure, ToneMap, ToneMapOperator};

fn srgb_encode(linear: f64) -> f64 {
    let c = linear.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

fn reinhard(x: f64) -> f64 {
    x / (1.0 + x)
}

/// Narkowicz's ACES fit, as docs/frame.md names it.
fn aces(x: f64) -> f64 {
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// 0, then log-spaced values from 1e-4 to 1e4.
fn ramp() -> Vec<f32> {
    let mut v = vec![0.0f32];
    v.extend((0..=160).map(|i| 10f32.powf(-4.0 + i as f32 * 0.05)));
    v
}

fn check_operator(operator: ToneMapOperator, exposure: f32, curve: fn(f64) -> f64) {
    let ramp = ramp();
    // Each channel gets a different scale of the ramp, to catch channel mix-ups.
    let input: Vec<[f32; 4]> = ramp.iter().map(|&x| [x, 0.5 * x, 2.0 * x, 1.0]).collect();
    let out = common::tone_map_on_gpu(&input, operator, exposure);
    for (px, (inp, got)) in input.iter().zip(&out).enumerate() {
        for c in 0..3 {
            let expected = 255.0 * srgb_encode(curve(inp[c] as f64 * exposure as f64));
            assert!(
                (got[c] as f64 - expected).abs() <= 1.0,
                "{operator:?} pixel {px} channel {c}: input {}, gpu {}, expected {expected:.2}",
                inp[c],
                got[c]
            );
        }
    }
    assert_eq!(out[0], [0, 0, 0, 255], "0 must map to 0");
    for c in 0..3 {
        assert!(
            out.windows(2).all(|w| w[1][c] >= w[0][c]),
            "{operator:?} not monotonic in channel {c}"
        );
    }
}

#[test]
fn reinhard_matches_its_formula_and_is_monotonic() {
    check_operator(ToneMapOperator::Reinhard, 1.0, reinhard);
    check_operator(ToneMapOperator::Reinhard, 2.5, reinhard);
}

#[test]
fn aces_matches_its_formula_and_is_monotonic() {
    check_operator(ToneMapOperator::Aces, 1.0, aces);
}

#[test]
fn inf_nan_and_negative_inputs_give_defined_output() {
    let special = [
        [f32::INFINITY, f32::NAN, -1.0, 1.0],
        [f32::NEG_INFINITY, -f32::NAN, -1e30, 1.0],
        [f32::MAX, 0.0, -0.0, f32::NAN],
    ];
    for operator in [ToneMapOperator::Reinhard, ToneMapOperator::Aces] {
        let out = common::tone_map_on_gpu(&special, operator, 1.0);
        // +Inf and the largest float saturate to white; NaN, -Inf and
        // negatives become black; alpha is always opaque.
        assert_eq!(out[0], [255, 0, 0, 255], "{operator:?}");
        assert_eq!(out[1], [0, 0, 0, 255], "{operator:?}");
        assert_eq!(out[2], [255, 0, 0, 255], "{operator:?}");
    }
}

#[test]
fn tone_mapping_the_hdr_output_reproduces_the_render() {
    // The render's own tone-map subpass and `tonemap` on its HDR output
    // must agree bit for bit (the HDR image round-trips exactly).
    let mut scene = aerial::scene::Scene::default_scene();
    scene.set_output_size(Some(160), Some(90)).unwrap();
    let rendered = common::render(&scene, true);
    let hdr = rendered.hdr.as_ref().unwrap();
    let again = render_run::run(
        RunSource::HdrImage(hdr, scene.tone_map),
        &common::validated_settings(),
        &mut || {},
    )
    .unwrap();
    common::assert_no_validation_messages(&again);
    assert_eq!(rendered.output.data, again.output.data);
}

#[test]
fn a_mis_sized_image_is_an_error_not_a_crash() {
    let image = Pixels {
        width: 4,
        height: 4,
        data: vec![0.0; 10],
    };
    let result = render_run::run(
        RunSource::HdrImage(
            &image,
            ToneMap {
                operator: ToneMapOperator::Reinhard,
                exposure: Exposure::Fixed(1.0),
                bloom: None,
            },
        ),
        &RenderSettings::default(),
        &mut || {},
    );
    let err = result.err().expect("rejected").to_string();
    assert!(err.contains("4x4"), "{err}");
}

// Tone mapping: both operators at exposures other than 1, through the
// library and through `aerial tonemap --operator --exposure`. The oracle is
// the operators' formulas and the sRGB encoding, within one 8-bit step.

/// Log-spaced values 1e-3 .. 1e2 in R, half of them in G, twice in B.
fn hdr_ramp() -> Pixels<f32> {
    let n = 101;
    let data = (0..n)
        .flat_map(|i| {
            let x = 10f32.powf(-3.0 + i as f32 * 0.05);
            [x, 0.5 * x, 2.0 * x, 1.0]
        })
        .collect();
    Pixels {
        width: n,
        height: 1,
        data,
    }
}

fn assert_tone_mapped(
    what: &str,
    input: &Pixels<f32>,
    output: &[u8],
    exposure: f64,
    curve: fn(f64) -> f64,
) {
    assert_eq!(output.len(), input.data.len(), "{what}");
    let mut worst: f64 = 0.0;
    for (i, (inp, got)) in input.data.iter().zip(output).enumerate() {
        if i % 4 == 3 {
            assert_eq!(*got, 255, "{what}: alpha");
            continue;
        }
        let expected = 255.0 * srgb_encode(curve(*inp as f64 * exposure));
        worst = worst.max((*got as f64 - expected).abs());
        assert!(
            (*got as f64 - expected).abs() <= 1.0,
            "{what}: value {i}: input {inp}, got {got}, expected {expected:.2}"
        );
    }
    // Exposure must have mattered: without it some outputs would be off by
    // far more than the tolerance.
    let unexposed = input
        .data
        .iter()
        .zip(output)
        .enumerate()
        .filter(|(i, _)| i % 4 != 3)
        .map(|(_, (inp, got))| (255.0 * srgb_encode(curve(*inp as f64)) - *got as f64).abs())
        .fold(0.0, f64::max);
    assert!(
        unexposed > 10.0,
        "{what}: exposure {exposure} changed nothing"
    );
}

#[test]
fn both_operators_apply_the_exposure() {
    let input = hdr_ramp();
    for (operator, curve) in [
        (ToneMapOperator::Aces, aces as fn(f64) -> f64),
        (ToneMapOperator::Reinhard, reinhard),
    ] {
        for exposure in [0.3f32, 3.0] {
            let run = render_run::run(
                RunSource::HdrImage(
                    &input,
                    ToneMap {
                        operator,
                        exposure: Exposure::Fixed(exposure),
                        bloom: None,
                    },
                ),
                &common::validated_settings(),
                &mut || {},
            )
            .unwrap();
            common::assert_no_validation_messages(&run);
            assert_tone_mapped(
                &format!("{operator:?} at exposure {exposure}"),
                &input,
                &run.output.data,
                exposure as f64,
                curve,
            );
        }
    }
}

#[test]
fn the_tonemap_command_honours_operator_and_exposure() {
    let dir = common::fresh_dir("tonemap", "command");
    let exr = dir.join("ramp.exr");
    let input = hdr_ramp();
    aerial::image_io::write_exr(&exr, &input).unwrap();
    for (operator, curve, exposure) in [
        ("aces", aces as fn(f64) -> f64, 2.5),
        ("reinhard", reinhard as fn(f64) -> f64, 0.4),
    ] {
        let png = dir.join(format!("{operator}.png"));
        let out = common::aerial()
            .arg("tonemap")
            .arg(&exr)
            .args(["--operator", operator, "--exposure", &exposure.to_string()])
            .arg("--validate")
            .arg("--out")
            .arg(&png)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{operator}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let img = image::open(&png).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (input.width, input.height));
        assert_tone_mapped(
            &format!("aerial tonemap --operator {operator} --exposure {exposure}"),
            &input,
            img.as_raw(),
            exposure,
            curve,
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The 8-bit output's sRGB encode is the exact piecewise curve, computed in
/// the tone-map shader (the output is UNORM, so no driver encode with its
/// own approximation is involved): every byte of a fine gradient through
/// the clamping tone map is within half a step of the f64 encode of its
/// input, and the bytes never step down. The gradient holds every
/// 16-bit step of [0, 1], the knee at 0.0031308 and, for every byte, the
/// inputs just below and above the one whose exact encode falls halfway
/// between two bytes (where a loose encode rounds the wrong way). The
/// margin beyond half a step is f32 arithmetic's, not an approximation's.
#[test]
fn the_srgb_encode_is_within_half_a_step_of_the_exact_curve() {
    let decode = |e: f64| {
        if e <= 0.04045 {
            e / 12.92
        } else {
            ((e + 0.055) / 1.055).powf(2.4)
        }
    };
    let mut values: Vec<f32> = (0..=65535).map(|i| i as f32 / 65535.0).collect();
    values.extend([0.0031308, 0.0031307, 0.0031309]);
    for k in 0..255 {
        // The linear value whose exact encode is (k + 0.5) / 255, and its
        // neighbours a relative 1e-4 either side.
        let half = decode((k as f64 + 0.5) / 255.0);
        values.extend([half * (1.0 - 1e-4), half * (1.0 + 1e-4)].map(|v| v as f32));
    }
    values.sort_by(f32::total_cmp);
    let width = 512u32;
    let height = values.len().div_ceil(width as usize) as u32;
    let mut data: Vec<f32> = values.iter().flat_map(|&v| [v, v, v, 1.0]).collect();
    data.resize((width * height * 4) as usize, 1.0);
    let image = Pixels {
        width,
        height,
        data,
    };
    let tone_map = ToneMap {
        operator: ToneMapOperator::None,
        exposure: Exposure::Fixed(1.0),
        bloom: None,
    };
    let run = render_run::run(
        RunSource::HdrImage(&image, tone_map),
        &common::validated_settings(),
        &mut || {},
    )
    .expect("tone map runs");
    common::assert_no_validation_messages(&run);
    let mut worst = (0.0f64, 0.0f32);
    let (mut off, mut down) = (0, 0);
    for (i, &v) in values.iter().enumerate() {
        let exact = 255.0 * srgb_encode(f64::from(v));
        for c in 0..3 {
            let error = (f64::from(run.output.data[i * 4 + c]) - exact).abs();
            if error > worst.0 {
                worst = (error, v);
            }
            off += usize::from(error > 0.5 + 1e-3);
        }
        assert_eq!(run.output.data[i * 4 + 3], 255);
        down += usize::from(i > 0 && run.output.data[i * 4] < run.output.data[(i - 1) * 4]);
    }
    eprintln!(
        "{} inputs: {off} bytes more than half a step off, {down} steps down; \
         largest distance {:.5} steps, at {:e}",
        values.len(),
        worst.0,
        worst.1
    );
    assert_eq!(
        off, 0,
        "largest distance {} steps, at {:e}",
        worst.0, worst.1
    );
    assert_eq!(down, 0, "the encode is not monotonic");
}
