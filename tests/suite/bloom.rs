//! Bloom (`[tone_map] bloom = { ... }`, knob `bloom`): one compute pass
//! between the render pass that draws the HDR image and the one that
//! tone-maps it builds a chain of levels (a quarter-size 4x4 mean of the
//! HDR image, then half-size 13-tap downsamples, 2x2-box upsamples, each level the mean of its own downsample and the
//! level below), and the tone map mixes level 0 in. Without bloom the
//! frame is exactly what it was; with it, the tone map's output matches
//! the same chain computed on the CPU in f64 from the read-back HDR image,
//! the light it shows is the light that came in, and it spreads; bad
//! settings are errors naming the file and the field. Every render is
//! under validation (synchronization included).

use crate::common;

use aerial::render::passes::{bloom, tonemap};
use aerial::render::{FramePlan, Pixels, SceneGeometry};
use aerial::scene::{Bloom, Scene, KNOBS};
use std::path::Path;

/// A small sphere glowing with a constant colour (its ambient term: kd and
/// ks are 0) on black, `width`×`height`, with `tone_map` lines added.
fn glow_scene(width: u32, height: u32, tone_map: &str) -> Scene {
    common::scene(&format!(
        "ambient = [1.0, 1.0, 1.0]\n\
         [output]\nwidth = {width}\nheight = {height}\nhdr_format = \"rgba32f\"\n\
         [tone_map]\n{tone_map}\n\
         [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         [[materials]]\nname = \"glow\"\nka = [40.0, 20.0, 10.0]\nkd = [0.0, 0.0, 0.0]\n\
         ks = [0.0, 0.0, 0.0]\n\
         [[objects]]\nname = \"ball\"\nmaterial = \"glow\"\n\
         shape = {{ type = \"sphere\", radius = 0.15 }}\n"
    ))
}

fn plan_of(scene: &Scene) -> FramePlan {
    FramePlan::new(scene, &SceneGeometry::new(scene).unwrap(), false)
}

#[test]
fn without_bloom_the_frame_is_unchanged() {
    let plain = glow_scene(64, 48, "exposure = 0.05");
    let plan = plan_of(&plain);
    assert!(!plan.has(bloom::PASS), "{:?}", plan.pass_names());
    assert_eq!(plan.render_pass_count(), 1);
    // Bloom asked for and turned off by the knob: the same frame, bit for
    // bit (output and HDR image).
    let mut off = glow_scene(64, 48, "exposure = 0.05\nbloom = {}");
    let knob = KNOBS.iter().find(|k| k.name == "bloom").unwrap();
    (knob.apply)(&mut off, "off").unwrap();
    assert_eq!(plan_of(&off).pass_names(), plan.pass_names());
    let a = common::render(&plain, true);
    let b = common::render(&off, true);
    assert!(!a.passes.contains(&"bloom"), "{:?}", a.passes);
    assert_eq!(a.passes, b.passes);
    assert_eq!(a.output.data, b.output.data);
    assert_eq!(a.hdr.unwrap().data, b.hdr.unwrap().data);
}

#[test]
fn bloom_frames_hold_the_pass_before_the_tone_map() {
    for tone_map in ["bloom = {}", "bloom = {}\nexposure = \"auto\""] {
        let plan = plan_of(&glow_scene(64, 48, tone_map));
        let names = plan.pass_names();
        let at = |name: &str| names.iter().position(|n| *n == name).unwrap();
        assert_eq!(at("bloom") + 1, at(tonemap::PASS.name()), "{names:?}");
        assert!(at("opaque") < at("bloom"), "{names:?}");
        assert_eq!(plan.render_pass_count(), 2, "{names:?}");
    }
    // Both compute passes together, under validation.
    let run = common::render(
        &glow_scene(64, 48, "bloom = { intensity = 0.5 }\nexposure = \"auto\""),
        false,
    );
    assert!(run.passes.contains(&"exposure") && run.passes.contains(&"bloom"));
    common::assert_not_blank(&run.output, 0.01);
    // Operator none keeps the HDR target and the tone map with bloom.
    let plan = plan_of(&glow_scene(64, 48, "operator = \"none\"\nbloom = {}"));
    assert!(plan.has(bloom::PASS), "{:?}", plan.pass_names());
}

