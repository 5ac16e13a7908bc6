//! Aerial perspective from the froxel volume (`aerial_perspective =
//! "volume"`) against the per-pixel march it replaces: the same image
//! within a tolerance measured on `earth_objects`, with and without the
//! sky-view table and multiple scattering; everything but the surfaces
//! bit-identical; the march, the default, unchanged bit for bit; the
//! volume's pass only where it serves surfaces; bad field values refused by
//! name. Every render runs under validation.

use crate::common;

use aerial::render::Pixels;
use aerial::scene::{AerialPerspective, Scene};
use std::path::Path;

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn with_mode(mut scene: Scene, mode: AerialPerspective) -> Scene {
    scene.sky.as_mut().unwrap().aerial_perspective = mode;
    scene
}

/// The HDR image and pass names of `scene`, rendered under validation.
fn hdr(scene: &Scene) -> (Pixels<f32>, Vec<&'static str>) {
    let run = common::render(scene, true);
    (run.hdr.expect("HDR kept"), run.passes)
}

/// How the volume's image differs from the march's: the pixels that differ
/// at all, and over them the largest relative error of a channel and the
/// root mean square of the relative error (relative to the march's
/// channel, at least a thousandth of the image's brightest channel, so
/// that a black shadow does not divide by zero).
struct Difference {
    differing: usize,
    max_relative: f64,
    rms_relative: f64,
}

fn difference(march: &Pixels<f32>, volume: &Pixels<f32>) -> Difference {
    assert_eq!((march.width, march.height), (volume.width, volume.height));
    let brightest = march
        .data
        .chunks_exact(4)
        .flat_map(|p| p[..3].iter().copied())
        .fold(0.0_f32, f32::max) as f64;
    assert!(brightest > 0.0, "a black march image");
    let floor = 1e-3 * brightest;
    let mut d = Difference {
        differing: 0,
        max_relative: 0.0,
        rms_relative: 0.0,
    };
    let mut sum = 0.0;
    for (m, v) in march.data.chunks_exact(4).zip(volume.data.chunks_exact(4)) {
        if m[..3] == v[..3] {
            continue;
        }
        d.differing += 1;
        for c in 0..3 {
            assert!(v[c].is_finite() && v[c] >= 0.0, "volume pixel {v:?}");
            let e = (f64::from(v[c]) - f64::from(m[c])).abs() / f64::from(m[c]).max(floor);
            d.max_relative = d.max_relative.max(e);
            sum += e * e;
        }
    }
    if d.differing > 0 {
        d.rms_relative = (sum / (3 * d.differing) as f64).sqrt();
    }
    d
}

/// `earth_objects` (five grey spheres from 40 m to 13 km, the farthest
/// seen through air of transmittance about 0.6 in blue), at 320x180, with
/// the default 32x32x32 volume, against the march, with the sky-view table
/// and without, with multiple scattering and without.
///
/// Measured (lavapipe): over the surface pixels the largest relative
/// error of a channel is 1.9e-3 and its RMS 9.7e-5 with the sky view and
/// multiple scattering (the bottom row of the farthest sphere, just above
/// the horizon, where the in-scattering changes fastest from one row of
/// columns to the next); before the objects were lit by the sky as well,
/// 4.6e-3 with multiple scattering and 2.8e-3 without, RMS 1.4e-4 and
/// 1.3e-4. The volume read with
/// its transmittance ignored (colour plus in-scattering) misses by up to
/// 0.48 (RMS 0.13); its slices read as if evenly spaced, by up to 0.95
/// (RMS 0.13); its columns read one column to the right, by up to 1.7e-2
/// (RMS 2.1e-3). The tolerances, 1e-2 largest and 1e-3 RMS, fail all
/// three.
#[test]
fn the_volume_matches_the_march_in_front_of_objects() {
    let base = load("earth_objects.toml");
    for (sky_view, multiple) in [(true, true), (false, true), (true, false), (false, false)] {
        let mut scene = base.clone();
        scene.set_output_size(Some(320), Some(180)).unwrap();
        let sky = scene.sky.as_mut().unwrap();
        if !sky_view {
            sky.sky_view = None;
        }
        sky.multiple_scattering = multiple;
        let label = format!("sky view {sky_view}, multiple scattering {multiple}");
        let (march, march_passes) = hdr(&with_mode(scene.clone(), AerialPerspective::March));
        let (volume, volume_passes) = hdr(&with_mode(scene.clone(), AerialPerspective::Volume));
        assert!(!march_passes.contains(&"aerial volume"), "{march_passes:?}");
        assert!(
            volume_passes.contains(&"aerial volume"),
            "{volume_passes:?}"
        );
        let d = difference(&march, &volume);
        println!(
            "{label}: {} pixels differ, relative error max {:.2e}, rms {:.2e}",
            d.differing, d.max_relative, d.rms_relative
        );
        // The five spheres cover about 2 % of the 57 600 pixels; only they
        // read the volume: the sky and the ground are drawn as before.
        assert!(
            (500..3000).contains(&d.differing),
            "{label}: {} pixels differ",
            d.differing
        );
        assert!(d.max_relative <= 1e-2, "{label}: max {:e}", d.max_relative);
        assert!(d.rms_relative <= 1e-3, "{label}: rms {:e}", d.rms_relative);
    }
}

