//! The model and reference against closed forms, and the optical-depth
//! table against the reference.

use super::quadrature::{densities_between, densities_to_top, radiance};
use super::*;

fn earth() -> Atmosphere {
    Atmosphere::earth()
}

fn sun(direction: DVec3) -> Sun {
    Sun {
        direction: direction.normalize(),
        irradiance: DVec3::ONE,
        angular_radius: 0.004675,
        disc: true,
    }
}

#[test]
fn ray_sphere_roots_lie_on_the_sphere_at_planet_scale() {
    let radius = 6_360_000.0;
    // From 1 m above the ground to 1e8 m away, grazing and steep.
    for (altitude, mu) in [
        (1.0, -0.001),
        (1.0, -6e-4),
        (10.0, -0.5),
        (60_000.0, -0.2),
        (1e8, -0.9999),
        (1e8, -0.99995),
    ] {
        let origin = DVec3::new(0.0, radius + altitude, 0.0);
        let direction = DVec3::new((1.0f64 - mu * mu).sqrt(), mu, 0.0);
        let (t0, t1) = ray_sphere(origin, direction, radius).expect("the ray hits the sphere");
        for t in [t0, t1] {
            let miss = (origin + t * direction).length() - radius;
            // Rounding of the point itself is ~1e-9 relative to 6.4e6 m.
            assert!(
                miss.abs() < 1e-3,
                "altitude {altitude}, mu {mu}: root {t} is {miss} m off the sphere"
            );
        }
    }
    // Horizontal at 1 m: misses the planet.
    let origin = DVec3::new(0.0, radius + 1.0, 0.0);
    assert!(ray_sphere(origin, DVec3::X, radius).is_none());
}

#[test]
fn phase_functions_integrate_to_one_over_the_sphere() {
    for phase in [
        &(|mu: f64| rayleigh_phase(mu)) as &dyn Fn(f64) -> f64,
        &|mu| cornette_shanks_phase(mu, 0.8),
        &|mu| cornette_shanks_phase(mu, -0.3),
    ] {
        // 2π ∫ p(μ) dμ by the midpoint rule on a fine grid.
        let n = 200_000;
        let total: f64 = (0..n)
            .map(|i| phase(-1.0 + (i as f64 + 0.5) * 2.0 / n as f64) * 2.0 / n as f64)
            .sum::<f64>()
            * std::f64::consts::TAU;
        assert!((total - 1.0).abs() < 1e-6, "integral {total}");
    }
}

#[test]
fn vertical_optical_depth_matches_the_closed_form() {
    let a = earth();
    for h in [0.0, 1.0, 1000.0, 30_000.0, 59_000.0] {
        let p = DVec3::new(0.0, a.bottom_radius + h, 0.0);
        let d = densities_to_top(&a, p, DVec3::Y).unwrap();
        let top = a.top_radius - a.bottom_radius;
        for (got, scale) in [
            (d.rayleigh, a.rayleigh_scale_height),
            (d.mie, a.mie_scale_height),
        ] {
            let exact = scale * ((-h / scale).exp() - (-top / scale).exp());
            assert!(
                ((got - exact) / exact).abs() < 1e-7,
                "h {h}: {got} against {exact}"
            );
        }
        // Ozone: the tent's area above h, by hand.
        let [s, m, e] = a.ozone_layer;
        let area_above = |h: f64| {
            if h <= s {
                (e - s) / 2.0
            } else if h <= m {
                (e - s) / 2.0 - (h - s) * (h - s) / (2.0 * (m - s))
            } else if h <= e {
                (e - h) * (e - h) / (2.0 * (e - m))
            } else {
                0.0
            }
        };
        assert!(
            (d.ozone - area_above(h)).abs() < 1e-6 * 15_000.0,
            "ozone at {h}"
        );
    }
}