#[test]
fn the_chain_is_capped_so_its_smallest_level_is_one_texel() {
    let b = |levels| Bloom {
        levels,
        ..Bloom::default()
    };
    assert_eq!(b(6).chain_levels(1280, 720), 6);
    // 720 >> 10 = 0: eight levels, the smallest 2x1.
    assert_eq!(b(10).chain_levels(1280, 720), 8);
    assert_eq!(bloom::level_size(1280, 720, 7), (2, 1));
    assert_eq!(bloom::level_size(1280, 720, 8).1, 0);
    assert_eq!(b(3).chain_levels(7, 7), 1);
    assert_eq!(b(3).chain_levels(3, 64), 0);
    // A frame too small for one level has no bloom pass.
    let plan = plan_of(&glow_scene(1, 16, "bloom = {}"));
    assert!(!plan.has(bloom::PASS));
}

/// An image of `width`×`height` RGB texels in f64.
#[derive(Clone)]
struct Level {
    width: usize,
    height: usize,
    rgb: Vec<[f64; 3]>,
}

impl Level {
    fn texel(&self, x: i64, y: i64) -> [f64; 3] {
        let x = x.clamp(0, self.width as i64 - 1) as usize;
        let y = y.clamp(0, self.height as i64 - 1) as usize;
        self.rgb[y * self.width + x]
    }

    /// Bilinear at (u, v) in texel units (texel centres at +0.5), edges
    /// clamped: what a clamped bilinear sampler returns.
    fn bilinear(&self, u: f64, v: f64) -> [f64; 3] {
        let (x, y) = (u - 0.5, v - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mut out = [0.0; 3];
        for (dx, dy, w) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let t = self.texel(x0 + dx, y0 + dy);
            for c in 0..3 {
                out[c] += w * t[c];
            }
        }
        out
    }

    /// The 2x2 box whose corner is (cx, cy): texels cx-1, cx by cy-1, cy.
    fn boxed(&self, cx: i64, cy: i64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (x, y) in [(cx - 1, cy - 1), (cx, cy - 1), (cx - 1, cy), (cx, cy)] {
            let t = self.texel(x, y);
            for c in 0..3 {
                out[c] += 0.25 * t[c];
            }
        }
        out
    }

    /// Level 0 from the HDR image: each texel the mean of the four 2x2
    /// boxes (each clamped to [0, 65504]) of the 4x4 texels it covers
    /// (documented in glsl/bloom_down.comp).
    fn down_from_hdr(&self) -> Level {
        let (width, height) = (self.width / 4, self.height / 4);
        let mut rgb = Vec::with_capacity(width * height);
        for y in 0..height as i64 {
            for x in 0..width as i64 {
                let mut sum = [0.0; 3];
                for (ox, oy) in [(-1, -1), (1, -1), (-1, 1), (1, 1)] {
                    let b = self.boxed(4 * x + 2 + ox, 4 * y + 2 + oy);
                    for c in 0..3 {
                        sum[c] += 0.25 * b[c].clamp(0.0, 65504.0);
                    }
                }
                rgb.push(sum);
            }
        }
        Level { width, height, rgb }
    }

    /// The 13-tap downsample (documented in glsl/bloom_down.comp).
    fn down(&self) -> Level {
        let (width, height) = (self.width / 2, self.height / 2);
        let mut rgb = Vec::with_capacity(width * height);
        let taps: [(i64, i64, f64); 13] = [
            (0, 0, 0.125),
            (-1, -1, 0.125),
            (1, -1, 0.125),
            (-1, 1, 0.125),
            (1, 1, 0.125),
            (-2, -2, 0.03125),
            (2, -2, 0.03125),
            (-2, 2, 0.03125),
            (2, 2, 0.03125),
            (0, -2, 0.0625),
            (-2, 0, 0.0625),
            (2, 0, 0.0625),
            (0, 2, 0.0625),
        ];
        for y in 0..height as i64 {
            for x in 0..width as i64 {
                let mut sum = [0.0; 3];
                for (ox, oy, w) in taps {
                    let b = self.boxed(2 * x + 1 + ox, 2 * y + 1 + oy);
                    for c in 0..3 {
                        sum[c] += w * b[c];
                    }
                }
                rgb.push(sum);
            }
        }
        Level { width, height, rgb }
    }

    /// `own_weight` of this level plus the rest of `below` blurred up with
    /// the 2x2 box of width 1: four bilinear taps at (+-1/2, +-1/2)
    /// (glsl/bloom_up.comp).
    fn up(&self, below: &Level, own_weight: f64) -> Level {
        let mut rgb = Vec::with_capacity(self.rgb.len());
        for y in 0..self.height {
            for x in 0..self.width {
                let (u, v) = ((x as f64 + 0.5) * 0.5, (y as f64 + 0.5) * 0.5);
                let mut blur = [0.0; 3];
                for (dx, dy) in [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)] {
                    let t = below.bilinear(u + dx, v + dy);
                    for c in 0..3 {
                        blur[c] += 0.25 * t[c];
                    }
                }
                let own = self.rgb[y * self.width + x];
                rgb.push(std::array::from_fn(|c| {
                    own_weight * own[c] + (1.0 - own_weight) * blur[c]
                }));
            }
        }
        Level {
            width: self.width,
            height: self.height,
            rgb,
        }
    }
}

