//! Writes a scale-test scene of the kind instancing is for: a field of `N`
//! rocks (spheres squashed, turned and sized at random, three materials,
//! so three instanced draws) scattered over a ground plane, seen from its
//! edge at eye height, so most rocks are far away and many are outside the
//! view. The placement is a fixed pseudo-random sequence: the same `N`
//! writes the same file.
//!
//! Run with `cargo run --example instance_field -- N OUT.toml [auto]`;
//! `auto` gives every rock `tessellation = "auto"` (chosen by its size on
//! screen) instead of the default grid.

use std::fmt::Write as _;

/// A small deterministic generator (xorshift64*), so the file depends on
/// `N` alone.
struct Sequence(u64);

impl Sequence {
    /// The next number, uniform in [0, 1).
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The next number, uniform in [lo, hi).
    fn between(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

mod common;

fn main() {
    let common::ScaleArgs {
        count: n,
        out,
        tessellation,
    } = common::scale_args("instance_field", "N rocks on a field");
    // About two rocks per 10 square metres.
    let half = ((n as f64) * 5.0).sqrt().max(2.0) / 2.0;
    let mut text = format!(
        "# {n} rocks on a field {side:.0} m across (written by the instance_field example).\n\
         ambient = [0.05, 0.05, 0.06]\n\n\
         [output]\nwidth = 640\nheight = 360\n\n\
         [camera]\neye = [0.0, 1.7, {eye_z:.1}]\nlook_at = [0.0, 0.0, 0.0]\nnear = 0.1\nfar = {far:.0}\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [-0.4, -1.0, 0.3]\ncolor = [1.0, 0.95, 0.9]\n\n\
         [[materials]]\nname = \"ground\"\nkd = [0.35, 0.4, 0.3]\n\n\
         [[materials]]\nname = \"granite\"\nkd = [0.5, 0.5, 0.52]\nks = [0.2, 0.2, 0.2]\nshininess = 16\n\n\
         [[materials]]\nname = \"sandstone\"\nkd = [0.7, 0.5, 0.3]\n\n\
         [[materials]]\nname = \"basalt\"\nkd = [0.2, 0.2, 0.22]\nks = [0.3, 0.3, 0.3]\nshininess = 32\n\n\
         [[objects]]\nname = \"ground\"\nmaterial = \"ground\"\n\
         shape = {{ type = \"plane\", width = {side:.1}, depth = {side:.1} }}\ntessellation = [4, 4]\n",
        side = 2.0 * half + 4.0,
        eye_z = half + 1.0,
        far = 6.0 * half + 100.0,
    );
    let mut random = Sequence(0x9e37_79b9_7f4a_7c15);
    let materials = ["granite", "sandstone", "basalt"];
    for k in 0..n {
        let material = materials[k % materials.len()];
        let (x, z) = (random.between(-half, half), random.between(-half, half));
        let size = random.between(0.15, 0.6);
        let (sx, sy, sz) = (
            size * random.between(0.7, 1.3),
            size * random.between(0.4, 0.9),
            size * random.between(0.7, 1.3),
        );
        let turn = random.between(0.0, 360.0);
        write!(
            text,
            "\n[[objects]]\nname = \"rock{k}\"\nmaterial = \"{material}\"\n\
             shape = {{ type = \"sphere\", radius = 1.0 }}\n{tessellation}\
             translate = [{x:.3}, {y:.3}, {z:.3}]\n\
             rotate = {{ axis = [0.0, 1.0, 0.0], degrees = {turn:.1} }}\n\
             scale = [{sx:.3}, {sy:.3}, {sz:.3}]\n",
            y = 0.3 * sy,
        )
        .expect("string write");
    }
    if let Err(e) = std::fs::write(&out, text) {
        eprintln!("cannot write {out}: {e}");
        std::process::exit(1);
    }
}
