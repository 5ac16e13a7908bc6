//! The frame as data: deferred lighting against forward on every example
//! scene, per-object and tile light culling, and LDR output without an HDR
//! attachment.
//! Every render runs under validation and must produce no message.

use crate::common;

use aerial::render::tiles::{self, TILE_SIZE};
use aerial::render::{FramePlan, Pixels, SceneGeometry};
use aerial::render_run::RenderRun;
use aerial::scene::{HdrFormat, Lighting, Scene, ToneMapOperator};
use std::path::Path;

/// Largest per-channel difference between two 8-bit images, in LSB, and
/// how many pixels differ at all.
/// Scene `name` rendered with forward and then with deferred lighting; the
/// deferred frame has its lighting pass and a picture.
fn forward_and_deferred(name: &str, scene: &Scene, keep_hdr: bool) -> (RenderRun, RenderRun) {
    let mut scene = scene.clone();
    scene.output.lighting = Lighting::Forward;
    let forward = common::render(&scene, keep_hdr);
    scene.output.lighting = Lighting::Deferred;
    let deferred = common::render(&scene, keep_hdr);
    assert!(
        deferred.passes.contains(&"lighting"),
        "{name}: deferred plan has no lighting pass: {:?}",
        deferred.passes
    );
    common::assert_not_blank(&deferred.output, 0.2);
    (forward, deferred)
}

fn diff_u8(a: &Pixels<u8>, b: &Pixels<u8>) -> (u8, usize) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let mut worst = 0;
    let mut differing = 0;
    for (pa, pb) in a.data.chunks_exact(4).zip(b.data.chunks_exact(4)) {
        let d = pa
            .iter()
            .zip(pb)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap_or(0);
        worst = worst.max(d);
        differing += usize::from(d > 0);
    }
    (worst, differing)
}

/// Forward and deferred lighting evaluate the same Blinn-Phong sum; the
/// deferred path reads kd, ks and shininess from 16-bit float targets, the
/// normal from a 16-bit octahedral encoding and the position from depth.
/// With culling off (light_cutoff = 0, so both evaluate every light) the
/// tone-mapped images must agree to within 2/255 everywhere, on at most 3 %
/// of the pixels (measured: at most 1/255, on 0.7-1.3 % of the pixels) and
/// the linear HDR images to a relative 0.5 % (measured: at most 0.16 %,
/// the 16-bit float G-buffer's rounding).
#[test]
fn deferred_and_forward_agree_on_every_example_scene() {
    for name in [
        "default.toml",
        "flag.toml",
        "many_lights.toml",
        "shading_models.toml",
        "transparency.toml",
    ] {
        let mut scene = common::example(name);
        scene.light_cutoff = 0.0;
        scene.set_output_size(Some(320), Some(180)).unwrap();
        let (forward, deferred) = forward_and_deferred(name, &scene, true);
        let (worst, differing) = diff_u8(&forward.output, &deferred.output);
        println!("{name}: forward vs deferred: {differing} pixels differ, by at most {worst}/255");
        assert!(worst <= 2, "{name}: differ by {worst}/255");
        assert!(
            differing * 100 <= 3 * (320 * 180),
            "{name}: {differing} pixels differ"
        );
        let (f, d) = (forward.hdr.unwrap(), deferred.hdr.unwrap());
        let mut worst_rel = 0.0f32;
        for (pf, pd) in f.data.chunks_exact(4).zip(d.data.chunks_exact(4)) {
            for c in 0..3 {
                let rel = (pf[c] - pd[c]).abs() / pf[c].abs().max(0.05);
                worst_rel = worst_rel.max(rel);
            }
        }
        println!("{name}: worst relative HDR difference {worst_rel:.2e}");
        assert!(worst_rel < 5e-3, "{name}: HDR differs by {worst_rel}");
    }
}

/// Culling is exact for the rendered light model: a point light's windowed
/// attenuation is 0 from its culling range on, so forward lighting (lights
/// culled per object) and deferred lighting (per 32x32 tile) give the same
/// image with every example scene's own `light_cutoff`. Oracle: the other
/// path; the bound is 1/255 on every channel of every pixel, with at most
/// 3 % of the pixels off by that (the G-buffer's rounding, as above).
/// Before the window, `many_lights.toml` (cutoff 0.02) differed by far
/// more on the small objects forward lighting culls lights from.
#[test]
fn deferred_and_forward_agree_with_each_scene_s_own_cutoff() {
    for name in [
        "default.toml",
        "flag.toml",
        "many_lights.toml",
        "normal_mapped.toml",
        "shading_models.toml",
        "smoothing.toml",
        "transparency.toml",
    ] {
        let mut scene = common::example(name);
        assert!(scene.light_cutoff > 0.0, "{name}: no cutoff to test");
        scene.set_output_size(Some(320), Some(180)).unwrap();
        let (forward, deferred) = forward_and_deferred(name, &scene, false);
        let (worst, differing) = diff_u8(&forward.output, &deferred.output);
        println!(
            "{name} (cutoff {}): forward vs deferred: {differing} pixels differ, by at most {worst}/255",
            scene.light_cutoff
        );
        assert!(worst <= 1, "{name}: differ by {worst}/255");
        assert!(
            differing * 100 <= 3 * (320 * 180),
            "{name}: {differing} pixels differ"
        );
    }
}