/// What the tone map shows with intensity 1 for a 2-level chain: level 0
/// (the mean of its downsample and level 1 blurred up) sampled
/// bilinearly at each output pixel, in linear HDR.
fn cpu_bloom(hdr: &Pixels<f32>) -> Level {
    let image = Level {
        width: hdr.width as usize,
        height: hdr.height as usize,
        rgb: hdr
            .data
            .chunks_exact(4)
            .map(|p| std::array::from_fn(|c| f64::from(p[c])))
            .collect(),
    };
    let level0 = image.down_from_hdr();
    let level1 = level0.down();
    let level0 = level0.up(&level1, 0.5);
    let mut rgb = Vec::with_capacity(image.rgb.len());
    for y in 0..image.height {
        for x in 0..image.width {
            rgb.push(level0.bilinear((x as f64 + 0.5) * 0.25, (y as f64 + 0.5) * 0.25));
        }
    }
    Level { rgb, ..image }
}

fn srgb_decode(byte: u8) -> f64 {
    let v = f64::from(byte) / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn srgb_encode(v: f64) -> f64 {
    let v = v.clamp(0.0, 1.0);
    255.0
        * if v <= 0.0031308 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        }
}

/// How the tone map's output with intensity 1 and no curve (the bloom
/// alone, times the exposure) compares with the 2-level chain computed on
/// the CPU from the read-back HDR image.
struct Comparison {
    /// The largest difference in 8-bit sRGB units, and where.
    worst: (f64, u32, u32),
    /// Linear light in the output over light in the exposed HDR image.
    ratio: f64,
    /// Pixels with red in the HDR image, and in the output.
    lit_in: usize,
    lit_out: usize,
}

/// Renders `glow(tone_map)` twice: once to find the CPU bloom's peak, then
/// exposed so that the peak shows as 0.9 (nothing clamps), and compares.
fn compare_with_cpu(glow: impl Fn(&str) -> Scene) -> Comparison {
    let tone_map = |exposure: f64| {
        format!(
            "operator = \"none\"\nexposure = {exposure}\n\
             bloom = {{ intensity = 1.0, levels = 2 }}"
        )
    };
    // The HDR image does not depend on the exposure.
    let probe = common::render(&glow(&tone_map(1.0)), true);
    let peak = cpu_bloom(&probe.hdr.unwrap())
        .rgb
        .iter()
        .flatten()
        .fold(0.0f64, |a, &b| a.max(b));
    assert!(peak > 0.5, "the sphere barely glows: {peak}");
    let exposure = 0.9 / peak;
    let run = common::render(&glow(&tone_map(exposure)), true);
    let hdr = run.hdr.unwrap();
    let expected = cpu_bloom(&hdr);
    let (width, height) = (hdr.width, hdr.height);
    let mut c = Comparison {
        worst: (0.0, 0, 0),
        ratio: 0.0,
        lit_in: 0,
        lit_out: 0,
    };
    let (mut light_in, mut light_out) = (0.0f64, 0.0f64);
    for y in 0..height {
        for x in 0..width {
            let i = (y * width + x) as usize;
            let out = common::pixel(&run.output, x, y);
            for (ch, &byte) in out.iter().take(3).enumerate() {
                let want = srgb_encode(expected.rgb[i][ch] * exposure);
                let diff = (f64::from(byte) - want).abs();
                if diff > c.worst.0 {
                    c.worst = (diff, x, y);
                }
                light_in += f64::from(hdr.data[i * 4 + ch]) * exposure;
                light_out += srgb_decode(byte);
            }
            c.lit_in += usize::from(hdr.data[i * 4] > 0.0);
            c.lit_out += usize::from(out[0] > 0);
        }
    }
    c.ratio = light_out / light_in;
    c
}

/// The output matches the chain computed on the CPU (within 1.5/255 in
/// sRGB on every pixel: the chain is stored in half floats, relative
/// error 2^-11 per step, and the output is rounded to 8 bits), carries the
/// light that came in (within 2 %: the filters are normalized, and what
/// the 8-bit output rounds away in the faint tail is below that;
/// measured: 0.50/255 at worst, ratio 0.9995) and
/// spreads it beyond the glowing sphere.
#[test]
fn bloom_matches_the_cpu_chain_and_keeps_the_light() {
    let c = compare_with_cpu(|tone_map| glow_scene(128, 96, tone_map));
    assert!(
        c.worst.0 <= 1.5,
        "output differs from the CPU chain by {:.2}/255 at ({}, {})",
        c.worst.0,
        c.worst.1,
        c.worst.2
    );
    assert!(
        (c.ratio - 1.0).abs() < 0.02,
        "light out / light in = {:.4}",
        c.ratio
    );
    assert!(
        c.lit_out > 4 * c.lit_in,
        "the light did not spread: {} pixels lit, {} glowing",
        c.lit_out,
        c.lit_in
    );
}

