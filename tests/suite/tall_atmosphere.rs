//! Tall atmospheres (`top_radius` far above the air, up to the accepted
//! 1e9 m) against the CPU double-precision reference: the sky from the
//! ground of Earth's noon at several tops and its sunset under the
//! tallest, a small planet, large scale
//! heights and an ozone layer far above the air, the planet and its limb
//! seen from space inside the nominal top, and a camera above the air but
//! inside the nominal top. The sky is held to the default scene's bound
//! (tests/atmosphere.rs: median relative error ≤ 1e-3, max ≤ 1e-2), views
//! from space to the same max and a 2e-3 median (see `check`). Every
//! render runs under validation.
//!
//! Before the pass cut the atmosphere where its air ends
//! (`Atmosphere::effective_top_radius`), Earth's noon sky was 16 % too
//! bright at `top_radius` = 3e7, 19 % at 1e8 and black from 3e8 up.

use crate::common;

use aerial::atmosphere::quadrature;
use aerial::render::Pixels;
use aerial::scene::Scene;
use glam::DVec3;

/// A sky-only 96×64 scene: camera at `eye` looking at `look_at`, sun
/// towards `sun`, `[atmosphere]` fields `atmosphere`, single scattering
/// (what `quadrature::radiance` integrates).
fn scene(eye: [f64; 3], look_at: [f64; 3], fov: f64, sun: [f64; 3], atmosphere: &str) -> Scene {
    common::scene(&format!(
        "[output]\nwidth = 96\nheight = 64\nhdr_format = \"rgba32f\"\n\
         [camera]\neye = {eye:?}\nlook_at = {look_at:?}\nfov_y = {fov}\nnear = 0.1\n\
         [sun]\ndirection = {sun:?}\n[atmosphere]\nmultiple_scattering = false\n{atmosphere}"
    ))
}

/// Earth's noon from 2 m (`earth_noon.toml`'s view) under `atmosphere`.
fn noon(atmosphere: &str) -> Scene {
    scene(
        [0.0, 2.0, 0.0],
        [0.0, 2.2, -1.0],
        70.0,
        [0.3, 0.866, 0.4],
        atmosphere,
    )
}

/// Which probe pixels count.
#[derive(Clone, Copy, PartialEq)]
enum Probes {
    /// Sky pixels only (rays that leave through the top), each relative
    /// to its own brightest channel: the default scene's test.
    Sky,
    /// Every pixel whose ray meets the atmosphere (sky, limb and ground
    /// through the air), relative to its brightest channel but at least a
    /// thousandth of the brightest probe: `--reference cpu`'s
    /// `max_rel_error` floor, so a limb pixel grazing the last wisp of air
    /// is not divided by ~0.
    All,
}

/// Relative errors of the rendered radiance at an 8×6 grid of probe
/// pixels against the reference (pixels within 5° of the sun left out):
/// (median, max) over probes and channels.
fn errors(label: &str, scene: &Scene, hdr: &Pixels<f32>, probes: Probes) -> (f64, f64) {
    let sky = scene.sky.as_ref().unwrap();
    let a = &sky.atmosphere;
    let origin = scene.camera.eye - a.center;
    let (w, h) = (scene.output.width, scene.output.height);
    let mut samples = Vec::new();
    for j in 0..6 {
        for i in 0..8 {
            let (x, y) = (w * (2 * i + 1) / 16, h * (2 * j + 1) / 12);
            let d = common::pixel_ray(scene, x, y);
            if d.dot(sky.sun.direction) > 5f64.to_radians().cos() {
                continue;
            }
            match (probes, quadrature::atmosphere_segment(a, origin, d)) {
                (Probes::Sky, Some((_, _, false))) | (Probes::All, Some(_)) => {}
                _ => continue,
            }
            let exact = quadrature::radiance(a, &sky.sun, origin, d);
            samples.push((exact, common::hdr_pixel(hdr, x, y), (x, y)));
        }
    }
    assert!(
        samples.len() >= 16,
        "{label}: only {} probes",
        samples.len()
    );
    let brightest = samples
        .iter()
        .map(|(e, _, _)| e.max_element())
        .fold(0.0, f64::max);
    assert!(brightest > 0.0, "{label}: every probe is black");
    let floor = match probes {
        Probes::Sky => 1e-300,
        Probes::All => 1e-3 * brightest,
    };
    // The median over the probes that show something (from space most
    // rays see black space, exactly); the max over all of them.
    let mut errors = Vec::new();
    let mut worst = (0.0, (0, 0), DVec3::ZERO, DVec3::ZERO);
    for &(exact, got, pixel) in &samples {
        let scale = exact.max_element().max(floor);
        let e = (got - exact).abs().max_element() / scale;
        if e > worst.0 {
            worst = (e, pixel, got, exact);
        }
        if exact.max_element() >= floor {
            errors.extend((0..3).map(|c| (got[c] - exact[c]).abs() / scale));
        }
    }
    errors.sort_by(f64::total_cmp);
    let median = errors[errors.len() / 2];
    let max = worst.0;
    println!(
        "{label}: {} probes ({} lit), relative error median {median:.2e}, max {max:.2e} \
         at {:?} ({} against {})",
        samples.len(),
        errors.len() / 3,
        worst.1,
        worst.2,
        worst.3
    );
    (median, max)
}

