//! The atmosphere's sun and sky light on objects, per shaded point: a
//! 600 m sphere standing on the ground, rendered forward and deferred, with
//! Phong, Gouraud and toon materials, against the f64 reference.
//!
//! The sun: under a sun 4° up, the transmittance from the sphere's lower
//! and upper sun-facing flanks (89 m and 513 m up) differs by 17 % (blue),
//! so one colour per object fails; each probe pixel's sun
//! term, recovered from the image by removing the aerial perspective of the
//! 12 m of air in front of it (from the reference), must match
//! kd·cos·E·T(point) within 1e-3. The sky: the sphere's shadowed side under
//! a sun 30° up is lit, bluish where it faces up, and matches the tilted-surface model
//! (`glsl/include/object_air.glsl`) with the horizontal irradiance of full
//! light transport; the model's own error against full transport over the
//! tilted hemisphere is measured by an ignored test
//! (`sky_light_model_against_full_transport`, figures in
//! docs/atmosphere.md). Every render runs under validation.

use crate::common;

use aerial::atmosphere::transport::{sky_irradiance, TransportSettings, UNLIMITED};
use aerial::atmosphere::{quadrature, Atmosphere, Sun};
use aerial::render::{render_on_cpu_with, Transport};
use aerial::scene::Scene;
use glam::DVec3;

const RADIUS: f64 = 300.0;
/// The sphere's centre: its bottom 1 m above the ground.
const CENTRE: [f64; 3] = [0.0, 301.0, 0.0];
/// How far the camera stands from each probe point, along its normal.
const DISTANCE: f64 = 12.0;
/// Image size; the probe is the pixel next to the centre.
const SIZE: u32 = 16;
const PROBE: (u32, u32) = (8, 8);
const KD: f64 = 0.8;

/// Towards the sun, `degrees` above the horizon, along +X.
fn sun_at(degrees: f64) -> DVec3 {
    let e = degrees.to_radians();
    DVec3::new(e.cos(), e.sin(), 0.0)
}

/// The unit normal in the XY plane at `degrees` above the horizontal,
/// facing +X (`towards_sun`) or -X.
fn normal_at(degrees: f64, towards_sun: bool) -> DVec3 {
    let e = degrees.to_radians();
    let x = if towards_sun { e.cos() } else { -e.cos() };
    DVec3::new(x, e.sin(), 0.0)
}

/// The sphere under a sun `sun_degrees` up, seen from DISTANCE metres out
/// along `normal` from its surface point there; a white-ish Lambertian
/// material of `shading` (no specular, no ambient), no other light.
fn sphere_scene(
    sun_degrees: f64,
    normal: DVec3,
    shading: &str,
    lighting: &str,
    multiple_scattering: bool,
) -> Scene {
    let centre = DVec3::from(CENTRE);
    let point = centre + RADIUS * normal;
    let eye = point + DISTANCE * normal;
    let sun = sun_at(sun_degrees);
    common::scene(&format!(
        "ambient = [0.0, 0.0, 0.0]\n\
         [output]\nwidth = {SIZE}\nheight = {SIZE}\nhdr_format = \"rgba32f\"\nlighting = \"{lighting}\"\n\
         [camera]\neye = {:?}\nlook_at = {:?}\nup = [0.0, 0.0, 1.0]\nfov_y = 20.0\nnear = 0.5\n\
         [[materials]]\nname = \"white\"\nkd = [{KD}, {KD}, {KD}]\nks = [0.0, 0.0, 0.0]\nshading = \"{shading}\"\n\
         [[objects]]\nname = \"sphere\"\nmaterial = \"white\"\n\
         shape = {{ type = \"sphere\", radius = {RADIUS} }}\ntessellation = [1024, 512]\n\
         translate = {CENTRE:?}\n\
         [sun]\ndirection = {:?}\n\
         [atmosphere]\nmultiple_scattering = {multiple_scattering}\n",
        eye.to_array(),
        point.to_array(),
        sun.to_array(),
    ))
}

/// Where pixel (x, y)'s ray meets the analytic sphere: the distance, the
/// point and the outward normal there.
fn hit(scene: &Scene, x: u32, y: u32) -> (f64, DVec3, DVec3) {
    let eye = scene.camera.eye;
    let d = common::pixel_ray(scene, x, y);
    let o = eye - DVec3::from(CENTRE);
    let b = o.dot(d);
    let c = o.length_squared() - RADIUS * RADIUS;
    let t = -b - (b * b - c).sqrt();
    let point = eye + t * d;
    (t, point, (point - DVec3::from(CENTRE)) / RADIUS)
}