/// HDR values above the largest half float are read as 65504: a sphere
/// whose ambient term is 1e12 (1e6 times 1e6, finite in the rgba32f
/// target) blooms like the CPU chain whose 2x2 boxes are clamped (the 8-bit
/// output would saturate around the sphere if 1e12 reached the chain).
#[test]
fn huge_hdr_values_are_clamped_before_the_chain() {
    let c = compare_with_cpu(|tone_map| {
        common::scene(&format!(
            "ambient = [1000000.0, 1000000.0, 1000000.0]\n\
             [output]\nwidth = 64\nheight = 48\nhdr_format = \"rgba32f\"\n\
             [tone_map]\n{tone_map}\n\
             [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             [[materials]]\nname = \"hot\"\nka = [1000000.0, 1000000.0, 1000000.0]\n\
             kd = [0.0, 0.0, 0.0]\nks = [0.0, 0.0, 0.0]\n\
             [[objects]]\nname = \"ball\"\nmaterial = \"hot\"\n\
             shape = {{ type = \"sphere\", radius = 0.3 }}\n"
        ))
    });
    assert!(
        c.worst.0 <= 1.5,
        "output differs from the CPU chain of the clamped image by {:.2}/255 at ({}, {})",
        c.worst.0,
        c.worst.1,
        c.worst.2
    );
    assert!(
        c.lit_out > 2 * c.lit_in,
        "{} lit, {} glowing",
        c.lit_out,
        c.lit_in
    );
}

#[test]
fn bad_bloom_settings_name_the_file_the_field_and_the_reason() {
    for (value, field, reason) in [
        (
            "{ intensity = 0.0 }",
            "tone_map.bloom.intensity",
            "greater than 0",
        ),
        (
            "{ intensity = 1.5 }",
            "tone_map.bloom.intensity",
            "at most 1",
        ),
        ("{ intensity = nan }", "tone_map.bloom.intensity", "finite"),
        ("{ levels = 0 }", "tone_map.bloom.levels", "1..=10"),
        ("{ levels = 11 }", "tone_map.bloom.levels", "1..=10"),
        (
            "{ radius = 0.0 }",
            "tone_map.bloom.radius",
            "greater than 0",
        ),
        ("{ threshold = 1.0 }", "threshold", "unknown field"),
    ] {
        let toml = format!(
            "[tone_map]\nbloom = {value}\n\
             [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n"
        );
        let err = Scene::from_toml(&toml, "bad_bloom.toml", Path::new("."))
            .err()
            .unwrap_or_else(|| panic!("bloom = {value} loaded"))
            .to_string();
        for part in ["bad_bloom.toml", field, reason] {
            assert!(
                err.contains(part),
                "bloom = {value}: '{err}' lacks '{part}'"
            );
        }
    }
    let scene = |text: &str| {
        Scene::from_toml(
            &format!("{text}[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n"),
            "bloom.toml",
            Path::new("."),
        )
        .unwrap()
    };
    assert_eq!(scene("").tone_map.bloom, None);
    assert_eq!(
        scene("[tone_map]\nbloom = {}\n").tone_map.bloom,
        Some(Bloom::default())
    );
}

#[test]
fn the_bloom_knob_takes_off_on_or_an_intensity() {
    let knob = KNOBS.iter().find(|k| k.name == "bloom").unwrap();
    let mut scene = glow_scene(16, 16, "");
    assert_eq!((knob.read)(&scene), "off");
    (knob.apply)(&mut scene, "on").unwrap();
    assert_eq!(scene.tone_map.bloom, Some(Bloom::default()));
    assert_eq!((knob.read)(&scene), "on");
    (knob.apply)(&mut scene, "0.25").unwrap();
    assert_eq!(scene.tone_map.bloom.unwrap().intensity, 0.25);
    assert_eq!((knob.read)(&scene), "0.25");
    (knob.apply)(&mut scene, "off").unwrap();
    assert_eq!(scene.tone_map.bloom, None);
    for bad in ["maybe", "0", "-1", "1.5", "NaN", "inf"] {
        let err = (knob.apply)(&mut scene, bad).unwrap_err();
        assert!(!err.is_empty(), "knob bloom={bad}");
    }
}
