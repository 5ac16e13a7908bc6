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

use aerial::render::Pixels;
use aerial::report::{compare_images, ImageRef, Metric, FLIP_DEFAULT_THRESHOLDS};
use aerial::scene::{Lighting, ModelSceneOptions, Scene};
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
    let name = format!("{lighting:?}_{:e}_{:e}_{:e}", offset.x, offset.y, offset.z).to_lowercase();
    assert_same_image(&name, &base, &moved, 2);
}

fn srgb(p: &Pixels<u8>) -> ImageRef<'_> {
    ImageRef::Srgb8 {
        width: p.width,
        height: p.height,
        rgba: &p.data,
    }
}

/// `moved` is `base` up to rounding: within the regression suite's FLIP
/// limits and at most `most` 1/255 steps on every channel of every pixel.
/// Both are saved for looking at: target/world_precision/<name>.png and
/// <name>_origin.png.
fn assert_same_image(name: &str, base: &Pixels<u8>, moved: &Pixels<u8>, most: u8) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("world_precision");
    std::fs::create_dir_all(&dir).unwrap();
    for (suffix, image) in [("", moved), ("_origin", base)] {
        image::save_buffer(
            dir.join(format!("{name}{suffix}.png")),
            &image.data,
            image.width,
            image.height,
            image::ColorType::Rgba8,
        )
        .unwrap();
    }
    assert_eq!((base.width, base.height), (moved.width, moved.height));
    let cmp = compare_images("at the origin", srgb(base), name, srgb(moved), Metric::Flip).unwrap();
    let largest = largest_difference(&base.data, &moved.data);
    eprintln!(
        "{name}: FLIP mean {:.5}, p99 {:.5}, worst window {:.5}; largest channel difference \
         {largest}/255",
        cmp.mean, cmp.p99, cmp.worst_window
    );
    assert!(
        cmp.passes(&FLIP_DEFAULT_THRESHOLDS),
        "{name}: FLIP mean {}, p99 {}, worst window {} beyond the regression limits",
        cmp.mean,
        cmp.p99,
        cmp.worst_window
    );
    assert!(
        largest <= most,
        "{name}: a channel differs by {largest}/255"
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

/// A UV sphere of `radius` around `centre` as OBJ text, with its normals,
/// the coordinates written in full (as an exporter working in f64 writes
/// a model placed in world coordinates).
fn sphere_obj(centre: DVec3, radius: f64) -> String {
    use std::fmt::Write as _;
    let (rings, segments) = (24, 48);
    let mut text = String::new();
    for ring in 0..=rings {
        let theta = std::f64::consts::PI * f64::from(ring) / f64::from(rings);
        for segment in 0..segments {
            let phi = std::f64::consts::TAU * f64::from(segment) / f64::from(segments);
            let n = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            let p = centre + n * radius;
            let _ = writeln!(
                text,
                "v {} {} {}\nvn {} {} {}",
                p.x, p.y, p.z, n.x, n.y, n.z
            );
        }
    }
    let index = |ring: u32, segment: u32| ring * segments + segment % segments + 1;
    for ring in 0..rings {
        for segment in 0..segments {
            let [a, b, c, d] = [
                index(ring, segment),
                index(ring, segment + 1),
                index(ring + 1, segment + 1),
                index(ring + 1, segment),
            ];
            // Counter-clockwise seen from outside.
            let _ = writeln!(
                text,
                "f {a}//{a} {b}//{b} {c}//{c}\nf {a}//{a} {c}//{c} {d}//{d}"
            );
        }
    }
    text
}

/// A scene with the sphere model `model` (at `centre`, of `radius`), the
/// camera 3.5 radii in front of it (+z) and a key light.
fn sphere_scene(model: &Path, centre: DVec3, radius: f64) -> Scene {
    let eye = centre + DVec3::new(0.0, 0.0, 3.5 * radius);
    let text = format!(
        "ambient = [0.05, 0.05, 0.05]\n[output]\nwidth = {WIDTH}\nheight = {HEIGHT}\n\
         [camera]\neye = [{:?}, {:?}, {:?}]\nlook_at = [{:?}, {:?}, {:?}]\nnear = {:?}\n\
         [[lights]]\ntype = \"directional\"\ndirection = [-0.4, -0.7, -0.6]\n\
         [[materials]]\nname = \"m\"\nkd = [0.8, 0.3, 0.2]\nks = [0.5, 0.5, 0.5]\nshininess = 32.0\n\
         [[objects]]\nname = \"ball\"\nmaterial = \"m\"\nshape = {{ type = \"obj\", path = {:?} }}\n",
        eye.x,
        eye.y,
        eye.z,
        centre.x,
        centre.y,
        centre.z,
        radius * 0.1,
        model.display().to_string(),
    );
    let mut scene = Scene::from_toml(&text, "sphere test scene", Path::new(""))
        .unwrap_or_else(|e| panic!("{e}"));
    scene.output.lighting = Lighting::Forward;
    scene
}

/// An OBJ model written far from the origin renders as the same model at
/// the origin (the camera moved along): its positions are read in f64 and
/// re-centred before they are rounded to 32 bits, as a scene's own
/// translations are. A unit sphere at 1e7 to 1e9 m on each axis, and a
/// 1 mm sphere at 1e6 m. Before, the sphere at 1e7 m came out distorted
/// and from 1e8 m (the 1 mm one from 1e6 m) the image was black.
#[test]
fn a_model_written_far_from_the_origin_renders_as_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    for (radius, offsets) in [
        (
            1.0,
            vec![
                DVec3::new(1e7, 0.0, 0.0),
                DVec3::new(0.0, 1e8, 0.0),
                DVec3::new(1e9, 0.0, 0.0),
                DVec3::new(-7e8 - 0.37, 3e8 + 0.1, 9e8),
            ],
        ),
        (
            1e-3,
            vec![DVec3::new(1e6, 0.0, 0.0), DVec3::new(0.0, 0.0, -1e6)],
        ),
    ] {
        let here = dir.path().join("origin.obj");
        std::fs::write(&here, sphere_obj(DVec3::ZERO, radius)).unwrap();
        let base = common::render(&sphere_scene(&here, DVec3::ZERO, radius), false).output;
        common::assert_not_blank(&base, 0.2);
        for offset in offsets {
            let far = dir.path().join("far.obj");
            std::fs::write(&far, sphere_obj(offset, radius)).unwrap();
            let moved = common::render(&sphere_scene(&far, offset, radius), false).output;
            let name = format!(
                "sphere_{radius:e}_at_{:e}_{:e}_{:e}",
                offset.x, offset.y, offset.z
            );
            assert_same_image(&name, &base, &moved, 2);
        }
    }
}

