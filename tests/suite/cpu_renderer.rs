//! The CPU double-precision reference renderer against the GPU, and
//! `aerial sweep --reference cpu` converging as the tessellation grows.

use crate::common;

use aerial::render::render_on_cpu;
use aerial::scene::Scene;
use std::path::Path;

const SPHERE: &str = r#"
ambient = [0.1, 0.1, 0.1]
[output]
width = 160
height = 120
hdr_format = "rgba32f"
[camera]
eye = [0.3, 0.6, 4.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 100.0
[[lights]]
type = "point"
position = [2.0, 2.0, 3.0]
intensity = 8.0
attenuation = [1.0, 0.1, 0.05]
[[lights]]
type = "directional"
direction = [1.0, -0.5, -1.0]
color = [0.2, 0.25, 0.3]
[[materials]]
name = "m"
kd = [0.7, 0.4, 0.3]
ks = [0.5, 0.5, 0.5]
shininess = 30.0
[[objects]]
name = "ellipsoid"
material = "m"
shape = { type = "sphere", radius = 1.0 }
tessellation = [256, 128]
scale = [1.3, 0.9, 1.0]
rotate = { axis = [0.0, 0.0, 1.0], degrees = 20.0 }
"#;

/// Inside pixels (the whole 3×3 neighbourhood covered in both images) agree
/// within 0.004 + 1 % per channel: the GPU's tessellated surface lies within
/// about 3·10⁻⁴ of the analytic one at 256×128. Silhouette pixels are left
/// out: there polygon and exact outline cover different pixels, which is
/// the tessellation error a sweep measures, not a defect.
#[test]
fn the_cpu_reference_matches_the_gpu_inside_silhouettes() {
    gpu_matches_cpu_inside_silhouettes(SPHERE);
}

/// A whole-number shininess up to 1023 is raised to by multiplying
/// (specialization constant 4), any other with `pow`: both match the
/// reference's `powf`. Odd exponents use the lowest bit, 1023 every one.
#[test]
fn whole_number_and_fractional_shininess_match_the_reference() {
    for shininess in ["1.0", "7.0", "30.5", "97.0", "1023.0", "1024.0", "0.25"] {
        println!("shininess {shininess}");
        gpu_matches_cpu_inside_silhouettes(
            &SPHERE.replace("shininess = 30.0", &format!("shininess = {shininess}")),
        );
    }
}

fn gpu_matches_cpu_inside_silhouettes(text: &str) {
    gpu_matches_cpu_inside(&common::scene(text), |_, _| true);
}

/// [`gpu_matches_cpu_inside_silhouettes`] for `scene`, at the pixels
/// `compared` keeps.
fn gpu_matches_cpu_inside(scene: &Scene, compared: impl Fn(u32, u32) -> bool) {
    let gpu = common::render(scene, true).hdr.unwrap();
    let cpu = render_on_cpu(scene).unwrap();
    assert_eq!((gpu.width, gpu.height), (cpu.width, cpu.height));
    let covered =
        |x: u32, y: u32| common::pixel(&gpu, x, y)[3] > 0.0 && common::pixel(&cpu, x, y)[3] > 0.0;
    let mut checked = 0;
    for y in 1..cpu.height - 1 {
        for x in 1..cpu.width - 1 {
            if !(0..9).all(|i| covered(x + i % 3 - 1, y + i / 3 - 1)) || !compared(x, y) {
                continue;
            }
            let (g, c) = (common::pixel(&gpu, x, y), common::pixel(&cpu, x, y));
            for ch in 0..3 {
                let tolerance = 0.004 + 0.01 * c[ch];
                assert!(
                    (g[ch] - c[ch]).abs() <= tolerance,
                    "pixel ({x},{y}) channel {ch}: gpu {}, cpu {}",
                    g[ch],
                    c[ch]
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 2000, "only {checked} inside pixels");
}

/// A 3 m plane under a point light whose highlight spreads over a 4x4
/// specular map (`specular_map`), seen at an angle; texels drawn nearest,
/// the filter the reference samples with.
fn specular_plane(dir: &Path, lighting: &str, material: &str) -> Scene {
    let toml = format!(
        r#"
ambient = [0.05, 0.05, 0.05]
[output]
width = 160
height = 120
hdr_format = "rgba32f"
texture_filter = "nearest"
lighting = "{lighting}"
[camera]
eye = [0.4, 2.2, 2.6]
look_at = [0.0, 0.0, 0.0]
fov_y = 50.0
[[lights]]
type = "point"
position = [0.3, 1.2, 0.2]
intensity = 3.0
attenuation = [1.0, 0.1, 0.05]
[[materials]]
name = "m"
kd = [0.2, 0.25, 0.3]
shininess = 8.0
{material}
[[objects]]
name = "floor"
material = "m"
shape = {{ type = "plane", width = 3.0, depth = 3.0 }}
"#
    );
    Scene::from_toml(&toml, "specular map test", dir).unwrap_or_else(|e| panic!("{e}"))
}

/// Writes a 4x4 specular map at `path` whose texel (x, y) is `texel(x, y)`
/// (sRGB-encoded).
fn write_specular_map(path: &Path, texel: impl Fn(u32, u32) -> [u8; 3]) {
    image::RgbImage::from_fn(4, 4, |x, y| image::Rgb(texel(x, y)))
        .save(path)
        .unwrap();
}

/// A specular map multiplies ks texel by texel, decoded from sRGB: the GPU
/// (forward and deferred) matches the reference within its tolerance.
/// Pixels whose exact UV lies within 2 % of a texel from a texel edge are
/// left out: there a rounding of the GPU's interpolated UV may pick the
/// neighbouring texel, which is no error of the map.
#[test]
fn a_specular_map_matches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_specular_map(&d.join("spec.png"), |x, y| {
        [
            (40 + 60 * x) as u8,
            (255 - 50 * y) as u8,
            (90 + 30 * (x + y)) as u8,
        ]
    });
    for lighting in ["forward", "deferred"] {
        println!("{lighting}");
        let scene = specular_plane(
            d,
            lighting,
            "ks = [1.0, 0.9, 0.8]\nspecular_map = \"spec.png\"",
        );
        let off_texel_edges = |x: u32, y: u32| {
            let ray = common::pixel_ray(&scene, x, y);
            let eye = scene.camera.eye;
            let hit = eye + ray * (-eye.y / ray.y);
            let (u, v) = (hit.x / 3.0 + 0.5, 0.5 - hit.z / 3.0);
            let off_edge = |t: f64| {
                let f = (t * 4.0).fract();
                f > 0.02 && f < 0.98
            };
            off_edge(u) && off_edge(v)
        };
        gpu_matches_cpu_inside(&scene, off_texel_edges);
    }
}

/// A black specular map takes away the highlight the same material shows
/// without it, and leaves exactly the image of `ks = 0`: a renderer that
/// ignored the map would draw the highlight.
#[test]
fn a_black_specular_map_removes_the_highlight() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_specular_map(&d.join("black.png"), |_, _| [0, 0, 0]);
    for lighting in ["forward", "deferred"] {
        let render = |material: &str| {
            let scene = specular_plane(d, lighting, material);
            common::render(&scene, true).hdr.unwrap()
        };
        let shiny = render("ks = [1.0, 1.0, 1.0]");
        let black = render("ks = [1.0, 1.0, 1.0]\nspecular_map = \"black.png\"");
        let matte = render("ks = [0.0, 0.0, 0.0]");
        let mut highlight = 0.0f32;
        for i in 0..shiny.data.len() {
            highlight = highlight.max(shiny.data[i] - matte.data[i]);
            assert!(
                (black.data[i] - matte.data[i]).abs() <= 1e-5,
                "{lighting}: value {i}: black map {}, ks = 0 {}",
                black.data[i],
                matte.data[i]
            );
        }
        assert!(highlight > 0.3, "{lighting}: highlight {highlight}");
    }
}

#[test]
fn unsupported_features_are_named() {
    let torus = SPHERE.replace(
        r#"shape = { type = "sphere", radius = 1.0 }"#,
        r#"shape = { type = "torus", major_radius = 1.0, minor_radius = 0.3 }"#,
    );
    let err = render_on_cpu(&common::scene(&torus))
        .unwrap_err()
        .to_string();
    assert!(err.contains("ellipsoid") && err.contains("torus"), "{err}");
}

/// The RMSE column of `aerial sweep SCENE --reference cpu` over `knobs`
/// (one timed frame per combination, under validation), in row order.
fn sweep_rmse_against_cpu(tag: &str, scene: &str, knobs: &[&str]) -> Vec<f64> {
    let out = std::env::temp_dir().join(format!("aerial-cpuref-{tag}-{}", std::process::id()));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let mut command = common::aerial();
    command.arg("sweep").arg(&scene).args([
        "--reference",
        "cpu",
        "--validate",
        "--frames",
        "1",
        "--warmup",
        "0",
    ]);
    for knob in knobs {
        command.args(["--knob", knob]);
    }
    common::succeed(command.arg("--out-dir").arg(&out));
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    std::fs::remove_dir_all(&out).ok();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "rmse").unwrap();
    lines
        .map(|l| l.split(',').collect::<Vec<_>>()[col].parse().unwrap())
        .collect()
}

#[test]
fn sweep_error_against_the_cpu_reference_falls_with_tessellation() {
    let rmse = sweep_rmse_against_cpu(
        "sweep",
        "assets/sweep/spheres.toml",
        &["size=96x54", "tessellation=0.125,0.5,2"],
    );
    assert_eq!(rmse.len(), 3);
    assert!(
        rmse[0] > rmse[1] && rmse[1] > rmse[2] && rmse[2] > 0.0,
        "{rmse:?}"
    );
}

/// With `[atmosphere]` the CPU reference draws the sky with every order
/// of scattering (the f64 single-scattering integral plus a Monte Carlo
/// estimate of the rest), so the error of the atmosphere pass against it
/// falls with the march's sample count until the multiple-scattering
/// table's approximation and the reference's own noise floor it, and
/// single scattering alone (`multiple_scattering=off`) shows what the
/// missing orders cost.
#[test]
fn sweep_error_against_the_cpu_reference_falls_with_atmosphere_samples() {
    let rmse = sweep_rmse_against_cpu(
        "sky",
        "assets/scenes/earth_sunset.toml",
        &[
            "size=32x18",
            "multiple_scattering=off,on",
            "atmosphere_samples=2,32",
        ],
    );
    // Rows: (off, 2), (off, 32), (on, 2), (on, 32).
    assert_eq!(rmse.len(), 4);
    println!("{rmse:?}");
    let (off_32, on_2, on_32) = (rmse[1], rmse[2], rmse[3]);
    // Measured: 7.0e-3 at 2 samples, 9.7e-4 at 32 with every order;
    // 2.5e-3 at 32 with single scattering.
    assert!(on_2 > 4.0 * on_32 && on_32 > 0.0, "{rmse:?}");
    assert!(off_32 > 2.0 * on_32, "{rmse:?}");
}