#[test]
fn grazing_optical_depth_matches_the_chapman_limit() {
    // A horizontal ray from the ground to an atmosphere top so high the
    // truncation is below 1e-10: H·Ch(x, 90°) with Ch(x, 90°) = x·eˣ·K₁(x)
    // = √(πx/2)·(1 + 3/(8x) − 15/(128x²) + O(x⁻³)), x = R/H.
    let mut a = earth();
    a.top_radius = a.bottom_radius + 400_000.0;
    let p = DVec3::new(0.0, a.bottom_radius, 0.0);
    let end = p + DVec3::X * ray_sphere(p, DVec3::X, a.top_radius).unwrap().1;
    let d = densities_between(&a, p, end);
    for (got, scale) in [
        (d.rayleigh, a.rayleigh_scale_height),
        (d.mie, a.mie_scale_height),
    ] {
        let x = a.bottom_radius / scale;
        let chapman = (std::f64::consts::PI * x / 2.0).sqrt()
            * (1.0 + 3.0 / (8.0 * x) - 15.0 / (128.0 * x * x));
        let exact = scale * chapman;
        assert!(
            ((got - exact) / exact).abs() < 1e-6,
            "scale height {scale}: {got} against {exact}"
        );
    }
}

#[test]
fn the_sky_is_blue_at_noon_and_reddens_towards_the_sun_at_sunset() {
    let a = earth();
    let eye = DVec3::new(0.0, a.bottom_radius + 1.0, 0.0);
    // Noon, looking 30° up to the north.
    let up30 = DVec3::new(0.0, 0.5, 0.866).normalize();
    let noon = radiance(&a, &sun(DVec3::Y), eye, up30);
    assert!(noon.z > noon.y && noon.y > noon.x, "noon sky {noon}");
    // Sunset: sun 1° above the western horizon, look 2° above it towards
    // the sun and away from it.
    let s = DVec3::new(-1.0, 0.01745, 0.0);
    let towards = radiance(&a, &sun(s), eye, DVec3::new(-1.0, 0.035, 0.0).normalize());
    let away = radiance(&a, &sun(s), eye, DVec3::new(1.0, 0.035, 0.0).normalize());
    let zenith = radiance(&a, &sun(s), eye, DVec3::Y);
    let red_over_blue = |c: DVec3| c.x / c.z;
    assert!(
        red_over_blue(towards) > 2.0 * red_over_blue(noon) && red_over_blue(towards) > 1.0,
        "towards the setting sun {towards}, noon {noon}"
    );
    // Redder low towards the sun than overhead, and brighter than the
    // opposite horizon (the Mie forward peak).
    assert!(
        red_over_blue(towards) > 2.0 * red_over_blue(zenith),
        "towards {towards} zenith {zenith}"
    );
    assert!(towards.x > away.x, "towards {towards} away {away}");
}

#[test]
fn radiance_is_finite_and_non_negative_in_extreme_cases() {
    let a = earth();
    let eyes = [
        DVec3::new(0.0, a.bottom_radius + 1.0, 0.0),
        DVec3::new(0.0, a.top_radius, 0.0),
        DVec3::new(0.0, a.bottom_radius + 1e8, 0.0),
    ];
    let suns = [DVec3::Y, DVec3::X, DVec3::new(1.0, -0.17, 0.0)];
    let views = [DVec3::Y, DVec3::X, DVec3::new(1.0, -0.01, 0.0), -DVec3::Y];
    for eye in eyes {
        for s in suns {
            for v in views {
                let l = radiance(&a, &sun(s), eye, v.normalize());
                assert!(
                    l.is_finite() && l.min_element() >= 0.0,
                    "eye {eye} sun {s} view {v}: {l}"
                );
            }
        }
    }
    // Sun 10° below the horizon: the zenith sky is much darker than at
    // sunset but only single scattering from high up remains.
    let eye = eyes[0];
    let night = radiance(&a, &sun(DVec3::new(1.0, -0.176, 0.0)), eye, DVec3::Y);
    let sunset = radiance(&a, &sun(DVec3::new(1.0, 0.0, 0.0)), eye, DVec3::Y);
    assert!(
        night.max_element() < 0.05 * sunset.max_element(),
        "{night} vs {sunset}"
    );
}

