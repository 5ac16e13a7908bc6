//! Deferred lighting reads kd, ks and shininess from the G-buffer; forward
//! lighting reads them from the material. For every value a scene accepts
//! (kd and ks up to 1e6, and down to tiny non-zero values) the two must
//! agree within the bound `tests/suite/frame_graph.rs` documents for the example
//! scenes: linear HDR within a relative 0.5 %, 8-bit output within 2/255.
//! Before, the G-buffer was always 16-bit float (largest value 65504):
//! kd = 1e5 rendered 35 % darker deferred than forward, 1e6 93 % darker.
//!
//! The scenes scale the material by k and the light by 1/k, so every
//! render has the same, well-exposed brightness and any error in the
//! material's range shows at full size.

use crate::common;

use aerial::render::{plan, FramePlan, SceneGeometry};
use aerial::scene::Lighting;

fn scene(k: f64) -> aerial::scene::Scene {
    let light = 1.0 / k;
    common::scene(&format!(
        "ambient = [0, 0, 0]\n\
         light_cutoff = 0\n\
         [output]\nwidth = 96\nheight = 64\nhdr_format = \"rgba32f\"\n\
         [camera]\neye = [0, 0.5, 4]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
         [[lights]]\ntype = \"point\"\nposition = [2, 3, 3]\ncolor = [1, 0.9, 0.8]\n\
         intensity = {light:e}\nattenuation = [1, 0, 0.02]\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.5, -1, -0.3]\n\
         color = [0.3, 0.3, 0.4]\nintensity = {light:e}\n\
         [[materials]]\nname = \"m\"\nkd = [{kd:e}, {kd2:e}, {kd3:e}]\n\
         ks = [{ks:e}, {ks:e}, {ks:e}]\nshininess = 24\n\
         [[objects]]\nname = \"ball\"\nmaterial = \"m\"\n\
         shape = {{ type = \"sphere\", radius = 1.0 }}\ntessellation = [48, 24]\n",
        kd = k,
        kd2 = 0.6 * k,
        kd3 = 0.35 * k,
        ks = 0.3 * k,
    ))
}

fn check(k: f64, wide: bool) {
    let mut scene = scene(k);
    let geometry = SceneGeometry::new(&scene).unwrap();
    scene.output.lighting = Lighting::Deferred;
    let deferred_plan = FramePlan::new(&scene, &geometry, true);
    assert!(deferred_plan.pass_names().contains(&"lighting"));
    let deferred = common::render(&scene, true);
    scene.output.lighting = Lighting::Forward;
    let forward = common::render(&scene, true);
    common::assert_not_blank(&forward.output, 0.2);

    let (f, d) = (forward.hdr.unwrap(), deferred.hdr.unwrap());
    let mut worst_rel = 0.0f32;
    let mut lit = 0;
    for (pf, pd) in f.data.chunks_exact(4).zip(d.data.chunks_exact(4)) {
        lit += usize::from(pf[0] > 0.05);
        for c in 0..3 {
            let rel = (pf[c] - pd[c]).abs() / pf[c].abs().max(0.05);
            worst_rel = worst_rel.max(rel);
        }
    }
    let worst_ldr = forward
        .output
        .data
        .iter()
        .zip(&deferred.output.data)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    eprintln!(
        "kd scale {k:e}: forward vs deferred: relative HDR {worst_rel:.2e}, 8-bit {worst_ldr}/255, \
         {lit} lit pixels"
    );
    let expected = if wide {
        plan::WIDE_GBUFFER_FORMAT
    } else {
        plan::ALBEDO_FORMAT
    };
    assert_eq!(plan::gbuffer_format(&scene), expected, "kd scale {k:e}");
    assert!(lit > 500, "kd scale {k:e}: only {lit} lit pixels");
    assert!(
        worst_rel < 5e-3,
        "kd scale {k:e}: deferred differs from forward by a relative {worst_rel}"
    );
    assert!(
        worst_ldr <= 2,
        "kd scale {k:e}: 8-bit differs by {worst_ldr}/255"
    );
}

#[test]
fn kd_1_uses_the_16_bit_gbuffer_and_agrees() {
    check(1.0, false);
}

#[test]
fn kd_1e4_agrees() {
    check(1e4, false);
}

#[test]
fn kd_1e5_beyond_16_bit_floats_agrees() {
    check(1e5, true);
}

#[test]
fn kd_1e6_the_largest_accepted_agrees() {
    check(1e6, true);
}

#[test]
fn tiny_kd_below_16_bit_normals_agrees() {
    check(1e-6, true);
}