/// A point light with a short range, over a floor lit by a directional
/// light: deferred tiles outside the light's screen rectangle must be
/// bit-identical with and without it, and pixels inside must change.
#[test]
fn a_light_whose_range_misses_a_tile_does_not_change_it() {
    let toml = r#"
        ambient = [0.05, 0.05, 0.05]
        light_cutoff = 0.2
        [output]
        width = 256
        height = 160
        lighting = "deferred"
        [camera]
        eye = [0.0, 6.0, 6.0]
        look_at = [0.0, 0.0, 0.0]
        [[lights]]
        type = "directional"
        direction = [-0.3, -1.0, -0.2]
        color = [0.4, 0.4, 0.4]
        [[lights]]
        type = "point"
        position = [1.5, 0.5, 0.5]
        color = [1.0, 0.6, 0.2]
        intensity = 2.0
        attenuation = [1.0, 0.0, 12.0]
        [[materials]]
        name = "floor"
        kd = [0.7, 0.7, 0.7]
        ks = [0.3, 0.3, 0.3]
        [[objects]]
        name = "floor"
        material = "floor"
        shape = { type = "plane", width = 12.0, depth = 12.0 }
        tessellation = [8, 8]
    "#;
    let with = common::scene(toml);
    let mut without = with.clone();
    without.lights.truncate(1);
    let lit = common::render(&with, false).output;
    let unlit = common::render(&without, false).output;

    let rect = tiles::light_screen_rect(&with, 1, 256, 160).expect("the light reaches the screen");
    assert!(
        (rect.x1 - rect.x0) * (rect.y1 - rect.y0) < 256 * 160 / 4,
        "the test light should cover a small part of the image, got {rect:?}"
    );
    // The tiles the light is listed for: those its rectangle touches.
    let in_lit_tile = |x: u32, y: u32| {
        let (tx, ty) = (x / TILE_SIZE, y / TILE_SIZE);
        (rect.x0 / TILE_SIZE..rect.x1.div_ceil(TILE_SIZE)).contains(&tx)
            && (rect.y0 / TILE_SIZE..rect.y1.div_ceil(TILE_SIZE)).contains(&ty)
    };
    let (mut changed_inside, mut changed_outside) = (0, 0);
    for y in 0..160 {
        for x in 0..256 {
            let (a, b) = (common::pixel(&lit, x, y), common::pixel(&unlit, x, y));
            if a != b {
                if in_lit_tile(x, y) {
                    changed_inside += 1;
                } else {
                    changed_outside += 1;
                }
            }
        }
    }
    assert_eq!(
        changed_outside, 0,
        "pixels outside the light's tiles changed"
    );
    assert!(
        changed_inside > 100,
        "the light changed only {changed_inside} pixels"
    );
    // The plan lists the light for exactly those tiles.
    let plan = FramePlan::new(&with, &SceneGeometry::new(&with).unwrap(), false);
    for group in &plan.tile_groups {
        for r in &group.rects {
            let inside = in_lit_tile(r.x0, r.y0);
            assert_eq!(
                group.lights.contains(&1),
                inside,
                "{r:?} {:?}",
                group.lights
            );
        }
    }
}

