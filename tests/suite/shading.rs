//! Shading models, culling, depth order and reversed-Z, each checked on a
//! rendered image under validation.

use crate::common;

use aerial::render::Pixels;

/// One sphere (radius 1 at the origin) lit by a point light near the view
/// direction, so the highlight faces the camera.
fn sphere_scene(shading: &str, tessellation: (u32, u32), ks: f32) -> String {
    format!(
        r#"
ambient = [0.05, 0.05, 0.05]
[output]
width = 128
height = 128
hdr_format = "rgba32f"
[camera]
eye = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
near = 0.1
far = 50.0
[[lights]]
type = "point"
position = [1.0, 1.0, 5.0]
color = [1.0, 1.0, 1.0]
intensity = 30.0
attenuation = [1.0, 0.0, 1.0]
[[materials]]
name = "m"
ka = [0.2, 0.2, 0.2]
kd = [0.5, 0.5, 0.6]
ks = [{ks}, {ks}, {ks}]
shininess = 60.0
shading = "{shading}"
[[objects]]
name = "ball"
material = "m"
shape = {{ type = "sphere", radius = 1.0 }}
tessellation = [{}, {}]
"#,
        tessellation.0, tessellation.1
    )
}

fn luminance(p: [f32; 4]) -> f64 {
    (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0
}

/// Per-pixel absolute difference statistics over pixels covered in both.
fn differences(a: &Pixels<f32>, b: &Pixels<f32>) -> (f64, f64) {
    let mut max: f64 = 0.0;
    let mut sum = 0.0;
    let mut n = 0usize;
    for (pa, pb) in a.data.chunks_exact(4).zip(b.data.chunks_exact(4)) {
        if pa[3] == 0.0 || pb[3] == 0.0 {
            continue;
        }
        let d = (0..3)
            .map(|c| (pa[c] - pb[c]).abs() as f64)
            .fold(0.0, f64::max);
        max = max.max(d);
        sum += d;
        n += 1;
    }
    (max, sum / n.max(1) as f64)
}

#[test]
fn gouraud_misses_the_highlight_on_a_coarse_mesh() {
    let phong = common::render(&common::scene(&sphere_scene("phong", (12, 6), 0.8)), true);
    let gouraud = common::render(&common::scene(&sphere_scene("gouraud", (12, 6), 0.8)), true);
    let (p, g) = (phong.hdr.unwrap(), gouraud.hdr.unwrap());
    let peak = |img: &Pixels<f32>| {
        img.data
            .chunks_exact(4)
            .map(|c| luminance([c[0], c[1], c[2], c[3]]))
            .fold(0.0, f64::max)
    };
    let (max_diff, _) = differences(&p, &g);
    // Per-pixel Phong reaches the highlight's peak between vertices; per-
    // vertex lighting interpolates it away on 12×6 quads.
    assert!(
        peak(&p) > peak(&g) + 0.2,
        "phong peak {} vs gouraud peak {}",
        peak(&p),
        peak(&g)
    );
    assert!(max_diff > 0.2, "images differ by at most {max_diff}");
}

#[test]
fn gouraud_and_phong_agree_on_a_dense_diffuse_mesh() {
    let phong = common::render(
        &common::scene(&sphere_scene("phong", (256, 128), 0.0)),
        true,
    );
    let gouraud = common::render(
        &common::scene(&sphere_scene("gouraud", (256, 128), 0.0)),
        true,
    );
    let (max_diff, mean_diff) = differences(&phong.hdr.unwrap(), &gouraud.hdr.unwrap());
    assert!(mean_diff < 2e-3, "mean difference {mean_diff}");
    assert!(max_diff < 0.03, "max difference {max_diff}");
}

#[test]
fn toon_has_black_silhouettes_and_lit_interior() {
    // Unattenuated light, so each tone is one value across the sphere.
    let toon = sphere_scene("toon", (128, 64), 0.3)
        .replace("width = 128\nheight = 128", "width = 256\nheight = 256")
        .replace(
            "intensity = 30.0\nattenuation = [1.0, 0.0, 1.0]",
            "intensity = 1.0\nattenuation = [1.0, 0.0, 0.0]",
        );
    let run = common::render(&common::scene(&toon), true);
    let hdr = run.hdr.unwrap();
    let (w, h) = (hdr.width, hdr.height);
    // Walk from the centre to the right along the middle row: the last
    // covered pixels before the background are the silhouette.
    let y = h / 2;
    let covered: Vec<u32> = (w / 2..w)
        .filter(|&x| common::pixel(&hdr, x, y)[3] > 0.0)
        .collect();
    let edge = *covered.last().expect("sphere covers the centre row");
    let rim = common::pixel(&hdr, edge, y);
    assert_eq!(
        &rim[..3],
        &[0.0, 0.0, 0.0],
        "silhouette pixel {edge} is {rim:?}"
    );
    let centre = common::pixel(&hdr, w / 2, y);
    assert!(luminance(centre) > 0.1, "centre is {centre:?}");
    // Two tones: the lit interior holds few distinct values.
    let mut tones: Vec<u32> = (0..w)
        .map(|x| common::pixel(&hdr, x, y))
        .filter(|p| p[3] > 0.0 && p[0] > 0.0)
        .map(|p| (p[0] * 1000.0) as u32)
        .collect();
    tones.sort_unstable();
    tones.dedup();
    assert!(
        tones.len() <= 4,
        "toon row has {} tones: {tones:?}",
        tones.len()
    );
}

/// Two planes facing the camera at `distance`, `gap` apart: red in front,
/// green behind, listed in `order`.
fn two_planes(distance: f64, gap: f64, near_first: bool, far: &str) -> String {
    let plane = |name: &str, z: f64| {
        format!(
            r#"
[[objects]]
name = "{name}"
material = "{name}"
shape = {{ type = "plane", width = {size}, depth = {size} }}
tessellation = [4, 4]
translate = [0.0, 0.0, {z}]
rotate = {{ axis = [1.0, 0.0, 0.0], degrees = 90.0 }}
"#,
            size = distance * 4.0
        )
    };
    let (front, back) = (plane("red", -distance), plane("green", -distance - gap));
    let objects = if near_first {
        front + &back
    } else {
        back + &front
    };
    format!(
        r#"
ambient = [1.0, 1.0, 1.0]
[output]
width = 64
height = 48
hdr_format = "rgba32f"
[camera]
eye = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
up = [0.0, 1.0, 0.0]
fov_y = 45.0
near = 0.1
{far}
[[materials]]
name = "red"
ka = [1.0, 0.0, 0.0]
kd = [0.0, 0.0, 0.0]
ks = [0.0, 0.0, 0.0]
shininess = 1.0
[[materials]]
name = "green"
ka = [0.0, 1.0, 0.0]
kd = [0.0, 0.0, 0.0]
ks = [0.0, 0.0, 0.0]
shininess = 1.0
{objects}"#
    )
}

fn all_red(p: &Pixels<f32>) -> bool {
    p.data.chunks_exact(4).all(|c| c[0] > 0.99 && c[1] < 0.01)
}

#[test]
fn nearer_surface_wins_in_either_draw_order() {
    for near_first in [true, false] {
        let run = common::render(
            &common::scene(&two_planes(10.0, 1.0, near_first, "far = 100.0")),
            true,
        );
        assert!(all_red(&run.hdr.unwrap()), "near_first = {near_first}");
    }
}

#[test]
fn reversed_z_separates_surfaces_one_metre_apart_at_a_million_metres() {
    // near = 0.1 with an infinite far plane: a near/far ratio no standard
    // depth buffer survives.
    for near_first in [true, false] {
        let run = common::render(
            &common::scene(&two_planes(1.0e6, 1.0, near_first, "")),
            true,
        );
        assert!(all_red(&run.hdr.unwrap()), "near_first = {near_first}");
    }
}

#[test]
fn back_faces_are_culled() {
    // From inside a closed sphere every triangle faces away: nothing is drawn.
    let inside = sphere_scene("phong", (32, 16), 0.5)
        .replace("eye = [0.0, 0.0, 4.0]", "eye = [0.0, 0.0, 0.2]");
    let run = common::render(&common::scene(&inside), true);
    let hdr = run.hdr.unwrap();
    assert!(
        hdr.data.chunks_exact(4).all(|c| c == [0.0; 4]),
        "something was drawn from inside the sphere"
    );
    // And from outside, the front faces are the ones drawn (lit from the front).
    let outside = common::render(&common::scene(&sphere_scene("phong", (32, 16), 0.5)), true);
    let hdr = outside.hdr.unwrap();
    assert!(luminance(common::pixel(&hdr, 64, 64)) > 0.3);
}

/// A white opaque wall with two transparent panes in front, listed in
/// `order`; lit by ambient light only, so each surface's colour is its ka.
fn panes(front_first: bool) -> String {
    let pane = |name: &str, z: f64| {
        format!(
            r#"
[[objects]]
name = "{name}"
material = "{name}"
shape = {{ type = "plane", width = 2.0, depth = 2.0 }}
tessellation = [4, 4]
translate = [0.0, 0.0, {z}]
rotate = {{ axis = [1.0, 0.0, 0.0], degrees = 90.0 }}
"#
        )
    };
    let (front, back) = (pane("red", -4.0), pane("blue", -5.0));
    let panes = if front_first {
        front + &back
    } else {
        back + &front
    };
    format!(
        r#"
ambient = [1.0, 1.0, 1.0]
[output]
width = 32
height = 32
hdr_format = "rgba32f"
[camera]
eye = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
fov_y = 10.0
near = 0.1
far = 100.0
[[materials]]
name = "white"
ka = [1.0, 1.0, 1.0]
kd = [0.0, 0.0, 0.0]
[[materials]]
name = "red"
ka = [1.0, 0.0, 0.0]
kd = [0.0, 0.0, 0.0]
opacity = 0.4
[[materials]]
name = "blue"
ka = [0.0, 0.0, 1.0]
kd = [0.0, 0.0, 0.0]
opacity = 0.5
{panes}
[[objects]]
name = "wall"
material = "white"
shape = {{ type = "plane", width = 50.0, depth = 50.0 }}
tessellation = [4, 4]
translate = [0.0, 0.0, -10.0]
rotate = {{ axis = [1.0, 0.0, 0.0], degrees = 90.0 }}
"#
    )
}

#[test]
fn transparent_objects_blend_back_to_front_in_any_scene_order() {
    // Straight alpha blending, back to front:
    // wall, then blue (a = 0.5), then red (a = 0.4) on top.
    let after_blue = [0.5 * 1.0, 0.5 * 1.0, 0.5 * 1.0 + 0.5 * 1.0];
    let expected = [
        0.4 * 1.0 + 0.6 * after_blue[0],
        0.6 * after_blue[1],
        0.6 * after_blue[2],
    ];
    for front_first in [true, false] {
        let run = common::render(&common::scene(&panes(front_first)), true);
        let hdr = run.hdr.unwrap();
        let got = common::pixel(&hdr, 16, 16);
        for c in 0..3 {
            assert!(
                (got[c] - expected[c]).abs() < 1e-3,
                "front_first = {front_first}: got {got:?}, expected {expected:?}"
            );
        }
    }
}

// Toon shading on a sphere, against a ray-traced oracle.
//
// A unit sphere at the origin seen from (0, 0, 4), lit by one directional
// light travelling along -Z (radiance 1), kd = 0.5, ks = 0.3, no ambient.
// Every visible point has N.L = N.z >= R/D = 0.25 (the silhouette circle
// lies at z = R^2/D), so it is lit: the diffuse tones are 0.5 (N.L > 0.5)
// and 0.2 (0.4 x 0.5, for 0 < N.L <= 0.5), the highlight adds 0.3, and the
// silhouette where |N.V| < 0.2 is black. Which pixels are in the silhouette
// ring follows from the exact ray-sphere intersection through each pixel
// centre; the scene is symmetric about the view axis, so the image's
// orientation does not matter.

const TOON_SIZE: u32 = 128;
const TOON_EYE: f64 = 4.0;
const TOON_FOV_DEG: f64 = 40.0;

/// |N.V| at the sphere point seen through pixel (x, y), or None if the
/// pixel's ray misses the unit sphere.
fn sphere_n_dot_v(x: u32, y: u32) -> Option<f64> {
    let half = (TOON_FOV_DEG.to_radians() / 2.0).tan();
    let px = ((x as f64 + 0.5) / TOON_SIZE as f64 * 2.0 - 1.0) * half;
    let py = ((y as f64 + 0.5) / TOON_SIZE as f64 * 2.0 - 1.0) * half;
    let len = (px * px + py * py + 1.0).sqrt();
    let d = [px / len, py / len, -1.0 / len];
    // |E + t d|^2 = 1 with E = (0, 0, D): t^2 + 2 t (E.d) + D^2 - 1 = 0.
    let b = TOON_EYE * d[2];
    let disc = b * b - (TOON_EYE * TOON_EYE - 1.0);
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    let p = [t * d[0], t * d[1], TOON_EYE + t * d[2]];
    // N = P (unit sphere), V = -d.
    Some((p[0] * d[0] + p[1] * d[1] + p[2] * d[2]).abs())
}

#[test]
fn toon_has_two_diffuse_tones_a_highlight_and_a_silhouette_of_the_right_width() {
    let toml = format!(
        r#"
[output]
width = {TOON_SIZE}
height = {TOON_SIZE}
hdr_format = "rgba32f"
[camera]
eye = [0.0, 0.0, {TOON_EYE}]
look_at = [0.0, 0.0, 0.0]
fov_y = {TOON_FOV_DEG}
[[lights]]
type = "directional"
direction = [0.0, 0.0, -1.0]
[[materials]]
name = "m"
kd = [0.5, 0.5, 0.5]
ka = [0.0, 0.0, 0.0]
ks = [0.3, 0.3, 0.3]
shininess = 60.0
shading = "toon"
[[objects]]
name = "ball"
material = "m"
shape = {{ type = "sphere", radius = 1.0 }}
tessellation = [256, 128]
"#
    );
    let run = common::render(&common::scene(&toml), true);
    let hdr = run.hdr.unwrap();

    // The only values on the sphere: black, the two tones, tone + highlight.
    let allowed = [0.0, 0.2, 0.5, 0.8];
    let mut seen = [0usize; 4];
    let (mut ring_expected, mut ring_rendered, mut wrong) = (0usize, 0usize, Vec::new());
    for y in 0..TOON_SIZE {
        for x in 0..TOON_SIZE {
            let p = common::pixel(&hdr, x, y);
            if p[3] == 0.0 {
                continue; // background: not covered by the mesh
            }
            let v = p[0] as f64;
            assert!(
                p[1] == p[0] && p[2] == p[0],
                "({x}, {y}) is not grey: {p:?}"
            );
            let k = allowed
                .iter()
                .position(|a| (v - a).abs() < 1e-4)
                .unwrap_or_else(|| panic!("({x}, {y}) = {v}: not one of {allowed:?}"));
            seen[k] += 1;
            let Some(n_dot_v) = sphere_n_dot_v(x, y) else {
                continue; // covered by a polygon, missed by the exact sphere
            };
            let black = k == 0;
            ring_expected += (n_dot_v < 0.2) as usize;
            ring_rendered += black as usize;
            // Within 0.02 of the threshold, the mesh's interpolated normals
            // may fall either way; elsewhere the classification is exact.
            if (n_dot_v - 0.2).abs() > 0.02 && black != (n_dot_v < 0.2) {
                wrong.push((x, y, n_dot_v, v));
            }
        }
    }
    assert!(wrong.is_empty(), "silhouette misclassified at {wrong:?}");
    // Each kind of pixel is present: ring, dark tone, bright tone, highlight.
    // (This also rules out a blank image: the sphere covers about a third
    // of the view.)
    assert!(seen.iter().all(|&n| n > 10), "pixel counts {seen:?}");
    assert!(seen.iter().sum::<usize>() > 4000, "pixel counts {seen:?}");
    // The ring's area matches |N.V| < 0.2 within 10 %.
    let ratio = ring_rendered as f64 / ring_expected as f64;
    eprintln!("toon: pixels {seen:?}, ring {ring_rendered} rendered, {ring_expected} predicted");
    assert!(
        (0.9..=1.1).contains(&ratio),
        "black ring {ring_rendered} pixels, |N.V| < 0.2 predicts {ring_expected}"
    );
}
