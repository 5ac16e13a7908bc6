//! The sky with every order of scattering against full light transport
//! (`atmosphere::transport`: the exact single-scattering integral plus an
//! unbiased Monte Carlo estimate of every higher order, with its standard
//! error), at probe pixels of renders from the ground to 40 km, with the
//! sun from the zenith to below the horizon. The reference leaves out
//! polarisation, refraction and the sun's size for lighting (see its
//! module documentation); the renderer leaves them out too, so these
//! tests measure the approximation of Hillaire's multiple-scattering
//! table and the tables' resolution, not physics both omit.
//!
//! Also: the ground seen from a camera standing on it (altitude 0), which
//! once rendered black straight down and as bright sky just below the
//! horizon; and the single-scattering switch.

use crate::common;

use aerial::atmosphere::quadrature;
use aerial::atmosphere::transport::{full_radiance, TransportSettings, UNLIMITED};
use aerial::scene::Scene;

/// A 48×48 sky scene at altitude `h` (m), the sun `sun_elevation` degrees
/// above the horizon towards −z, the camera turned `azimuth` degrees from
/// the sun and looking `look_elevation` degrees up, ground albedo 0.1 (the
/// issue's probe settings), with the `[atmosphere]` fields `extra`.
fn sky(h: f64, sun_elevation: f64, azimuth: f64, look_elevation: f64, extra: &str) -> Scene {
    let (se, sa) = (sun_elevation.to_radians(), 0.0f64);
    let sun = [sa.sin() * se.cos(), se.sin(), -sa.cos() * se.cos()];
    let (le, la) = (look_elevation.to_radians(), azimuth.to_radians());
    let eye = [0.0, h, 0.0];
    let look = [la.sin() * le.cos(), h + le.sin(), -la.cos() * le.cos()];
    common::scene(&format!(
        "[output]\nwidth = 48\nheight = 48\nhdr_format = \"rgba32f\"\n\
         [camera]\neye = {eye:?}\nlook_at = {look:?}\nfov_y = 100.0\nnear = 0.1\n\
         [sun]\ndirection = {sun:?}\ndisc = false\n\
         [atmosphere]\nground_albedo = [0.1, 0.1, 0.1]\n{extra}"
    ))
}

/// Relative errors per channel of the render against full transport at
/// five probe pixels (the corners and the centre) (those within 5° of the sun left out), with
/// the reference's relative standard error alongside; and the smallest
/// rendered channel, to tell a black sky.
struct Probes {
    errors: Vec<(f64, f64)>,
    darkest: f64,
}

fn probe(label: &str, scene: &Scene, paths: u32) -> Probes {
    let hdr = common::render(scene, true).hdr.unwrap();
    let sky = scene.sky.as_ref().unwrap();
    let origin = scene.camera.eye - sky.atmosphere.center;
    let mut errors = Vec::new();
    let mut darkest = f64::INFINITY;
    for (x, y) in [(8, 8), (40, 8), (24, 24), (8, 40), (40, 40)] {
        {
            let d = common::pixel_ray(scene, x, y);
            if d.dot(sky.sun.direction) > 5f64.to_radians().cos() {
                continue;
            }
            let settings = TransportSettings {
                paths,
                seed: u64::from(x * 1000 + y),
                max_order: UNLIMITED,
            };
            let exact = full_radiance(&sky.atmosphere, &sky.sun, origin, d, settings);
            let got = common::hdr_pixel(&hdr, x, y);
            for c in 0..3 {
                let e = exact.radiance[c].max(1e-30);
                errors.push(((got[c] - e).abs() / e, exact.std_error[c] / e));
                darkest = darkest.min(got[c] / e);
            }
            println!(
                "{label} ({x}, {y}): gpu {}, full {} ± {}, single {}",
                e3(got),
                e3(exact.radiance),
                e3(exact.std_error),
                e3(exact.single)
            );
        }
    }
    Probes { errors, darkest }
}

/// A colour in three significant digits.
fn e3(c: glam::DVec3) -> String {
    format!("[{:.2e}, {:.2e}, {:.2e}]", c.x, c.y, c.z)
}

/// The median of the errors as measured (the reference's noise only adds
/// to it, so judging it is conservative), and their maximum less three of
/// its probe's standard errors (the reference's own noise is not the
/// renderer's error).
fn median_and_max(errors: &[(f64, f64)]) -> (f64, f64) {
    let mut raw: Vec<f64> = errors.iter().map(|(e, _)| *e).collect();
    raw.sort_by(f64::total_cmp);
    let max = errors
        .iter()
        .map(|(e, s)| (e - 3.0 * s).max(0.0))
        .fold(0.0, f64::max);
    (raw[raw.len() / 2], max)
}