/// The surface's own radiance at pixel (x, y) of `hdr`: the pixel with
/// the air in front of it removed (the reference's single-scattered light
/// and transmittance over those metres).
fn surface_radiance(scene: &Scene, pixel: DVec3, x: u32, y: u32) -> DVec3 {
    let sky = scene.sky.as_ref().unwrap();
    let a = &sky.atmosphere;
    let eye = scene.camera.eye;
    let d = common::pixel_ray(scene, x, y);
    let (t, _, _) = hit(scene, x, y);
    let (inscattered, view) = quadrature::aerial_perspective(a, &sky.sun, eye - a.center, d, t);
    (pixel - inscattered) / view
}

/// The sun's colour at `point` (world space): E · T, exact.
fn sun_colour(scene: &Scene, point: DVec3) -> DVec3 {
    let sky = scene.sky.as_ref().unwrap();
    let a = &sky.atmosphere;
    sky.sun.irradiance * quadrature::sun_transmittance(a, point - a.center, sky.sun.direction)
}

fn relative_error(got: DVec3, want: DVec3) -> f64 {
    ((got - want).abs() / want.abs().max(DVec3::splat(1e-12))).max_element()
}

/// The sun term at the sphere's lower and upper sun-facing flanks, 45°
/// below and above its equator (89 m and 513 m up), under a sun 4° up,
/// for every shading model and both lighting paths: within 1e-3 of
/// kd·cos·E·T(point) (toon: kd·E·T, its lit tone). The two flanks' exact
/// colours differ by far more than that, so the sphere's one colour of
/// before fails.
#[test]
fn sun_on_a_600_m_sphere_follows_each_point() {
    let sun_degrees = 4.0;
    let mut flanks = Vec::new();
    for elevation in [-45.0, 45.0] {
        let normal = normal_at(elevation, true);
        let mut colours = Vec::new();
        for (shading, lighting, bound) in [
            ("phong", "forward", 1e-3),
            ("phong", "deferred", 1e-3),
            // Lit per vertex, the colour interpolated across each
            // 1.8 m triangle.
            ("gouraud", "forward", 1e-3),
            ("toon", "forward", 1e-3),
        ] {
            let scene = sphere_scene(sun_degrees, normal, shading, lighting, false);
            let run = common::render(&scene, true);
            if lighting == "deferred" {
                assert!(run.passes.contains(&"lighting"), "{:?}", run.passes);
            }
            let hdr = run.hdr.unwrap();
            let (x, y) = PROBE;
            let (_, point, n) = hit(&scene, x, y);
            let sun = sun_colour(&scene, point);
            let s = scene.sky.as_ref().unwrap().sun.direction;
            let factor = if shading == "toon" {
                assert!(n.dot(s) > 0.5, "the probe is in toon's lit tone");
                KD
            } else {
                KD * n.dot(s)
            };
            let want = sun * factor;
            let got = surface_radiance(&scene, common::hdr_pixel(&hdr, x, y), x, y);
            let e = relative_error(got, want);
            println!(
                "flank {elevation}°, {shading} {lighting}: {got} against {want}: {e:.2e} \
                 (altitude {:.0} m)",
                point.y
            );
            assert!(
                e <= bound,
                "{shading} {lighting}, flank {elevation}°: {e:e}"
            );
            colours.push(sun);
        }
        // The CPU reference renderer: the same sun at the pixel's point.
        let scene = sphere_scene(sun_degrees, normal, "phong", "forward", false);
        let cpu = render_on_cpu_with(&scene, Transport::Single).unwrap();
        let (x, y) = PROBE;
        let (_, point, n) = hit(&scene, x, y);
        let s = scene.sky.as_ref().unwrap().sun.direction;
        let want = sun_colour(&scene, point) * KD * n.dot(s);
        let got = surface_radiance(&scene, common::hdr_pixel(&cpu, x, y), x, y);
        let e = relative_error(got, want);
        println!("flank {elevation}°, CPU reference: {e:.2e}");
        assert!(e <= 1e-6, "CPU reference, flank {elevation}°: {e:e}");
        flanks.push(colours[0]);
    }
    // What one colour per object would miss: the flanks' colours differ.
    let difference = relative_error(flanks[0], flanks[1]);
    println!("the two flanks' sun colours differ by {difference:.2e}");
    assert!(difference > 0.05, "{difference:e}");
}

/// The local zenith at `point` (world space) and the sun's irradiance
/// through the air on a horizontal surface there, in f64.
fn sun_on_horizontal(atmosphere: &Atmosphere, sun: &Sun, point: DVec3) -> (DVec3, DVec3) {
    let rel = point - atmosphere.center;
    let up = rel.normalize();
    let transmittance = quadrature::sun_transmittance(atmosphere, rel, sun.direction);
    (
        up,
        sun.irradiance * transmittance * up.dot(sun.direction).max(0.0),
    )
}

