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

mod common;

use glam::DVec3;

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

fn hit_sphere(origin: DVec3, dir: DVec3, centre: DVec3, r: f64) -> Option<f64> {
    let oc = origin - centre;
    let b = oc.dot(dir);
    let c = oc.length_squared() - r * r;
    let disc = b * b - c;
    (disc > 0.0).then(|| -b - disc.sqrt())
}

#[test]
fn blinn_phong_matches_double_precision_oracle() {
    let scene = common::scene(SCENE);
    let run = common::render(&scene, true);
    let hdr = run.hdr.as_ref().expect("HDR requested");

    // Round-trip through the EXR writer, as a user of --hdr would see it.
    let dir = std::env::temp_dir().join(format!("aerial-oracle-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("oracle.exr");
    aerial::render::output::write_exr(&path, hdr).unwrap();
    let exr = aerial::render::output::read_exr(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();

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
            let Some(t) = hit_sphere(cam.eye, d, DVec3::ZERO, 1.0) else {
                continue;
            };
            let p = cam.eye + d * t;
            let n = p.normalize();
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