/// `tone_map.operator = "none"` with an rgba32f target: the surface pass
/// writes the sRGB output directly (no HDR attachment, no tone map); the
/// image equals the clamped linear HDR image of the same scene (read back
/// through the HDR path), sRGB-encoded, to within one step of rounding, and
/// is the very image the HDR path gives. With rgba16f the HDR target stays
/// (its rounding would change the PNG), so `--hdr` never changes the PNG.
#[test]
fn ldr_output_is_the_clamped_hdr_image() {
    let mut scene = common::example("default.toml");
    scene.set_output_size(Some(200), Some(120)).unwrap();
    scene.tone_map.operator = ToneMapOperator::None;
    // rgba16f: the same frame with and without the HDR image read back.
    assert_eq!(scene.output.hdr_format, HdrFormat::Rgba16F);
    let without = common::render(&scene, false);
    assert_eq!(without.passes, vec!["opaque", "tonemap", "readback"]);
    common::assert_not_blank(&without.output, 0.2);
    let with = common::render(&scene, true);
    assert!(
        without.output.data == with.output.data,
        "rgba16f: the PNG depends on --hdr ({:?} differing/worst)",
        diff_u8(&without.output, &with.output)
    );

    scene.output.hdr_format = HdrFormat::Rgba32F;
    let direct = common::render(&scene, false);
    assert_eq!(direct.passes, vec!["opaque", "readback"]);
    common::assert_not_blank(&direct.output, 0.2);
    let via_hdr = common::render(&scene, true);
    assert_eq!(via_hdr.passes, vec!["opaque", "tonemap", "readback"]);
    let hdr = via_hdr.hdr.unwrap();
    let srgb = |c: f32| {
        let c = c.clamp(0.0, 1.0);
        let v = if c <= 0.0031308 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        v * 255.0
    };
    let mut worst = 0.0f32;
    for (p, h) in direct
        .output
        .data
        .chunks_exact(4)
        .zip(hdr.data.chunks_exact(4))
    {
        for c in 0..3 {
            worst = worst.max((f32::from(p[c]) - srgb(h[c])).abs());
        }
    }
    // 0.5 for rounding, plus the 16-bit float HDR target's rounding seen
    // through the sRGB curve's steep start.
    assert!(worst <= 1.0, "worst difference {worst} LSB");
    let (d, n) = diff_u8(&direct.output, &via_hdr.output);
    assert_eq!((d, n), (0, 0), "direct and tone-mapped LDR differ");
}

/// LDR output with transparent objects, or with deferred lighting, keeps
/// the HDR target and a clamping tone map (so the image is still exactly
/// the clamped HDR image); deferred and forward then agree as with any
/// tone map.
#[test]
fn deferred_ldr_with_transparency_agrees_with_forward() {
    let mut scene = common::example("transparency.toml");
    scene.light_cutoff = 0.0;
    scene.set_output_size(Some(240), Some(135)).unwrap();
    scene.tone_map.operator = ToneMapOperator::None;
    let forward = common::render(&scene, false);
    assert_eq!(
        forward.passes,
        vec!["opaque", "transparent", "tonemap", "readback"]
    );
    scene.output.lighting = Lighting::Deferred;
    let deferred = common::render(&scene, false);
    assert_eq!(
        deferred.passes,
        vec!["gbuffer", "lighting", "transparent", "tonemap", "readback"]
    );
    common::assert_not_blank(&deferred.output, 0.2);
    let (worst, differing) = diff_u8(&forward.output, &deferred.output);
    assert!(worst <= 2, "differ by {worst}/255");
    assert!(
        differing * 100 <= 3 * 240 * 135,
        "{differing} pixels differ"
    );
}

// Per-object light culling, checked on pixels.
//
// A unit sphere at the origin, seen from (0, 0, 5), lit by a dim directional
// light and a point light at (0, 0, 4) with attenuation 1/(1 + d^2). The
// point light's distance to the sphere's bounding sphere is 3, so it
// reaches the object with at most 1/10 of its intensity I. With
// light_cutoff = 0.01 it is culled for I = 0.05 (0.005 < 0.01) and kept for
// I = 0.15 (0.015 > 0.01; judged at the sphere's centre, 4 away, it would
// wrongly be culled: 0.15/17 < 0.01).
//
// A culled light contributes nothing, and with the windowed attenuation
// (1 / (1 + d^2) - cutoff / I, clamped at 0) a light beyond its range
// contributes nothing either, so culling changes no pixel. Against no
// cutoff at all (no window) the difference is at most the light's
// unwindowed radiance at the nearest point, I/10, times kd + ks = 1, for
// a light that is culled, and cutoff x (kd + ks) for one that is kept.

fn culling_scene(intensity: Option<f64>, cutoff: f64) -> Scene {
    let light = intensity.map_or(String::new(), |i| {
        format!(
            "[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 4.0]\n\
             intensity = {i}\nattenuation = [1.0, 0.0, 1.0]\n"
        )
    });
    common::scene(&format!(
        r#"
light_cutoff = {cutoff}
[output]
width = 96
height = 96
hdr_format = "rgba32f"
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
[[lights]]
type = "directional"
direction = [-1.0, -1.0, -1.0]
intensity = 0.5
{light}
[[materials]]
name = "m"
kd = [0.5, 0.5, 0.5]
ka = [0.0, 0.0, 0.0]
ks = [0.5, 0.5, 0.5]
shininess = 20.0
[[objects]]
name = "ball"
material = "m"
shape = {{ type = "sphere", radius = 1.0 }}
"#
    ))
}

