//! Documented inclusive bounds are accepted at the bound and refused just
//! past it, whatever rounding the value goes through (the scene keeps f32
//! values, and 1e-6 rounded to f32 is just below 1e-6); and `normalmap`
//! gives unit normals at every scale it accepts.

use crate::common;

use aerial::scene::Scene;
use std::path::Path;

fn with_object(transform: &str) -> Result<Scene, aerial::scene::SceneError> {
    let toml = format!(
        "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         [[materials]]\nname = \"m\"\nkd = [0.5, 0.5, 0.5]\n\
         [[objects]]\nname = \"o\"\nmaterial = \"m\"\n\
         shape = {{ type = \"sphere\", radius = 1.0 }}\n{transform}\n"
    );
    Scene::from_toml(&toml, "bounds test", Path::new(env!("CARGO_MANIFEST_DIR")))
}

#[test]
fn scale_components_are_accepted_at_both_documented_bounds() {
    for scale in ["[1e-6, 1.0, 1.0]", "[1.0, 1e-6, 1e9]", "[1e9, 1e9, 1e9]"] {
        let scene = with_object(&format!("scale = {scale}"));
        assert!(scene.is_ok(), "scale = {scale}: {}", scene.unwrap_err());
    }
    for (scale, component) in [
        ("[9.99e-7, 1.0, 1.0]", "component 0"),
        ("[1.0, 1.0, 1.0001e9]", "component 2"),
    ] {
        let err = with_object(&format!("scale = {scale}"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("scale")
                && err.contains(component)
                && err.contains("between 1e-6 and 1e9"),
            "scale = {scale}: {err}"
        );
    }
    // Lengths share the bounds: a radius at each bound is accepted.
    for radius in ["1e-6", "1e9"] {
        let toml = format!(
            "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             [[materials]]\nname = \"m\"\nkd = [0.5, 0.5, 0.5]\n\
             [[objects]]\nname = \"o\"\nmaterial = \"m\"\n\
             shape = {{ type = \"sphere\", radius = {radius} }}\n"
        );
        let scene = Scene::from_toml(&toml, "bounds test", Path::new("."));
        assert!(scene.is_ok(), "radius = {radius}: {}", scene.unwrap_err());
    }
}

/// `earth_noon.toml` with `mie_g` set, at a small size.
fn earth_noon_with_mie_g(g: &str) -> Result<Scene, aerial::scene::SceneError> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let text = std::fs::read_to_string(dir.join("earth_noon.toml")).unwrap();
    assert!(!text.contains("mie_g"), "the example sets mie_g itself");
    let text = text.replace("[atmosphere]", &format!("[atmosphere]\nmie_g = {g}"));
    let mut scene = Scene::from_toml(&text, "earth_noon.toml with mie_g", &dir)?;
    scene.set_output_size(Some(48), Some(27)).unwrap();
    Ok(scene)
}

#[test]
fn mie_g_is_accepted_at_plus_and_minus_0_999_and_renders() {
    for g in ["0.999", "-0.999"] {
        let scene = earth_noon_with_mie_g(g).unwrap_or_else(|e| panic!("mie_g = {g}: {e}"));
        let run = common::render(&scene, true);
        let hdr = run.hdr.unwrap();
        assert!(
            hdr.data.iter().all(|v| v.is_finite()),
            "mie_g = {g}: a value that is not finite"
        );
        assert!(
            hdr.data
                .chunks_exact(4)
                .any(|p| p[..3].iter().any(|&c| c > 0.0)),
            "mie_g = {g}: a black sky"
        );
    }
    for g in ["0.9991", "-0.9991", "1.0"] {
        let err = earth_noon_with_mie_g(g).unwrap_err().to_string();
        assert!(
            err.contains("atmosphere.mie_g") && err.contains("between -0.999 and 0.999"),
            "mie_g = {g}: {err}"
        );
    }
}

#[test]
fn normalmap_gives_unit_normals_at_huge_scales() {
    let dir = tempfile::tempdir().unwrap();
    // A ramp along x: every texel has the same slope, 1/255 per texel.
    let (w, h) = (16u32, 4u32);
    let height = image::GrayImage::from_fn(w, h, |x, _| image::Luma([(x * 8) as u8]));
    let input = dir.path().join("ramp.png");
    height.save(&input).unwrap();
    for scale in ["1", "1e20", "1e30", "3.4e38"] {
        let out = dir.path().join(format!("n-{scale}.png"));
        common::succeed(
            common::aerial()
                .arg("normalmap")
                .arg(&input)
                .args(["--scale", scale, "--edge", "clamp", "--out"])
                .arg(&out),
        );
        let normals = image::open(&out).unwrap().to_rgba8();
        // Away from the clamped edges the slope is uniform.
        for x in 1..w - 1 {
            for y in 0..h {
                let p = normals.get_pixel(x, y).0;
                let n: Vec<f64> = p[..3]
                    .iter()
                    .map(|&c| f64::from(c) / 255.0 * 2.0 - 1.0)
                    .collect();
                let length = n.iter().map(|c| c * c).sum::<f64>().sqrt();
                // 8-bit encoding: each component within 1/255.
                assert!(
                    (length - 1.0).abs() < 0.02,
                    "scale {scale}, texel ({x}, {y}): {p:?} has length {length}"
                );
                if scale != "1" {
                    // The slope dominates: the normal lies flat, towards -x.
                    assert!(p[0] <= 1 && p[2] <= 129, "scale {scale}: {p:?}");
                }
            }
        }
    }
}