/// Renders `scene` under validation and holds it to the default's bound.
fn check(label: &str, scene: &Scene, probes: Probes) {
    let run = common::render(scene, true);
    assert!(run.passes.contains(&"atmosphere"), "{:?}", run.passes);
    let hdr = run.hdr.unwrap();
    for v in &hdr.data {
        assert!(v.is_finite() && *v >= 0.0, "{label}: value {v}");
    }
    let (median, max) = errors(label, scene, &hdr, probes);
    // From space the lit probes are mostly ground seen through the air,
    // which the default's own views from space are held to 2 % on
    // (tests/atmosphere.rs); here the max stays at the sky's 1e-2 and the
    // median at 2e-3 (measured: the default top's 4.1e-4 median and
    // 2.5e-3 max from 3e7 m; a tall top's 1.0e-3 and 3.9e-3 to 5.7e-3).
    let median_bound = match probes {
        Probes::Sky => 1e-3,
        Probes::All => 2e-3,
    };
    assert!(median <= median_bound, "{label}: median {median:e}");
    assert!(max <= 1e-2, "{label}: max {max:e}");
}

#[test]
fn earths_noon_sky_matches_the_reference_for_every_top_up_to_the_maximum() {
    for top in ["6420000.0", "3e7", "1e8", "3e8", "1e9"] {
        let scene = noon(&format!("top_radius = {top}\n"));
        check(&format!("noon, top {top}"), &scene, Probes::Sky);
    }
    // Every pixel marched (no sky-view table), at the largest top.
    let mut scene = noon("top_radius = 1e9\n");
    scene.sky.as_mut().unwrap().sky_view = None;
    check("noon, top 1e9, every pixel marched", &scene, Probes::Sky);
}

#[test]
fn a_sunset_under_the_tallest_top_matches_the_reference() {
    // The sun 1° up, looking towards its side of the sky: sun rays graze
    // the ground through the whole cut atmosphere.
    let scene = scene(
        [0.0, 2.0, 0.0],
        [-1.0, 2.4, 0.0],
        80.0,
        [-1.0, 0.0175, 0.0],
        "top_radius = 1e9\n",
    );
    check("sunset, top 1e9", &scene, Probes::Sky);
}

#[test]
fn other_planets_with_tall_atmospheres_match_the_reference() {
    for (label, atmosphere) in [
        // A 100 km moon under a 1e8 m atmosphere of Earth's air.
        (
            "small planet",
            "bottom_radius = 100000.0\ntop_radius = 1e8\nozone_layer = [1000.0, 2000.0, 3000.0]\n",
        ),
        // Scale heights of 100 km and 20 km under a 1e8 m top: the air
        // fills the first two thousand kilometres.
        (
            "large scale heights",
            "top_radius = 1e8\nrayleigh_scale_height = 100000.0\nmie_scale_height = 20000.0\n",
        ),
        // An absorbing layer from 100 to 300 km, above the air: the cut
        // keeps all of it.
        (
            "ozone far above the air",
            "top_radius = 1e9\nozone_layer = [100000.0, 200000.0, 300000.0]\n",
        ),
    ] {
        check(&format!("{label}, noon"), &noon(atmosphere), Probes::Sky);
    }
}

#[test]
fn a_tall_atmosphere_seen_from_space_matches_the_reference() {
    // The planet and its limb from 3e7 m off its centre, inside the 1e9 m
    // nominal top: ground through the air, the lit limb and the sky.
    let centre_y = -6_360_000.0;
    check(
        "planet from 3e7 m, default top",
        &scene(
            [0.0, centre_y, 3e7],
            [0.0, centre_y, 0.0],
            30.0,
            [1.0, 0.5, 0.3],
            "",
        ),
        Probes::All,
    );
    check(
        "planet from 3e7 m, top 1e9",
        &scene(
            [0.0, centre_y, 3e7],
            [0.0, centre_y, 0.0],
            30.0,
            [1.0, 0.5, 0.3],
            "top_radius = 1e9\n",
        ),
        Probes::All,
    );
    // From 1000 km above the ground, above the air (cut at about 160 km)
    // but inside the 1e8 m top, looking at the limb.
    let r = 6_360_000.0 + 1e6;
    let horizon_dip = (6_360_000.0f64 / r).acos();
    check(
        "limb from 1000 km, top 1e8",
        &scene(
            [0.0, 1e6, 0.0],
            [0.0, 1e6 - horizon_dip.tan(), -1.0],
            20.0,
            [0.4, 0.25, -0.88],
            "top_radius = 1e8\n",
        ),
        Probes::All,
    );
}