/// "march" is the default and draws exactly the image it drew before the
/// volume existed: the same pipelines, no volume pass. A scene without
/// objects gets no volume pass either, and its image does not depend on
/// the mode.
#[test]
fn the_march_is_the_default_and_unchanged_bit_for_bit() {
    let mut scene = load("earth_objects.toml");
    scene.set_output_size(Some(160), Some(90)).unwrap();
    assert_eq!(
        scene.sky.as_ref().unwrap().aerial_perspective,
        AerialPerspective::March
    );
    let (default, passes) = hdr(&scene);
    assert!(!passes.contains(&"aerial volume"), "{passes:?}");
    let (march, _) = hdr(&with_mode(scene.clone(), AerialPerspective::March));
    assert!(default.data == march.data, "the default is not the march");

    let mut sky_only = load("earth_noon.toml");
    sky_only.set_output_size(Some(160), Some(90)).unwrap();
    let (march, _) = hdr(&with_mode(sky_only.clone(), AerialPerspective::March));
    let (volume, passes) = hdr(&with_mode(sky_only, AerialPerspective::Volume));
    assert!(!passes.contains(&"aerial volume"), "{passes:?}");
    assert!(march.data == volume.data, "a sky without objects changed");
}

/// A volume the size of the screen in columns and 64 slices reads closer
/// to the march than the default 32^3: the error is the volume's
/// resolution, not a fixed bias. Odd, unequal sides exercise the layout.
#[test]
fn a_finer_volume_is_closer_to_the_march() {
    let mut scene = load("earth_objects.toml");
    scene.set_output_size(Some(160), Some(90)).unwrap();
    let (march, _) = hdr(&scene);
    let mut errors = Vec::new();
    for size in [(7, 5, 9), (32, 32, 32), (160, 90, 64)] {
        let mut scene = with_mode(scene.clone(), AerialPerspective::Volume);
        scene.sky.as_mut().unwrap().aerial_volume = size;
        let (volume, _) = hdr(&scene);
        let d = difference(&march, &volume);
        println!(
            "{size:?}: relative error max {:.2e}, rms {:.2e}",
            d.max_relative, d.rms_relative
        );
        errors.push(d.rms_relative);
    }
    assert!(
        errors[0] > 2.0 * errors[1] && errors[1] > 2.0 * errors[2],
        "{errors:?}"
    );
}

/// Bad values of both fields are refused with the file, the field and the
/// reason; so are bad knob values.
#[test]
fn bad_aerial_values_are_refused_by_name() {
    let head = "[camera]\neye = [0.0, 2.0, 0.0]\nlook_at = [0.0, 2.0, -1.0]\n\
                [sun]\ndirection = [0.0, 1.0, 0.0]\n[atmosphere]\n";
    for (line, field, reason) in [
        (
            "aerial_volume = \"32x32\"",
            "atmosphere.aerial_volume",
            "WIDTHxHEIGHTxDEPTH",
        ),
        (
            "aerial_volume = \"32x1x32\"",
            "atmosphere.aerial_volume",
            "between 2 and 256",
        ),
        (
            "aerial_volume = \"32x32x257\"",
            "atmosphere.aerial_volume",
            "between 2 and 256",
        ),
        (
            "aerial_volume = \"32x-3x32\"",
            "atmosphere.aerial_volume",
            "'-3'",
        ),
        (
            "aerial_perspective = \"froxels\"",
            "aerial_perspective",
            "march",
        ),
    ] {
        let text = format!("{head}{line}\n");
        let e = Scene::from_toml(&text, "bad.toml", Path::new("."))
            .err()
            .unwrap_or_else(|| panic!("accepted: {line}"))
            .to_string();
        assert!(e.starts_with("bad.toml"), "{e}");
        assert!(e.contains(field) && e.contains(reason), "{line}: {e}");
    }
    let mut scene = load("earth_objects.toml");
    for (knob, value) in [
        ("aerial_volume", "0x32x32"),
        ("aerial_volume", "32x32"),
        ("aerial_perspective", "both"),
    ] {
        let e = aerial::scene::Knob::find(knob)
            .unwrap()
            .set(&mut scene, value)
            .unwrap_err()
            .to_string();
        assert!(e.contains(knob) && e.contains(value), "{e}");
    }
}
