//! Writes the model assets of the example scenes into `assets/models/`:
//!
//! - `cut_torus.obj` + `.mtl`: a torus cut along parameter lines into four
//!   objects, each repeating its boundary vertices (how multi-object files
//!   arrive from exporters), with UVs tiled so the normal map repeats, and
//!   no normals (so the loader smooths it across the cuts);
//! - `cut_sphere.obj`: a coarse sphere cut the same way, for comparing the
//!   smoothing modes;
//! - `bumps.png`: a tangent-space normal map (green up) of a field of round
//!   bumps, derived analytically from its height function.
//!
//! Run with `cargo run --example make_model_assets`; the outputs are
//! deterministic, so re-running reproduces the committed files.
//!
//! With `--cut-torus DIR [N,N,...]` it writes instead the benchmark models
//! of `docs/mesh-performance.md` into `DIR`, as `torus<N>.obj` for N
//! triangles (default 10000,100000,1000000): the same torus on a 4v x v
//! grid, v = sqrt(N / 8), cut into 8 objects along u, with UVs and no
//! normals. They are too large to commit.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::Path;

/// Writes `surface` sampled on a `segments` grid as `cuts.0 x cuts.1`
/// objects; `uv_repeat` scales the texture coordinates.
fn grid_obj(
    header: &str,
    surface: impl Fn(f64, f64) -> [f64; 3],
    segments: (u32, u32),
    cuts: (u32, u32),
    uv_repeat: (f64, f64),
) -> String {
    let mut text = String::from(header);
    let mut base = 1;
    for cu in 0..cuts.0 {
        for cv in 0..cuts.1 {
            writeln!(text, "o part_{cu}_{cv}").unwrap();
            let (i0, i1) = (segments.0 * cu / cuts.0, segments.0 * (cu + 1) / cuts.0);
            let (j0, j1) = (segments.1 * cv / cuts.1, segments.1 * (cv + 1) / cuts.1);
            let cols = i1 - i0 + 1;
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let (u, v) = (
                        f64::from(i) / f64::from(segments.0),
                        f64::from(j) / f64::from(segments.1),
                    );
                    // Exact zeros at poles and seams, so that pole
                    // triangles collapse exactly.
                    let p = surface(u, v).map(|x| if x.abs() < 1e-9 { 0.0 } else { x });
                    writeln!(text, "v {:.6} {:.6} {:.6}", p[0], p[1], p[2]).unwrap();
                    writeln!(text, "vt {:.6} {:.6}", u * uv_repeat.0, v * uv_repeat.1).unwrap();
                }
            }
            for j in 0..j1 - j0 {
                for i in 0..cols - 1 {
                    let a = base + j * cols + i;
                    let (b, c, d) = (a + 1, a + cols + 1, a + cols);
                    writeln!(text, "f {a}/{a} {b}/{b} {c}/{c}").unwrap();
                    writeln!(text, "f {a}/{a} {c}/{c} {d}/{d}").unwrap();
                }
            }
            base += cols * (j1 - j0 + 1);
        }
    }
    text
}

/// Torus around Y, major radius 1, minor 0.4; (u, v) -> outward is
/// counter-clockwise.
fn torus(u: f64, v: f64) -> [f64; 3] {
    let (phi, theta) = (u * TAU, v * TAU);
    let r = 1.0 + 0.4 * theta.cos();
    [r * phi.cos(), 0.4 * theta.sin(), -r * phi.sin()]
}

/// Unit sphere, v = 0 at the south pole.
fn sphere(u: f64, v: f64) -> [f64; 3] {
    let (phi, theta) = (u * TAU, v * PI);
    [
        theta.sin() * phi.cos(),
        -theta.cos(),
        -theta.sin() * phi.sin(),
    ]
}

/// Normal map of round bumps: height h = cos^2 of the distance to the cell
/// centre (zero outside radius r), normal = normalize(-S dh/dx, -S dh/dy, 1)
/// with y up the image.
fn bumps(size: u32) -> image::RgbaImage {
    let cells = 4.0;
    let radius = 0.35;
    let strength = 0.6;
    image::RgbaImage::from_fn(size, size, |x, y| {
        // Texel centre in [0, 1), y pointing up the image.
        let fx = (f64::from(x) + 0.5) / f64::from(size) * cells;
        let fy = (f64::from(size - 1 - y) + 0.5) / f64::from(size) * cells;
        let (dx, dy) = (fx.fract() - 0.5, fy.fract() - 0.5);
        let d = (dx * dx + dy * dy).sqrt();
        let (gx, gy) = if d < radius && d > 0.0 {
            // h = cos^2(k d) with k = pi / 2r, so dh/dd = -k sin(2 k d);
            // the gradient points along (dx, dy) / d.
            let k = PI / (2.0 * radius);
            let dh = -k * (2.0 * k * d).sin();
            (dh * dx / d, dh * dy / d)
        } else {
            (0.0, 0.0)
        };
        let n = [-strength * gx, -strength * gy, 1.0];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let texel = n.map(|c| ((0.5 + 0.5 * c / len) * 255.0).round() as u8);
        image::Rgba([texel[0], texel[1], texel[2], 255])
    })
}

/// The benchmark tori (`--cut-torus DIR [SIZES]`).
fn write_cut_tori(dir: &Path, sizes: &str) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    for n in sizes.split(',') {
        let n: u32 = n
            .trim()
            .parse()
            .map_err(|e| std::io::Error::other(format!("triangle count {n:?}: {e}")))?;
        let v = (f64::from(n / 8)).sqrt().round() as u32;
        let text = grid_obj(
            "# made by examples/make_model_assets.rs --cut-torus\n",
            torus,
            (4 * v, v),
            (8, 1),
            (1.0, 1.0),
        );
        std::fs::write(dir.join(format!("torus{n}.obj")), text)?;
    }
    Ok(())
}

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--cut-torus") {
        let Some(dir) = args.get(1) else {
            return Err(std::io::Error::other("usage: --cut-torus DIR [N,N,...]"));
        };
        let sizes = args.get(2).map_or("10000,100000,1000000", String::as_str);
        return write_cut_tori(Path::new(dir), sizes);
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models");
    std::fs::create_dir_all(&dir)?;
    let header = "# made by examples/make_model_assets.rs\n";
    std::fs::write(
        dir.join("cut_torus.obj"),
        grid_obj(
            &format!("{header}mtllib cut_torus.mtl\nusemtl bumpy\n"),
            torus,
            (48, 24),
            (4, 1),
            (6.0, 2.0),
        ),
    )?;
    std::fs::write(
        dir.join("cut_torus.mtl"),
        format!("{header}newmtl bumpy\nKd 0.75 0.45 0.2\nKs 0.4 0.4 0.4\nNs 48\nnorm bumps.png\n"),
    )?;
    std::fs::write(
        dir.join("cut_sphere.obj"),
        grid_obj(header, sphere, (24, 12), (4, 2), (1.0, 1.0)),
    )?;
    bumps(128)
        .save(dir.join("bumps.png"))
        .map_err(std::io::Error::other)?;
    Ok(())
}