/// Largest per-channel difference over pixels covered in both images, and
/// how many covered pixels there are.
fn max_difference(a: &Pixels<f32>, b: &Pixels<f32>) -> (f64, usize) {
    let mut worst: f64 = 0.0;
    let mut covered = 0;
    for (pa, pb) in a.data.chunks_exact(4).zip(b.data.chunks_exact(4)) {
        if pa[3] == 0.0 || pb[3] == 0.0 {
            continue;
        }
        covered += 1;
        for c in 0..3 {
            worst = worst.max((pa[c] as f64 - pb[c] as f64).abs());
        }
    }
    (worst, covered)
}

fn hdr(scene: &Scene) -> Pixels<f32> {
    let run = common::render(scene, true);
    common::assert_not_blank(&run.output, 0.2);
    run.hdr.unwrap()
}

#[test]
fn a_culled_light_changes_no_pixel_beyond_the_cutoff_bound() {
    let cutoff = 0.01;
    let without = hdr(&culling_scene(None, cutoff));

    // Culled: the object's pixels are exactly those without the light.
    let culled = hdr(&culling_scene(Some(0.05), cutoff));
    let (diff, covered) = max_difference(&culled, &without);
    assert!(covered > 2000, "{covered} covered pixels");
    assert_eq!(diff, 0.0, "a culled light changed the object");

    // Without culling the same light does reach the object, by no more
    // than the bound I/10 x (kd + ks) = 0.005 (plus float rounding).
    let exact = hdr(&culling_scene(Some(0.05), 0.0));
    let (diff, _) = max_difference(&exact, &culled);
    assert!(
        diff > 0.001 && diff <= 0.005 + 1e-5,
        "culling changed a pixel by {diff}, bound 0.005"
    );

    // Above the cutoff the light is kept, and it changes the object: its
    // windowed attenuation (1 / (1 + d^2) - cutoff / I, from d = 3 at the
    // nearest point) gives 0.15 x (0.1 - 0.0667) x (kd + ks) = 0.005 there.
    let kept = hdr(&culling_scene(Some(0.15), cutoff));
    let (diff, _) = max_difference(&kept, &without);
    assert!(
        diff > 0.003 && diff <= 0.005 + 1e-5,
        "a light above the cutoff changed the object by {diff}, expected 0.005"
    );
    // The window dims it by at most cutoff x (kd + ks) = 0.01 against no
    // cutoff at all.
    let kept_exact = hdr(&culling_scene(Some(0.15), 0.0));
    let (diff, _) = max_difference(&kept, &kept_exact);
    assert!(
        diff > 0.0 && diff <= 0.01 + 1e-5,
        "the window changed a pixel by {diff}, bound 0.01"
    );
}

/// Lights carried as specialization constants (`static_lights = true`, the
/// default) and read from their uniform blocks give the same image, bit
/// for bit, forward and deferred: the constants are the block's floats and
/// the shader's arithmetic is the same. Oracle: the block path. Scenes: six
/// lights on every object and tile (all static), three lights with the
/// default cutoff, and sixteen lights with culling off (more than a
/// pipeline carries, so both settings read the blocks there).
#[test]
fn static_lights_draw_what_uniform_blocks_draw() {
    let bench = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench/many_lights.toml");
    let mut scenes = vec![(
        "bench many_lights.toml",
        Scene::load(&bench).unwrap_or_else(|e| panic!("{e}")),
    )];
    scenes.push(("default.toml", common::example("default.toml")));
    let mut sixteen = common::example("many_lights.toml");
    sixteen.light_cutoff = 0.0;
    scenes.push(("many_lights.toml, no culling", sixteen));
    for (name, mut scene) in scenes {
        scene.set_output_size(Some(160), Some(90)).unwrap();
        scene.output.static_lights = false;
        let (block_forward, block_deferred) = forward_and_deferred(name, &scene, true);
        scene.output.static_lights = true;
        let (forward, deferred) = forward_and_deferred(name, &scene, true);
        common::assert_not_blank(&forward.output, 0.2);
        for (path, a, b) in [
            ("forward", &forward, &block_forward),
            ("deferred", &deferred, &block_deferred),
        ] {
            assert_eq!(diff_u8(&a.output, &b.output), (0, 0), "{name}, {path}");
            let (ha, hb) = (a.hdr.as_ref().unwrap(), b.hdr.as_ref().unwrap());
            assert!(
                ha.data
                    .iter()
                    .zip(&hb.data)
                    .all(|(x, y)| x.to_bits() == y.to_bits()),
                "{name}, {path}: HDR differs"
            );
        }
    }
}