#[test]
fn the_default_sky_matches_full_light_transport() {
    let mut day = Vec::new();
    let mut twilight = Vec::new();
    for h in [2.0, 10_000.0, 40_000.0] {
        for sun in [90.0, 45.0, 10.0, 2.0, -5.0] {
            let scene = sky(h, sun, 70.0, 30.0, "");
            let label = format!("{h} m, sun {sun}°");
            let probes = probe(&label, &scene, 4096);
            if sun < 0.0 {
                // Twilight: lit by higher orders; nothing black.
                assert!(probes.darkest > 0.2, "{label}: {}", probes.darkest);
                twilight.extend(probes.errors);
            } else {
                day.extend(probes.errors);
            }
        }
    }
    // The targets: median 3 %, max 8 %. Measured (4096 paths, the
    // reference's median standard error 1.1 %): median 1.7 %, max beyond
    // three standard errors 3.6 %.
    let (median, max) = median_and_max(&day);
    println!("sun 2-90° up: median {median:.3}, max {max:.3}");
    assert!(median <= 0.03, "median {median}");
    assert!(max <= 0.08, "max {max}");
    // In twilight the reference's paths reach sunlight rarely, so its
    // spread is wide and its own error estimate unreliable where few
    // paths score: only probes it knows to 5 % are judged.
    let known: Vec<(f64, f64)> = twilight.into_iter().filter(|(_, s)| *s <= 0.05).collect();
    assert!(
        known.len() >= 10,
        "{} twilight probes known to 5 %",
        known.len()
    );
    let (median, max) = median_and_max(&known);
    println!(
        "twilight ({} probes): median {median:.3}, max {max:.3}",
        known.len()
    );
    // Target 20 %; measured 4.3 % on 21 probes.
    assert!(max <= 0.2, "twilight max {max}");
}

/// Single scattering alone is too dark against full transport, by more
/// than the renderer's error with every order: the switch matters, and the
/// reference sees the difference.
#[test]
fn single_scattering_is_too_dark_against_full_transport() {
    let on = probe("on", &sky(2.0, 45.0, 150.0, 30.0, ""), 4096);
    let off = probe(
        "off",
        &sky(2.0, 45.0, 150.0, 30.0, "multiple_scattering = false\n"),
        4096,
    );
    let (on_median, _) = median_and_max(&on.errors);
    let (off_median, _) = median_and_max(&off.errors);
    println!("median error: on {on_median:.3}, off {off_median:.3}");
    assert!(off_median > 0.1, "off {off_median}");
    assert!(
        off_median > 3.0 * on_median,
        "on {on_median}, off {off_median}"
    );
}

/// A camera exactly on the ground sees the ground below the horizon: straight
/// down and a degree below the horizon towards a low sun, the ground's
/// radiance (as the reference integrates it), not black and not the sky.
#[test]
fn a_camera_on_the_ground_sees_the_ground() {
    for (label, look) in [
        ("straight down", [0.0, -1.0, 0.05]),
        ("1° below the horizon", [0.0, -0.01745, -0.99985]),
    ] {
        let scene = common::scene(&format!(
            "[output]\nwidth = 16\nheight = 16\nhdr_format = \"rgba32f\"\n\
             [camera]\neye = [0.0, 0.0, 0.0]\nlook_at = {look:?}\nfov_y = 1.0\nnear = 0.001\n\
             [sun]\ndirection = [0.0, 0.0872, -0.9962]\ndisc = false\n\
             [atmosphere]\nmultiple_scattering = false\n"
        ));
        let hdr = common::render(&scene, true).hdr.unwrap();
        let sky = scene.sky.as_ref().unwrap();
        let origin = scene.camera.eye - sky.atmosphere.center;
        let d = common::pixel_ray(&scene, 8, 8);
        let segment = quadrature::atmosphere_segment(&sky.atmosphere, origin, d);
        assert!(
            matches!(segment, Some((_, _, true))),
            "{label}: {segment:?}"
        );
        let exact = quadrature::radiance(&sky.atmosphere, &sky.sun, origin, d);
        let got = common::hdr_pixel(&hdr, 8, 8);
        println!("{label}: {got} against {exact}");
        assert!(exact.min_element() > 0.0, "{label}: {exact}");
        assert!(
            (got - exact).abs().max_element() <= 0.01 * exact.max_element(),
            "{label}: {got} against {exact}"
        );
    }
}