/// Rays (altitude, cosine) that miss the ground: altitudes concentrated
/// near the ground and the top, cosines from the horizon up, denser near
/// it, on a grid offset from any texel centre.
fn rays_above_ground(a: &Atmosphere, altitudes: usize, directions: usize) -> Vec<(f64, f64)> {
    let top = a.top_radius - a.bottom_radius;
    let mut rays = Vec::new();
    for i in 0..altitudes {
        let x = (i as f64 + 0.37) / altitudes as f64;
        let alt = top * (0.5 * std::f64::consts::PI * x).sin().powi(2) * 0.999_9;
        let r = a.bottom_radius + alt;
        let horizon = -(alt * (2.0 * a.bottom_radius + alt)).sqrt() / r;
        for j in 0..directions {
            let s = (j as f64 + 0.41) / directions as f64;
            rays.push((alt, horizon + (1.0 - horizon) * s * s));
        }
    }
    rays
}

/// The largest transmittance error of what the pass looks up towards the
/// sun (`table`, ozone as `ozone` says) over rays that miss the ground.
fn max_transmittance_error(a: &Atmosphere, table: &OpticalDepthTable, ozone: OzoneDepth) -> f64 {
    let mut worst = 0f64;
    for (alt, mu) in rays_above_ground(a, 61, 149) {
        let p = DVec3::new(0.0, a.bottom_radius + alt, 0.0);
        let dir = DVec3::new((1.0 - mu * mu).sqrt(), mu, 0.0);
        let Some(exact) = densities_to_top(a, p, dir) else {
            continue;
        };
        let got = table.densities(a, alt, mu, ozone);
        let e = (a.transmittance(exact) - a.transmittance(got))
            .abs()
            .max_element();
        worst = worst.max(e);
    }
    worst
}

/// The largest transmittance error of `table` over the rays that miss the
/// ground, with ozone and without (its absorption zeroed, so only the
/// Rayleigh and Mie channels count).
fn table_errors(a: &Atmosphere, table: &OpticalDepthTable, ozone: OzoneDepth) -> (f64, f64) {
    let mut no_ozone = a.clone();
    no_ozone.ozone_absorption = DVec3::ZERO;
    (
        max_transmittance_error(a, table, ozone),
        max_transmittance_error(&no_ozone, table, ozone),
    )
}

#[test]
fn a_256x64_horizon_table_meets_its_transmittance_bounds() {
    let a = earth();
    let table = OpticalDepthTable::bake(&a, 256, 64, TableMapping::Horizon);
    let (with_ozone, without) = table_errors(&a, &table, OzoneDepth::Exact);
    println!(
        "256x64 horizon table: max transmittance error {with_ozone:.3e} (without ozone \
         {without:.3e}), bake {:.3} s ({} KiB)",
        table.bake_seconds,
        table.bytes() / 1024
    );
    // The goal: 1e-4 over every ray that misses the ground (measured
    // 7.0e-5 with and without ozone; the worst rays leave the ground
    // steeply, where the logarithm's curvature across a column shows).
    assert!(without <= 1e-4, "without ozone {without:e}");
    assert!(with_ozone <= 1e-4, "with ozone {with_ozone:e}");
    // The bake time is printed, not asserted: a unit test's wall clock
    // on a shared host measures the host (it read 8.4 s under load); the
    // bake's cost is in the sweep's `od_table_bake_ms`.
    // Ozone from the table's channel instead: the tent's kinks cost more
    // than ten times the goal (measured 2.6e-3), which is why the pass
    // integrates it in closed form by default.
    let (from_table, _) = table_errors(&a, &table, OzoneDepth::Table);
    println!("256x64 horizon table, ozone from the table: {from_table:.3e}");
    assert!(
        from_table > 5.0 * with_ozone && from_table < 5e-3,
        "{from_table:e}"
    );
    // The seed's linear mapping at the same size is far worse: the mapping
    // is what buys the accuracy.
    let seed = OpticalDepthTable::bake(&a, 256, 64, TableMapping::Linear);
    let (seed_with, seed_without) = table_errors(&a, &seed, OzoneDepth::Exact);
    println!("256x64 seed table: {seed_with:.3e} (without ozone {seed_without:.3e})");
    assert!(seed_without > 10.0 * without);
}

