//! The GPU's per-pixel Blinn-Phong against a CPU evaluation of the same
//! formula in double precision.
//!
//! The CPU side computes each pixel's ray from the camera description and
//! intersects it with the analytic sphere, independently of the renderer's
//! matrices. The rendered sphere is a tessellation (256×128), so its surface
//! lies up to r·(1 − cos(π/128)) ≈ 3·10⁻⁴ r inside the analytic one; the
//! stated tolerance, |gpu − cpu| ≤ 0.004 + 0.01·cpu per channel on the
//! 32-bit float HDR output read back from the EXR file, covers that and
//! float32 shading.

use crate::common;

use glam::{DMat4, DQuat, DVec3};

const SCENE: &str = r#"
ambient = [0.2, 0.2, 0.2]
[output]
width = 160
height = 120
hdr_format = "rgba32f"
[camera]
eye = [0.0, 0.5, 5.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0
[[lights]]
type = "point"
position = [2.0, 2.0, 4.0]
color = [1.0, 0.9, 0.8]
intensity = 12.0
attenuation = [1.0, 0.1, 0.05]
[[materials]]
name = "clay"
ka = [0.1, 0.1, 0.1]
kd = [0.6, 0.5, 0.4]
ks = [0.5, 0.5, 0.5]
shininess = 20.0
shading = "phong"
[[objects]]
name = "ball"
material = "clay"
shape = { type = "sphere", radius = 1.0 }
tessellation = [256, 128]
"#;

struct Camera {
    eye: DVec3,
    u: DVec3,
    v: DVec3,
    w: DVec3,
    tan_half_fov: f64,
    aspect: f64,
}

impl Camera {
    /// The textbook camera basis: w = (eye − lookat)/|·|, u = up×w/|·|, v = w×u.
    fn new(eye: DVec3, look_at: DVec3, up: DVec3, fov_deg: f64, aspect: f64) -> Camera {
        let w = (eye - look_at).normalize();
        let u = up.cross(w).normalize();
        let v = w.cross(u);
        Camera {
            eye,
            u,
            v,
            w,
            tan_half_fov: (fov_deg.to_radians() / 2.0).tan(),
            aspect,
        }
    }

    /// Direction through the centre of pixel (x, y), row 0 at the top.
    fn ray(&self, x: u32, y: u32, width: u32, height: u32) -> DVec3 {
        let sx = ((x as f64 + 0.5) / width as f64 * 2.0 - 1.0) * self.tan_half_fov * self.aspect;
        let sy = (1.0 - (y as f64 + 0.5) / height as f64 * 2.0) * self.tan_half_fov;
        (self.u * sx + self.v * sy - self.w).normalize()
    }
}

/// The first hit of a ray with the unit sphere transformed by `model`:
/// the world-space point and the world-space unit normal. The ray is taken
/// to object space, where the surface is |p| = 1, and the normal is the
/// gradient of that implicit function carried back by M^-T.
fn hit_transformed_sphere(origin: DVec3, dir: DVec3, model: DMat4) -> Option<(DVec3, DVec3)> {
    let inv = model.inverse();
    let o = inv.transform_point3(origin);
    let d = inv.transform_vector3(dir);
    let a = d.length_squared();
    let b = o.dot(d);
    let c = o.length_squared() - 1.0;
    let disc = b * b - a * c;
    if disc <= 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / a;
    let p_object = o + d * t;
    let normal = inv.transpose().transform_vector3(p_object).normalize();
    Some((origin + dir * t, normal))
}

#[test]
fn blinn_phong_matches_double_precision_oracle() {
    check_against_oracle(SCENE, DMat4::IDENTITY);
}

#[test]
fn non_uniformly_scaled_normals_use_the_inverse_transpose() {
    // An ellipsoid: the sphere scaled (1.5, 0.8, 1) and turned 30° about z.
    // Transforming normals with M instead of M^-T tilts them visibly.
    let scene = SCENE.replace(
        "tessellation = [256, 128]",
        "tessellation = [256, 128]\nscale = [1.5, 0.8, 1.0]\nrotate = { axis = [0.0, 0.0, 1.0], degrees = 30.0 }",
    );
    let model = DMat4::from_scale_rotation_translation(
        DVec3::new(1.5, 0.8, 1.0),
        DQuat::from_rotation_z(30f64.to_radians()),
        DVec3::ZERO,
    );
    check_against_oracle(&scene, model);
}

fn check_against_oracle(scene_toml: &str, model: DMat4) {
    let scene = common::scene(scene_toml);
    let run = common::render(&scene, true);
    let hdr = run.hdr.as_ref().expect("HDR requested");

    // Round-trip through the EXR writer, as a user of --hdr would see it.
    // Tests run in parallel: one file name per model.
    let path = std::env::temp_dir().join(format!(
        "aerial-oracle-{}-{:x}.exr",
        std::process::id(),
        model
            .to_cols_array()
            .iter()
            .map(|v| v.to_bits())
            .fold(0u64, |a, b| a.rotate_left(7) ^ b)
    ));
    aerial::image_io::write_exr(&path, hdr).unwrap();
    let exr = aerial::image_io::read_exr(&path).unwrap();
    std::fs::remove_file(&path).ok();

    let (w, h) = (exr.width, exr.height);
    let cam = Camera::new(
        DVec3::new(0.0, 0.5, 5.0),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        w as f64 / h as f64,
    );
    let light = DVec3::new(2.0, 2.0, 4.0);
    let le = DVec3::new(1.0, 0.9, 0.8) * 12.0;
    let (ka, kd, ks, shine) = (
        DVec3::splat(0.1),
        DVec3::new(0.6, 0.5, 0.4),
        DVec3::splat(0.5),
        20.0,
    );
    let la = DVec3::splat(0.2);

    let mut checked = 0;
    let mut worst = 0.0f64;
    let mut saw_highlight = false;
    for y in (0..h).step_by(3) {
        for x in (0..w).step_by(3) {
            let d = cam.ray(x, y, w, h);
            let Some((p, n)) = hit_transformed_sphere(cam.eye, d, model) else {
                continue;
            };
            let v = (cam.eye - p).normalize();
            // Stay away from the silhouette, where the polygonal outline
            // and the analytic one cover different pixels.
            if n.dot(v) < 0.35 {
                continue;
            }
            let to_light = light - p;
            let dist = to_light.length();
            let l = to_light / dist;
            let att = 1.0 / (1.0 + 0.1 * dist + 0.05 * dist * dist);
            let mut expected = ka * la;
            let cos_theta = n.dot(l);
            if cos_theta > 0.0 {
                let hv = (l + v).normalize();
                let spec = n.dot(hv).max(0.0).powf(shine);
                expected += le * att * (kd * cos_theta + ks * spec);
                saw_highlight |= spec > 0.8;
            }
            let got = common::pixel(&exr, x, y);
            for c in 0..3 {
                let e = expected[c];
                let g = got[c] as f64;
                let tolerance = 0.004 + 0.01 * e;
                worst = worst.max((g - e).abs() / tolerance);
                assert!(
                    (g - e).abs() <= tolerance,
                    "pixel ({x},{y}) channel {c}: gpu {g:.5}, cpu {e:.5}"
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 150, "only {checked} pixels checked");
    assert!(
        saw_highlight,
        "the sampled pixels never reached the highlight"
    );
    eprintln!("{checked} pixels within tolerance; worst error {worst:.2} of the tolerance");
}
