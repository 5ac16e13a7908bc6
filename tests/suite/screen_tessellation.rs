//! `tessellation = "auto"` end to end: a grid of small spheres drawn with
//! grids chosen by screen-space error looks like the fixed 64x32 image at a
//! fraction of the triangles, and `aerial render` says what it chose.

use aerial::report::image_diff::{compare_images, ImageRef, Metric};
use aerial::scene::Knob;

use crate::common;

/// `side`x`side` spheres of radius 0.4 one unit apart, seen from above
/// and in front, at 160x90, with the fixed default tessellation.
fn sphere_grid(side: usize) -> String {
    let mut text = format!(
        "[output]\nwidth = 160\nheight = 90\n\
         [camera]\neye = [0.0, {h}, {d}]\nlook_at = [0.0, 0.0, 0.0]\n\
         [[lights]]\ntype = \"directional\"\ndirection = [-0.3, -1.0, -0.5]\n\
         [[materials]]\nname = \"clay\"\nkd = [0.7, 0.3, 0.2]\n",
        h = 0.6 * side as f64 + 2.0,
        d = 1.2 * side as f64 + 4.0,
    );
    let half = side as f64 / 2.0 - 0.5;
    for i in 0..side {
        for j in 0..side {
            text += &format!(
                "[[objects]]\nname = \"s{i}_{j}\"\nmaterial = \"clay\"\n\
                 shape = {{ type = \"sphere\", radius = 0.4 }}\n\
                 translate = [{}, 0.0, {}]\n",
                i as f64 - half,
                j as f64 - half
            );
        }
    }
    text
}

fn srgb(p: &aerial::render::Pixels<u8>) -> ImageRef<'_> {
    ImageRef::Srgb8 {
        width: p.width,
        height: p.height,
        rgba: &p.data,
    }
}

#[test]
fn auto_draws_a_fraction_of_the_triangles_for_the_same_image() {
    let fixed = common::scene(&sphere_grid(8));
    let mut auto = fixed.clone();
    Knob::find("tessellation")
        .unwrap()
        .set(&mut auto, "auto")
        .unwrap();
    let (fixed_triangles, auto_triangles) = (fixed.triangle_count(), auto.triangle_count());
    assert!(
        auto_triangles * 10 < fixed_triangles,
        "auto {auto_triangles}, fixed {fixed_triangles}"
    );
    let (a, b) = (common::render(&fixed, false), common::render(&auto, false));
    common::assert_not_blank(&b.output, 0.02);
    let diff = compare_images(
        "fixed",
        srgb(&a.output),
        "auto",
        srgb(&b.output),
        Metric::Flip,
    )
    .unwrap();
    assert!(diff.mean <= 0.02, "FLIP mean {}", diff.mean);

    // A tighter budget: more triangles, and closer to the fixed image.
    let mut finer = auto.clone();
    Knob::find("max_pixel_error")
        .unwrap()
        .set(&mut finer, "0.125")
        .unwrap();
    assert!(finer.triangle_count() > 2 * auto_triangles);
    let c = common::render(&finer, false);
    let closer = compare_images(
        "fixed",
        srgb(&a.output),
        "finer",
        srgb(&c.output),
        Metric::Flip,
    )
    .unwrap();
    assert!(
        closer.mean < diff.mean,
        "{} then {}",
        diff.mean,
        closer.mean
    );
}

#[test]
fn render_prints_the_chosen_grids_and_triangles() {
    let dir = common::Scratch::new();
    let scene_path = dir.path("grid.toml");
    let text = sphere_grid(3).replace("translate", "tessellation = \"auto\"\ntranslate");
    std::fs::write(&scene_path, &text).unwrap();
    let scene = common::scene(&text);
    let out = common::succeed(
        common::aerial()
            .arg("render")
            .arg(&scene_path)
            .arg("--out")
            .arg(dir.path("grid.png")),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    let expected = format!("{} triangles drawn", scene.triangle_count());
    assert!(
        stderr.contains("tessellation auto (max_pixel_error 0.5): 9 objects, grids ")
            && stderr.contains(&expected),
        "{stderr}"
    );
    // A fixed scene prints no such line.
    std::fs::write(&scene_path, sphere_grid(2)).unwrap();
    let out = common::succeed(
        common::aerial()
            .arg("render")
            .arg(&scene_path)
            .arg("--out")
            .arg(dir.path("fixed.png")),
    );
    assert!(!String::from_utf8_lossy(&out.stderr).contains("tessellation auto"));
}