/// The tilted-surface model of the sky light (`object_air.glsl`), in f64,
/// with `horizontal` the sky's irradiance E_h on a horizontal surface at
/// `point` (world space), β the surface's tilt from level:
/// E_h (1 + cos β)/2 (1 + f sin³(β/2)) + albedo (E_sun,h + E_h)
/// (1 − cos β)/2, f = √(E_sun,h / (E_sun,h + E_h)).
fn sky_model(
    atmosphere: &Atmosphere,
    sun: &Sun,
    point: DVec3,
    n: DVec3,
    horizontal: DVec3,
) -> DVec3 {
    let (up, sun_horizontal) = sun_on_horizontal(atmosphere, sun, point);
    let global = sun_horizontal + horizontal;
    let cos_tilt = n.dot(up);
    let tilt = cos_tilt.clamp(-1.0, 1.0).acos();
    let f = DVec3::new(
        (sun_horizontal.x / global.x).sqrt(),
        (sun_horizontal.y / global.y).sqrt(),
        (sun_horizontal.z / global.z).sqrt(),
    );
    horizontal * (0.5 + 0.5 * cos_tilt) * (DVec3::ONE + f * (tilt / 2.0).sin().powi(3))
        + atmosphere.ground_albedo * global * (0.5 - 0.5 * cos_tilt)
}

/// The plain isotropic model, without the horizon's band, for comparison.
fn isotropic_model(
    atmosphere: &Atmosphere,
    sun: &Sun,
    point: DVec3,
    n: DVec3,
    horizontal: DVec3,
) -> DVec3 {
    let (up, sun_horizontal) = sun_on_horizontal(atmosphere, sun, point);
    let c = n.dot(up);
    horizontal * (0.5 + 0.5 * c)
        + atmosphere.ground_albedo * (sun_horizontal + horizontal) * (0.5 - 0.5 * c)
}

/// Full transport's irradiance from the sky on a surface of normal `n` at
/// `point` (world space), with its standard error.
fn transport_irradiance(
    atmosphere: &Atmosphere,
    sun: &Sun,
    point: DVec3,
    n: DVec3,
    paths: u32,
    seed: u64,
) -> (DVec3, DVec3) {
    let settings = TransportSettings {
        paths,
        seed,
        max_order: UNLIMITED,
    };
    sky_irradiance(atmosphere, sun, point - atmosphere.center, n, settings)
}

/// The shadowed side under a sun 30° up, forward and deferred, Phong,
/// Gouraud and toon: lit by the sky and the ground alone (bluish where it
/// faces up, 45° up away from the sun; facing level or down the sunlit
/// ground's reflection outweighs the sky), and within 8 % of the model
/// evaluated with full transport's horizontal irradiance (the test's:
/// Monte Carlo at under 0.5 % standard error). The GPU's horizontal
/// irradiance comes from the sky-irradiance table, which integrates
/// Hillaire's approximation of the higher orders (a blue sky a few per
/// cent dark, docs/atmosphere.md): measured here 3.2 / 4.7 / 6.4 % below
/// full transport (R / G / B) where the sky dominates.
/// The CPU reference renderer draws the same model from its own
/// irradiance. With single scattering the shadowed side stays black.
#[test]
fn sky_lights_the_shadowed_side_bluish() {
    let sun_degrees = 30.0;
    for elevation in [-45.0, 0.0, 45.0] {
        let normal = normal_at(elevation, false);
        let probe_scene = sphere_scene(sun_degrees, normal, "phong", "forward", true);
        let sky = probe_scene.sky.clone().unwrap();
        let (x, y) = PROBE;
        let (_, point, n) = hit(&probe_scene, x, y);
        assert!(n.dot(sky.sun.direction) < 0.0, "the probe is in shadow");
        let (horizontal, error) = transport_irradiance(
            &sky.atmosphere,
            &sky.sun,
            point,
            (point - sky.atmosphere.center).normalize(),
            1 << 17,
            7,
        );
        assert!(
            (error / horizontal).max_element() < 5e-3,
            "{error} of {horizontal}"
        );
        let want = KD * sky_model(&sky.atmosphere, &sky.sun, point, n, horizontal);
        // Facing up, the sky's blue dominates; facing level or down, the
        // sunlit ground's reflection (albedo 0.3) outweighs it.
        let bluish = elevation > 0.0;
        assert!(want.min_element() > 0.0, "{want}");
        if bluish {
            assert!(want.z > want.x, "the sky's light is blue: {want}");
        }
        for (shading, lighting) in [
            ("phong", "forward"),
            ("phong", "deferred"),
            ("gouraud", "forward"),
            ("toon", "forward"),
        ] {
            let scene = sphere_scene(sun_degrees, normal, shading, lighting, true);
            let hdr = common::render(&scene, true).hdr.unwrap();
            let got = surface_radiance(&scene, common::hdr_pixel(&hdr, x, y), x, y);
            let e = relative_error(got, want);
            println!(
                "shadowed side {elevation}°, {shading} {lighting}: {got} against {want}: {e:.2e}"
            );
            assert!(got.min_element() > 0.0, "{shading} {lighting}: {got}");
            if bluish {
                assert!(got.z > 1.5 * got.x, "{shading} {lighting}: {got}");
            }
            assert!(e <= 0.08, "{shading} {lighting}, {elevation}°: {e:e}");
        }
        // The CPU reference: the same model from its own irradiance.
        let cpu = render_on_cpu_with(&probe_scene, Transport::Full { paths: 256 }).unwrap();
        let got = surface_radiance(&probe_scene, common::hdr_pixel(&cpu, x, y), x, y);
        let e = relative_error(got, want);
        println!("shadowed side {elevation}°, CPU reference: {got}: {e:.2e}");
        assert!(e <= 0.02, "CPU reference, {elevation}°: {e:e}");
        // Single scattering: no sky light, black in the sun's shadow.
        let single = sphere_scene(sun_degrees, normal, "phong", "forward", false);
        let hdr = common::render(&single, true).hdr.unwrap();
        let got = surface_radiance(&single, common::hdr_pixel(&hdr, x, y), x, y);
        assert!(got.abs().max_element() < 1e-3 * want.max_element(), "{got}");
    }
}

