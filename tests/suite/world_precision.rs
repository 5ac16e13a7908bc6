//! World precision: a scene far from the world origin renders like the same
//! scene at the origin. The renderer works relative to the camera (model-view
//! matrices and light positions composed in f64 and only then rounded to
//! f32; positions rebuilt from depth stay camera-relative), so translating
//! the whole scene by X changes nothing the GPU sees but rounding.
//!
//! Oracle: the untranslated render of the same scene, compared with the
//! regression suite's FLIP limits (`FLIP_DEFAULT_THRESHOLDS`: mean 0.03,
//! p99 0.1, worst 12x12 window 0.3) and, stricter, at most 2/255 on every
//! channel of every pixel. Before camera-relative rendering, the default
//! scene moved by 1e6 was off by more than half the range and by 1e8 drew
//! nothing.

use crate::common;

use aerial::report::{compare_images, ImageRef, Metric, FLIP_DEFAULT_THRESHOLDS};
use aerial::scene::{Lighting, Scene};
use glam::DVec3;
use std::path::Path;

const WIDTH: u32 = 160;
const HEIGHT: u32 = 90;

fn default_scene(lighting: Lighting) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    scene
        .set_output_size(Some(WIDTH), Some(HEIGHT))
        .unwrap_or_else(|e| panic!("{e}"));
    scene.output.lighting = lighting;
    scene
}

fn largest_difference(a: &[u8], b: &[u8]) -> u8 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

fn check(lighting: Lighting, offset: DVec3) {
    let base = common::render(&default_scene(lighting), false).output;
    let moved_scene = common::translated(default_scene(lighting), offset);
    let moved = common::render(&moved_scene, false).output;
    common::assert_not_blank(&moved, 0.5);
    // For looking at: target/world_precision/<lighting>_<x>.png.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("world_precision");
    std::fs::create_dir_all(&dir).unwrap();
    let name = format!("{lighting:?}_{:e}_{:e}_{:e}", offset.x, offset.y, offset.z).to_lowercase();
    for (suffix, image) in [("", &moved), ("_origin", &base)] {
        image::save_buffer(
            dir.join(format!("{name}{suffix}.png")),
            &image.data,
            WIDTH,
            HEIGHT,
            image::ColorType::Rgba8,
        )
        .unwrap();
    }
    assert_eq!((base.width, base.height), (moved.width, moved.height));
    let cmp = compare_images(
        "at the origin",
        ImageRef::Srgb8 {
            width: WIDTH,
            height: HEIGHT,
            rgba: &base.data,
        },
        &format!("moved by {offset}"),
        ImageRef::Srgb8 {
            width: WIDTH,
            height: HEIGHT,
            rgba: &moved.data,
        },
        Metric::Flip,
    )
    .unwrap();
    let largest = largest_difference(&base.data, &moved.data);
    eprintln!(
        "{lighting:?} moved by {offset}: FLIP mean {:.5}, p99 {:.5}, worst window {:.5}; largest \
         channel difference {largest}/255",
        cmp.mean, cmp.p99, cmp.worst_window
    );
    assert!(
        cmp.passes(&FLIP_DEFAULT_THRESHOLDS),
        "{lighting:?} moved by {offset}: FLIP mean {}, p99 {}, worst window {} beyond the \
         regression limits",
        cmp.mean,
        cmp.p99,
        cmp.worst_window
    );
    assert!(
        largest <= 2,
        "{lighting:?} moved by {offset}: a channel differs by {largest}/255"
    );
}

#[test]
fn forward_scene_moved_by_1e6_renders_as_at_the_origin() {
    check(Lighting::Forward, DVec3::new(1e6, 0.0, 0.0));
}

#[test]
fn forward_scene_moved_by_1e9_renders_as_at_the_origin() {
    check(Lighting::Forward, DVec3::new(1e9, 0.0, 0.0));
}

#[test]
fn deferred_scene_moved_by_1e6_renders_as_at_the_origin() {
    check(Lighting::Deferred, DVec3::new(1e6, 0.0, 0.0));
}

#[test]
fn deferred_scene_moved_by_1e9_renders_as_at_the_origin() {
    check(Lighting::Deferred, DVec3::new(1e9, 0.0, 0.0));
}

/// Negative, intermediate and inexact offsets on every axis; one of them
/// puts the camera 1 m above the ground of a 6,360 km planet centred at
/// the origin.
#[test]
fn other_offsets_render_as_at_the_origin() {
    for (offset, lighting) in [
        (DVec3::new(-1e9, 0.0, 0.0), Lighting::Forward),
        (DVec3::new(3.3e7, 0.0, 0.0), Lighting::Deferred),
        (DVec3::new(-1e5, 0.0, 0.0), Lighting::Deferred),
        (DVec3::new(0.0, 6_360_000.0 - 1.4, 0.0), Lighting::Forward),
        (
            DVec3::new(-999_999_999.37, 123_456_789.1, 5e8 + 0.3),
            Lighting::Deferred,
        ),
    ] {
        check(lighting, offset);
    }
}
