//! The CPU double-precision reference renderer against the GPU, and
//! `aerial sweep --reference cpu` converging as the tessellation grows.

use crate::common;

use aerial::render::render_on_cpu;
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
    let scene = common::scene(text);
    let gpu = common::render(&scene, true).hdr.unwrap();
    let cpu = render_on_cpu(&scene).unwrap();
    assert_eq!((gpu.width, gpu.height), (cpu.width, cpu.height));
    let covered =
        |x: u32, y: u32| common::pixel(&gpu, x, y)[3] > 0.0 && common::pixel(&cpu, x, y)[3] > 0.0;
    let mut checked = 0;
    for y in 1..cpu.height - 1 {
        for x in 1..cpu.width - 1 {
            if !(0..9).all(|i| covered(x + i % 3 - 1, y + i / 3 - 1)) {
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