/// The closed-form ozone integral against the adaptive reference, on
/// Earth's layer, one cut by the top of the atmosphere, a thin one and a
/// small planet's: relative to the largest value, within 1e-6 (Gauss's
/// error on a 900 km chord is about 1e-7).
#[test]
fn ozone_in_closed_form_matches_the_reference() {
    let earth = earth();
    let mut cut = earth.clone();
    cut.ozone_layer = [30_000.0, 50_000.0, 90_000.0];
    let mut thin = earth.clone();
    thin.ozone_layer = [0.0, 100.0, 300.0];
    let mut small = earth.clone();
    small.bottom_radius = 1.0e6;
    small.top_radius = 1.1e6;
    small.center = DVec3::new(0.0, -1.0e6, 0.0);
    small.ozone_layer = [5_000.0, 40_000.0, 60_000.0];
    for (name, a) in [
        ("earth", earth),
        ("cut", cut),
        ("thin", thin),
        ("small", small),
    ] {
        let (mut worst, mut largest) = (0f64, 0f64);
        for (alt, mu) in rays_above_ground(&a, 37, 53) {
            let p = DVec3::new(0.0, a.bottom_radius + alt, 0.0);
            let dir = DVec3::new((1.0 - mu * mu).sqrt(), mu, 0.0);
            let Some(exact) = densities_to_top(&a, p, dir) else {
                continue;
            };
            let got = crate::atmosphere::ozone::ozone_to_top(&a, alt, mu);
            worst = worst.max((got - exact.ozone).abs());
            largest = largest.max(exact.ozone);
        }
        println!("{name}: ozone max error {worst:.3e} of {largest:.3e}");
        assert!(
            largest > 0.0 && worst <= 1e-6 * largest,
            "{name}: {worst:e} of {largest:e}"
        );
    }
}

/// Tall atmospheres: the cut of [`Atmosphere::effective_top_radius`] and
/// the reference's own cut ([`super::quadrature::pieces`]).
mod tall {
    use super::*;
    use crate::atmosphere::quadrature::{pieces, REFERENCE_CUT};

    fn tall(top: f64) -> Atmosphere {
        Atmosphere {
            top_radius: top,
            ..earth()
        }
    }

