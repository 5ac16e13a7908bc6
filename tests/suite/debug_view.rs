//! `--debug-view`: the HDR image holds the surface attribute itself, the
//! PNG shows 0.5 + 0.5 v. Checked on a sphere against its analytic normal
//! (the ray through each pixel centre intersected with the exact sphere),
//! against the definitions of the tangent frame, and through the CLI.
//! Every render runs under validation.

use crate::common;

use aerial::scene::{DebugView, Scene};
use glam::{DVec3, DVec4, Vec3};

const SIZE: u32 = 96;

fn sphere_scene(view: DebugView) -> Scene {
    let mut scene = common::scene(
        "[output]\nwidth = 96\nheight = 96\n\
         [camera]\neye = [0.0, 0.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 45.0\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.0, 0.0, -1.0]\n\
         [[materials]]\nname = \"m\"\nkd = [0.7, 0.2, 0.4]\n\
         [[objects]]\nname = \"ball\"\nmaterial = \"m\"\n\
         shape = { type = \"sphere\", radius = 1.0 }\ntessellation = [128, 64]\n",
    );
    scene.output.debug_view = Some(view);
    scene
}

/// The unit sphere's point seen through pixel (x, y), if any: the ray from
/// the eye through the pixel centre, from the inverse view-projection in
/// double precision.
fn exact_hit(scene: &Scene, x: u32, y: u32) -> Option<DVec3> {
    let inverse = scene.camera.view_projection(1.0).as_dmat4().inverse();
    let ndc_x = (f64::from(x) + 0.5) / f64::from(SIZE) * 2.0 - 1.0;
    let ndc_y = (f64::from(y) + 0.5) / f64::from(SIZE) * 2.0 - 1.0;
    let far = inverse * DVec4::new(ndc_x, ndc_y, 0.5, 1.0);
    let eye = scene.camera.eye;
    // The view-projection is camera-relative: the unprojected point is
    // already the direction from the eye.
    let d = (far.truncate() / far.w).normalize();
    // |eye + t d| = 1: t^2 + 2 b t + c = 0.
    let b = eye.dot(d);
    let c = eye.length_squared() - 1.0;
    let disc = b * b - c;
    (disc > 0.0).then(|| eye + d * (-b - disc.sqrt()))
}

fn hdr_at(hdr: &aerial::render::Pixels<f32>, x: u32, y: u32) -> Vec3 {
    let p = common::pixel(hdr, x, y);
    Vec3::new(p[0], p[1], p[2])
}

#[test]
fn normals_match_the_exact_sphere_and_the_png_shows_half_plus_half() {
    let scene = sphere_scene(DebugView::Normals);
    let run = common::render(&scene, true);
    let hdr = run.hdr.as_ref().unwrap();
    let (mut compared, mut worst) = (0, 0.0f64);
    let mut background = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let n = hdr_at(hdr, x, y);
            match exact_hit(&scene, x, y) {
                // Away from the silhouette, where polygon and sphere cover
                // different pixels.
                Some(p) if p.z > 0.3 => {
                    let angle = n.as_dvec3().angle_between(p).to_degrees();
                    worst = worst.max(angle);
                    compared += 1;
                    assert!((n.length() - 1.0).abs() < 1e-3, "not unit: {n}");
                }
                None if n == Vec3::ZERO => background += 1,
                _ => {}
            }
            // The PNG stores 0.5 + 0.5 v (to one step of rounding).
            let png = common::pixel(&run.output, x, y);
            for c in 0..3 {
                let expect = ((0.5 + 0.5 * n[c]).clamp(0.0, 1.0) * 255.0).round();
                assert!(
                    (f32::from(png[c]) - expect).abs() <= 1.0,
                    "({x},{y}) channel {c}: {} vs {expect}",
                    png[c]
                );
            }
        }
    }
    println!("{compared} pixels, worst normal error {worst:.3} degrees");
    assert!(compared > 2000, "only {compared} pixels on the sphere");
    assert!(
        background > 3000,
        "background must be 0, found {background} such pixels"
    );
    // 128x64 segments (2.8 x 2.8 degrees per quad): the interpolated
    // normal at the polygon's hit point is within a fraction of a degree of
    // the exact sphere's (measured 0.45); 0.75 leaves room for rounding.
    assert!(worst < 0.75, "worst {worst} degrees");
}

#[test]
fn tangent_frames_are_orthonormal_and_follow_u() {
    let frame = |view| {
        let run = common::render(&sphere_scene(view), true);
        run.hdr.unwrap()
    };
    let (normals, tangents, bitangents, uvs, albedo) = (
        frame(DebugView::Normals),
        frame(DebugView::Tangents),
        frame(DebugView::Bitangents),
        frame(DebugView::Uv),
        frame(DebugView::Albedo),
    );
    let scene = sphere_scene(DebugView::Normals);
    let mut checked = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some(p) = exact_hit(&scene, x, y) else {
                continue;
            };
            if p.z < 0.3 || p.y.abs() > 0.9 {
                continue; // silhouette and poles
            }
            let (n, t, b) = (
                hdr_at(&normals, x, y),
                hdr_at(&tangents, x, y),
                hdr_at(&bitangents, x, y),
            );
            assert!((t.length() - 1.0).abs() < 1e-3 && (b.length() - 1.0).abs() < 1e-3);
            assert!(n.dot(t).abs() < 1e-3 && n.dot(b).abs() < 1e-3 && t.dot(b).abs() < 1e-3);
            // u runs around the sphere's axis (y), so T is horizontal and B,
            // along v, lies in the meridian plane.
            assert!(t.y.abs() < 0.02, "({x},{y}) T = {t}");
            assert!(
                b.dot(Vec3::new(-p.z as f32, 0.0, p.x as f32).normalize())
                    .abs()
                    < 0.02
            );
            let uv = hdr_at(&uvs, x, y);
            assert!((0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y) && uv.z == 0.0);
            let kd = hdr_at(&albedo, x, y);
            assert!(
                (kd - Vec3::new(0.7, 0.2, 0.4)).abs().max_element() < 1e-3,
                "{kd}"
            );
            checked += 1;
        }
    }
    assert!(checked > 1500, "only {checked} pixels checked");
}

#[test]
fn the_cli_takes_debug_view() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("n.png");
    let result = common::aerial()
        .args([
            "render",
            "--validate",
            "--debug-view",
            "normals",
            "--width",
            "64",
            "--height",
            "36",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    // The default scene's ground faces +y: (0.5, 1, 0.5) in the bottom row.
    let img = image::open(&out).unwrap().to_rgb8();
    let ground = img.get_pixel(32, 35).0;
    assert!(
        ground[1] >= 254 && ground[0].abs_diff(128) <= 1 && ground[2].abs_diff(128) <= 1,
        "{ground:?}"
    );
    let bad = common::aerial()
        .args(["render", "--debug-view", "colours"])
        .arg("--out")
        .arg(dir.path().join("x.png"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
}