/// The tilted-surface model against full transport's irradiance over the
/// tilted hemisphere itself, on the ground and 600 m up, for normals from
/// straight up to straight down, towards the sun, away from it and across,
/// under suns 60°, 30°, 10° and 2° up. Prints a table; the figures are in
/// docs/atmosphere.md. Ignored: about a minute in release.
#[test]
#[ignore]
fn sky_light_model_against_full_transport() {
    let scene = sphere_scene(30.0, DVec3::Y, "phong", "forward", true);
    let base = scene.sky.clone().unwrap();
    let paths = 1 << 15;
    let mut worst = 0.0f64;
    let mut worst_plain = 0.0f64;
    let mut errors = Vec::new();
    let mut errors_plain = Vec::new();
    for sun_degrees in [60.0, 30.0, 10.0, 2.0] {
        let mut sun = base.sun.clone();
        sun.direction = sun_at(sun_degrees);
        for altitude in [1.0, 600.0] {
            let point = DVec3::new(0.0, altitude, 0.0);
            let up = DVec3::Y;
            let (horizontal, _) = transport_irradiance(&base.atmosphere, &sun, point, up, paths, 1);
            for (label, n) in [
                ("up", up),
                ("45° up, to the sun", normal_at(45.0, true)),
                ("45° up, away", normal_at(45.0, false)),
                ("level, to the sun", normal_at(0.0, true)),
                ("level, away", normal_at(0.0, false)),
                ("level, across", DVec3::Z),
                ("45° down, away", normal_at(-45.0, false)),
                ("down", -up),
            ] {
                let model = sky_model(&base.atmosphere, &sun, point, n, horizontal);
                let plain = isotropic_model(&base.atmosphere, &sun, point, n, horizontal);
                let (exact, error) =
                    transport_irradiance(&base.atmosphere, &sun, point, n, paths, 2);
                let e = (model - exact) / exact;
                let e_plain = (plain - exact) / exact;
                let e_max = e.abs().max_element();
                worst = worst.max(e_max);
                worst_plain = worst_plain.max(e_plain.abs().max_element());
                errors.push(e_max);
                errors_plain.push(e_plain.abs().max_element());
                println!(
                    "sun {sun_degrees:>2}°, {altitude:>3} m, {label:<20}: model {model:.4} \
                     exact {exact:.4} (± {:.1e}): {:+.3} / {:+.3} / {:+.3} \
                     (isotropic: {:+.3} / {:+.3} / {:+.3})",
                    (error / exact).max_element(),
                    e.x,
                    e.y,
                    e.z,
                    e_plain.x,
                    e_plain.y,
                    e_plain.z
                );
            }
        }
    }
    errors.sort_by(f64::total_cmp);
    errors_plain.sort_by(f64::total_cmp);
    println!(
        "median {:.3}, worst {worst:.3} (relative, worst channel); isotropic alone: \
         median {:.3}, worst {worst_plain:.3}",
        errors[errors.len() / 2],
        errors_plain[errors_plain.len() / 2]
    );
}
