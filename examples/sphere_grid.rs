//! Writes a scale-test scene: `N` identical spheres (default tessellation)
//! on a square grid one unit apart, one directional light, a camera that
//! sees the whole grid. For measuring how the renderer's cost follows the
//! object count (`docs/performance.md`, "Many objects").
//!
//! Run with `cargo run --example sphere_grid -- N OUT.toml [auto]`; with
//! `auto` every sphere has `tessellation = "auto"` (its grid chosen by
//! screen-space error, `docs/performance.md`).

use std::fmt::Write as _;

mod common;

fn main() {
    let common::ScaleArgs {
        count: n,
        out,
        tessellation,
    } = common::scale_args("sphere_grid", "N spheres on a square grid");
    let side = (n as f64).sqrt().ceil().max(1.0) as usize;
    let half = side as f64 / 2.0;
    let mut text = format!(
        "# {n} identical spheres on a {side}x{side} grid (written by the sphere_grid example).\n\
         [output]\nwidth = 640\nheight = 360\n\n\
         [camera]\neye = [0.0, {h:.1}, {d:.1}]\nlook_at = [0.0, 0.0, 0.0]\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [-0.3, -1.0, -0.5]\ncolor = [1.0, 1.0, 1.0]\n\n\
         [[materials]]\nname = \"clay\"\nkd = [0.7, 0.3, 0.2]\n",
        h = 0.6 * side as f64 + 2.0,
        d = 1.2 * side as f64 + 4.0,
    );
    for k in 0..n {
        let (i, j) = (k / side, k % side);
        let (x, z) = (i as f64 - half + 0.5, j as f64 - half + 0.5);
        write!(
            text,
            "\n[[objects]]\nname = \"sphere{k}\"\nmaterial = \"clay\"\n\
             shape = {{ type = \"sphere\", radius = 0.4 }}\ntranslate = [{x:.1}, 0.0, {z:.1}]\n\
             {tessellation}"
        )
        .expect("string write");
    }
    if let Err(e) = std::fs::write(&out, text) {
        eprintln!("cannot write {out}: {e}");
        std::process::exit(1);
    }
}