/// The scene `aerial render MODEL.obj` builds around a far-off model
/// frames it as it frames the same model at the origin: the camera is
/// placed in f64 from the model's f64 bounds, and the image is the same.
#[test]
fn a_far_off_model_is_framed_as_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    let options = ModelSceneOptions {
        width: WIDTH,
        height: HEIGHT,
        ..ModelSceneOptions::default()
    };
    let here = dir.path().join("origin.obj");
    std::fs::write(&here, sphere_obj(DVec3::ZERO, 1.0)).unwrap();
    let base = common::render(&Scene::from_model(&here, &options).unwrap(), false).output;
    common::assert_not_blank(&base, 0.2);
    for offset in [DVec3::new(1e8, 0.0, 0.0), DVec3::new(-3e8, 2e8, 9.9e8)] {
        let far = dir.path().join("far.obj");
        std::fs::write(&far, sphere_obj(offset, 1.0)).unwrap();
        let scene = Scene::from_model(&far, &options).unwrap();
        assert!(
            (scene.camera.look_at - offset).length() < 1e-6,
            "{}",
            scene.camera.look_at
        );
        let moved = common::render(&scene, false).output;
        let name = format!(
            "model_scene_at_{:e}_{:e}_{:e}",
            offset.x, offset.y, offset.z
        );
        assert_same_image(&name, &base, &moved, 2);
    }
}