    /// ∫ e^(−h/H) ds along the horizontal ray from radius `r`, outwards,
    /// by the composite Simpson rule on a grid far finer than the
    /// Gaussian of width √(rH) it integrates (brute force, no adaptivity).
    fn horizontal_column(bottom: f64, r: f64, scale_height: f64) -> f64 {
        let width = (r * scale_height).sqrt().max(scale_height);
        let length = 60.0 * width;
        let n = 200_000;
        let h = length / n as f64;
        let f = |s: f64| (-((r * r + s * s).sqrt() - bottom) / scale_height).exp();
        (0..n)
            .map(|i| {
                let (a, b) = (i as f64 * h, (i + 1) as f64 * h);
                h / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b))
            })
            .sum()
    }

    #[test]
    fn column_above_bounds_the_horizontal_column_within_a_factor_of_two() {
        for (bottom, h, scale_height, top) in [
            (6.36e6, 0.0, 8000.0, 6.42e6),
            (6.36e6, 150_000.0, 8000.0, 1e9),
            (6.36e6, 40_000.0, 1200.0, 1e9),
            (1e5, 2_000.0, 500.0, 1e8),
            (1e6, 1e6, 1e5, 1e9),
        ] {
            let exact = horizontal_column(bottom, bottom + h, scale_height);
            let bound = column_above(h, scale_height, bottom + h).max(0.0);
            let loose = column_above(h, scale_height, top);
            println!("R {bottom:e} h {h:e} H {scale_height:e}: {exact:.4e} <= {bound:.4e}");
            assert!(
                exact <= bound && bound <= loose,
                "{exact:e} {bound:e} {loose:e}"
            );
            // Not much of a bound if it were far above: about √2 for a
            // planet much larger than H (Chapman's √(π r H / 2)).
            assert!(bound <= 2.0 * exact, "{exact:e} {bound:e}");
        }
    }

    #[test]
    fn earth_keeps_its_top_and_tall_atmospheres_are_cut_where_the_air_ends() {
        assert_eq!(earth().effective_top_radius(), earth().top_radius);
        for top in [3e7, 1e8, 3e8, 1e9] {
            let a = tall(top);
            let cut = a.effective_top_radius() - a.bottom_radius;
            println!("top {top:e}: cut at {:.1} km", cut / 1000.0);
            assert!((100e3..200e3).contains(&cut), "{cut}");
            // What is left above the cut, on the horizontal ray from it
            // (the largest column a ray above it can meet), is below the
            // tolerance of the vertical column, for both exponentials.
            for scale_height in [a.rayleigh_scale_height, a.mie_scale_height] {
                let left = horizontal_column(a.bottom_radius, a.bottom_radius + cut, scale_height);
                assert!(
                    2.0 * left <= CUT_TOLERANCE * scale_height,
                    "H {scale_height}: {left:e}"
                );
            }
        }
        // An absorbing ozone layer is never cut; large scale heights push
        // the cut up to the top; a small planet keeps its cut above
        // MIN_CUT_THICKNESS.
        let mut high_ozone = tall(1e9);
        high_ozone.ozone_layer = [1e6, 2e6, 3e6];
        assert!(high_ozone.effective_top_radius() >= high_ozone.bottom_radius + 3e6);
        let mut thick = tall(1e8);
        thick.rayleigh_scale_height = 1e7;
        assert_eq!(thick.effective_top_radius(), 1e8);
        let mut tiny = tall(1e9);
        tiny.bottom_radius = 1e8;
        tiny.rayleigh_scale_height = 1.0;
        tiny.mie_scale_height = 1.0;
        tiny.ozone_absorption = DVec3::ZERO;
        assert_eq!(
            tiny.effective_top_radius(),
            tiny.bottom_radius + tiny.bottom_radius * MIN_CUT_THICKNESS
        );
    }

    /// The reference on a 1e9 m atmosphere: the vertical optical depth
    /// against its closed form (the top's term e^(−(R_top − R)/H) is 0),
    /// and a ray from far out in space that grazes the air 5 km above the
    /// ground against brute force. Before the reference cut its own
    /// initial grid (64 panels of 3e7 m) stepped over the air.
    #[test]
    fn the_reference_stays_exact_in_a_tall_atmosphere() {
        let a = tall(1e9);
        for h in [0.0, 1000.0, 30_000.0, 100_000.0] {
            let p = DVec3::new(0.0, a.bottom_radius + h, 0.0);
            let d = densities_to_top(&a, p, DVec3::Y).unwrap();
            for (got, scale) in [
                (d.rayleigh, a.rayleigh_scale_height),
                (d.mie, a.mie_scale_height),
            ] {
                let exact = scale * (-h / scale).exp();
                assert!(
                    (got - exact).abs() <= 1e-7 * exact + REFERENCE_CUT * scale,
                    "h {h}: {got} against {exact}"
                );
            }
        }
        // From 9e8 m along the x axis, aimed to pass 5 km above the ground.
        let low = a.bottom_radius + 5000.0;
        let start = DVec3::new(-9e8, low, 0.0);
        let end = DVec3::new(9e8, low, 0.0);
        let got = densities_between(&a, start, end);
        // Along y = low the closest point is at x = 0; both halves are the
        // horizontal column from there.
        for (value, scale) in [
            (got.rayleigh, a.rayleigh_scale_height),
            (got.mie, a.mie_scale_height),
        ] {
            let exact = 2.0 * horizontal_column(a.bottom_radius, low, scale);
            println!("grazing from space, H {scale}: {value:.6e} against {exact:.6e}");
            assert!(
                ((value - exact) / exact).abs() < 1e-6,
                "H {scale}: {value:e} against {exact:e}"
            );
        }
        // The cut integrates only the stretch near the planet; a Mie
        // scale height of 1 m under 100 km Rayleigh is split apart.
        let parts = pieces(&a, start, DVec3::X, 0.0, 1.8e9);
        let covered: f64 = parts.iter().map(|(t0, t1)| t1 - t0).sum();
        assert!(covered < 5e6, "{parts:?}");
        let mut thin_mie = a.clone();
        thin_mie.rayleigh_scale_height = 1e5;
        thin_mie.mie_scale_height = 1.0;
        thin_mie.ozone_absorption = DVec3::ZERO;
        let ground = DVec3::new(0.0, a.bottom_radius, 0.0);
        let parts = pieces(&thin_mie, ground, DVec3::Y, 0.0, 1e9);
        assert!(parts.len() == 2 && parts[0].1 < 100.0, "{parts:?}");
        let d = densities_to_top(&thin_mie, ground, DVec3::Y).unwrap();
        assert!((d.mie - 1.0).abs() < 1e-7, "{}", d.mie);
        assert!((d.rayleigh - 1e5).abs() < 1e-7 * 1e5, "{}", d.rayleigh);
        // Earth's default is integrated in one piece, as before the cut.
        let earth = earth();
        let p = DVec3::new(0.0, earth.bottom_radius, 0.0);
        assert_eq!(pieces(&earth, p, DVec3::X, 0.0, 1e6), vec![(0.0, 1e6)]);
    }

    /// In a tall atmosphere the sky from the ground is the sky of the same
    /// air under a top just below the reference's cut (integrated the old
    /// way, in one piece): the reference's cut changes nothing it can see.
    #[test]
    fn the_reference_radiance_does_not_depend_on_an_empty_top() {
        let high = tall(1e9);
        let low = tall(earth().bottom_radius + 250_000.0);
        let eye = DVec3::new(0.0, high.bottom_radius + 2.0, 0.0);
        let s = sun(DVec3::new(0.3, 0.866, 0.4));
        for view in [
            DVec3::Y,
            DVec3::new(0.0, 0.2, -1.0),
            DVec3::new(1.0, 0.01, 0.0),
            DVec3::new(0.3, -0.2, 1.0),
        ] {
            let view = view.normalize();
            let (a, b) = (
                radiance(&high, &s, eye, view),
                radiance(&low, &s, eye, view),
            );
            assert!(
                (a - b).abs().max_element() <= 1e-6 * b.max_element(),
                "{view}: {a} against {b}"
            );
        }
    }

    /// The optical-depth table of a tall atmosphere, spanning its
    /// effective top, meets the default's 1e-4 transmittance goal over
    /// rays in the air (looked up in the full atmosphere).
    #[test]
    fn a_tall_atmospheres_table_meets_the_transmittance_goal() {
        for top in [3e7, 1e9] {
            let a = tall(top);
            let table = OpticalDepthTable::bake(&a, 256, 64, TableMapping::Horizon);
            let rays = rays_above_ground(&a.effective(), 61, 149);
            let mut worst = 0f64;
            for (alt, mu) in rays {
                let p = DVec3::new(0.0, a.bottom_radius + alt, 0.0);
                let dir = DVec3::new((1.0 - mu * mu).sqrt(), mu, 0.0);
                let Some(exact) = densities_to_top(&a, p, dir) else {
                    continue;
                };
                let got = table.densities(&a, alt, mu, OzoneDepth::Exact);
                let e = (a.transmittance(exact) - a.transmittance(got))
                    .abs()
                    .max_element();
                worst = worst.max(e);
            }
            println!(
                "top {top:e}: table max transmittance error {worst:.3e}, bake {:.3} s",
                table.bake_seconds
            );
            assert!(worst <= 1e-4, "top {top:e}: {worst:e}");
        }
    }
}
