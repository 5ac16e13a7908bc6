//! Normal maps, checked against geometry: a flat surface whose map tilts
//! every normal by an angle must shade like the same surface without a map,
//! rotated by that angle (a directional light and a diffuse material make
//! the colour depend only on the normal). This ties together the tangent
//! frame (T along +u, B along +v), the handedness of mirrored UVs, the
//! green-channel convention, linear (not sRGB) decoding, and the forward
//! and deferred paths. Every render runs under validation.

use crate::common;

use std::path::Path;

use aerial::scene::material_maps::MapKind;
use aerial::scene::Scene;

const TILT_DEGREES: f32 = 30.0;

/// A 4x4 normal map whose every texel is the tangent-space direction
/// `(x, y, z)` stored as `0.5 + 0.5 c`.
fn write_map(path: &Path, c: [f32; 3]) {
    let texel = c.map(|x| ((0.5 + 0.5 * x) * 255.0).round() as u8);
    let img = image::RgbaImage::from_fn(4, 4, |_, _| {
        image::Rgba([texel[0], texel[1], texel[2], 255])
    });
    img.save(path).unwrap();
}

/// A unit quad in the XZ plane facing +Y; `mirrored` reverses u, so that
/// the tangent runs along -X with handedness -1.
fn write_quad(path: &Path, mirrored: bool) {
    let (u0, u1) = if mirrored { (1, 0) } else { (0, 1) };
    let text = format!(
        "v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n\
         vt {u0} 0\nvt {u1} 0\nvt {u1} 1\nvt {u0} 1\n\
         f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
    );
    std::fs::write(path, text).unwrap();
}

use common::tilt_scene as scene;

use common::assert_close;

#[test]
fn mapped_tilt_matches_rotated_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (s, c) = TILT_DEGREES.to_radians().sin_cos();
    write_map(&d.join("tilt_t.png"), [s, 0.0, c]); // towards +T
    write_map(&d.join("tilt_b.png"), [0.0, s, c]); // towards +B
    write_quad(&d.join("quad.obj"), false);
    write_quad(&d.join("mirrored.obj"), true);
    let plane = "{ type = \"plane\", width = 2, depth = 2 }";
    let quad = "{ type = \"obj\", path = \"quad.obj\" }";
    let mirrored = "{ type = \"obj\", path = \"mirrored.obj\" }";
    let map = |file: &str| format!("normal_map = \"{file}\"");
    let render = |s: &Scene| common::centre_rgb(&common::render(s, false).output);

    for lighting in ["forward", "deferred"] {
        let flat = render(&scene(d, lighting, "", plane, 0.0));
        // Rotating +Y towards +X is a negative turn about +Z.
        let turned_x = render(&scene(d, lighting, "", plane, -TILT_DEGREES));
        let turned_back = render(&scene(d, lighting, "", plane, TILT_DEGREES));
        assert!(
            (turned_x[0] - flat[0]).abs() > 10.0 && (turned_back[0] - flat[0]).abs() > 10.0,
            "{lighting}: the tilt must change the shading: {flat:?} {turned_x:?} {turned_back:?}"
        );
        // Parametric plane: T = +X.
        let mapped = render(&scene(d, lighting, &map("tilt_t.png"), plane, 0.0));
        assert_close(
            mapped,
            turned_x,
            &format!("{lighting}: plane, map towards +T"),
        );
        // OBJ quad: u along +X, so T = +X as well.
        let mapped = render(&scene(d, lighting, &map("tilt_t.png"), quad, 0.0));
        assert_close(
            mapped,
            turned_x,
            &format!("{lighting}: obj quad, map towards +T"),
        );
        // Mirrored UVs: T = -X with handedness -1, so the same map tilts
        // the other way.
        let mapped = render(&scene(d, lighting, &map("tilt_t.png"), mirrored, 0.0));
        assert_close(mapped, turned_back, &format!("{lighting}: mirrored quad"));
    }

    // B: on the plane B = -Z (v grows towards -Z), so a map towards +B
    // equals turning +Y towards -Z: a negative turn about +X. With green
    // down the same texels tilt towards -B, i.e. +Z.
    let toml_b = |material: &str, axis: &str, degrees: f32| {
        let toml = format!(
            "ambient = [0.05, 0.05, 0.05]\n[output]\nwidth = 48\nheight = 48\n\
             [camera]\neye = [0, 4, 0]\nlook_at = [0, 0, 0]\nup = [0, 0, -1]\nfov_y = 30\n\
             [tone_map]\noperator = \"none\"\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0.3, -1, 0.6]\nintensity = 0.8\n\
             [[materials]]\nname = \"m\"\nkd = [0.8, 0.8, 0.8]\n{material}\n\
             [[objects]]\nname = \"o\"\nmaterial = \"m\"\nshape = {plane}\n\
             rotate = {{ axis = {axis}, degrees = {degrees} }}\n"
        );
        Scene::from_toml(&toml, "normal_maps test", d).unwrap()
    };
    let towards_minus_z = render(&toml_b("", "[1, 0, 0]", -TILT_DEGREES));
    let towards_plus_z = render(&toml_b("", "[1, 0, 0]", TILT_DEGREES));
    assert!((towards_minus_z[0] - towards_plus_z[0]).abs() > 10.0);
    let up = render(&toml_b(&map("tilt_b.png"), "[1, 0, 0]", 0.0));
    assert_close(up, towards_minus_z, "green up");
    let down = render(&toml_b(
        &format!("{}\nnormal_map_green = \"down\"", map("tilt_b.png")),
        "[1, 0, 0]",
        0.0,
    ));
    assert_close(down, towards_plus_z, "green down");
}

/// A flat map (0.5, 0.5, 1) changes nothing; textured and normal-mapped
/// materials together (two image sets) render clean.
#[test]
fn flat_map_is_identity_and_textured_maps_render_clean() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(&d.join("flat.png"), [0.0, 0.0, 1.0]);
    let plane = "{ type = \"plane\", width = 2, depth = 2 }";
    let render = |s: &Scene| common::centre_rgb(&common::render(s, false).output);
    let without = render(&scene(d, "forward", "", plane, 10.0));
    let with = render(&scene(
        d,
        "forward",
        "normal_map = \"flat.png\"",
        plane,
        10.0,
    ));
    assert_close(with, without, "flat map");
    let checker = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/checker.png");
    std::fs::copy(checker, d.join("checker.png")).unwrap();
    for lighting in ["forward", "deferred"] {
        let s = scene(
            d,
            lighting,
            "texture = \"checker.png\"\nnormal_map = \"flat.png\"",
            plane,
            10.0,
        );
        common::assert_not_blank(&common::render(&s, false).output, 0.1);
    }
}

/// Bad normal-map input is an error naming the field or the group.
#[test]
fn normal_map_errors_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let plane = "{ type = \"plane\", width = 2, depth = 2 }";
    let attempt = |material: &str, shape: &str| {
        let toml = format!(
            "[camera]\neye = [0, 4, 1]\nlook_at = [0, 0, 0]\n\
             [[materials]]\nname = \"m\"\nkd = [1, 1, 1]\n{material}\n\
             [[objects]]\nname = \"o\"\nmaterial = \"m\"\nshape = {shape}\n"
        );
        Scene::from_toml(&toml, "t.toml", d)
            .unwrap_err()
            .to_string()
    };
    let e = attempt("normal_map = \"missing.png\"", plane);
    assert!(e.contains("materials[0].normal_map: file not found"), "{e}");
    let e = attempt("normal_map_green = \"down\"", plane);
    assert!(e.contains("materials[0].normal_map_green"), "{e}");
    write_map(&d.join("flat.png"), [0.0, 0.0, 1.0]);
    std::fs::write(d.join("no_uv.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let e = attempt(
        "normal_map = \"flat.png\"",
        "{ type = \"obj\", path = \"no_uv.obj\" }",
    );
    assert!(e.contains("without texture coordinates"), "{e}");
}

/// Only objects whose material has a normal map take the `NORMAL_MAP`
/// variant, and a map shared by two materials is loaded once.
#[test]
fn plan_uses_the_normal_map_variant_only_where_needed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(&d.join("flat.png"), [0.0, 0.0, 1.0]);
    let toml = "[camera]\neye = [0, 4, 6]\nlook_at = [0, 0, 0]\n\
         [[materials]]\nname = \"a\"\nkd = [1, 1, 1]\nnormal_map = \"flat.png\"\n\
         [[materials]]\nname = \"b\"\nkd = [1, 0, 0]\nnormal_map = \"flat.png\"\n\
         [[materials]]\nname = \"plain\"\nkd = [0, 1, 0]\n\
         [[objects]]\nname = \"x\"\nmaterial = \"a\"\nshape = { type = \"sphere\", radius = 1 }\n\
         [[objects]]\nname = \"y\"\nmaterial = \"b\"\nshape = { type = \"sphere\", radius = 1 }\n\
         [[objects]]\nname = \"z\"\nmaterial = \"plain\"\nshape = { type = \"sphere\", radius = 1 }\n";
    let scene = Scene::from_toml(toml, "t.toml", d).unwrap();
    let geometry = aerial::render::geometry::SceneGeometry::new(&scene).unwrap();
    let plan = aerial::render::FramePlan::new(&scene, &geometry, false);
    assert_eq!(plan.maps.len(), 1);
    for draw in plan.draws() {
        let mapped = scene.objects[draw.object].material != 2;
        assert_eq!(
            draw.pipeline.maps.contains(MapKind::Normal),
            mapped,
            "{draw:?}"
        );
        assert_eq!(
            draw.maps[MapKind::Normal as usize].is_some(),
            mapped,
            "{draw:?}"
        );
    }
}

/// A normal map that is not a PNG is refused before rendering, naming the
/// file (the same checks as base-colour textures).
#[test]
fn non_png_normal_map_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("map.jpg"),
        [0xFF, 0xD8, 0xFF, 0xE0, 0, 0x10, b'J', b'F'],
    )
    .unwrap();
    let s = scene(
        d,
        "forward",
        "normal_map = \"map.jpg\"",
        "{ type = \"plane\", width = 2, depth = 2 }",
        0.0,
    );
    let error = match aerial::render_run::render(&s, &common::validated_settings()) {
        Ok(_) => panic!("a JPEG normal map rendered"),
        Err(e) => e.to_string(),
    };
    assert!(
        error.contains("map.jpg") && error.contains("JPEG"),
        "{error}"
    );
}

/// A hostile model — collapsed, repeated and mirrored UVs, repeated
/// corners, slivers — normal-mapped, forward and deferred: validation-clean
/// and no NaN or Inf in the linear HDR image.
#[test]
fn stress_model_with_normal_map_renders_finite_and_clean() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(&d.join("tilt.png"), [0.5, -0.3, 0.81]);
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut text = String::new();
    for _ in 0..10 {
        let p = [next(), next(), next()].map(|x| x * 2.0 - 1.0);
        text.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    // Few distinct UVs, one repeated: zero-UV-area triangles are common.
    for uv in ["0 0", "1 0", "0 1", "1 0", "0.5 0.5"] {
        text.push_str(&format!("vt {uv}\n"));
    }
    for _ in 0..80 {
        let corner = |n: &mut dyn FnMut() -> f32| {
            let v = (n() * 10.0) as usize % 10 + 1;
            let t = (n() * 5.0) as usize % 5 + 1;
            format!("{v}/{t}")
        };
        let (a, b, c) = (corner(&mut next), corner(&mut next), corner(&mut next));
        text.push_str(&format!("f {a} {b} {c}\n"));
    }
    std::fs::write(d.join("stress.obj"), text).unwrap();
    for lighting in ["forward", "deferred"] {
        let s = scene(
            d,
            lighting,
            "normal_map = \"tilt.png\"",
            "{ type = \"obj\", path = \"stress.obj\" }",
            0.0,
        );
        let run = common::render(&s, true);
        let hdr = run.hdr.expect("HDR kept");
        assert!(
            hdr.data.iter().all(|x| x.is_finite()),
            "{lighting}: non-finite HDR"
        );
        for i in 0..s.objects.len() {
            let mesh = s.object_mesh(i);
            assert!(aerial::mesh::tangents::max_orthonormality_error(&mesh) < 1e-5);
        }
    }
}

/// A 16-bit normal map keeps its precision (stored as 16-bit UNORM): a
/// 30-degree tilt shades like the turned plane in the linear HDR image to
/// a relative 2e-4 (measured: equal in the 16-bit float HDR target), where
/// the same map in 8 bits is off by 7e-4 (its directions are quantized to
/// about 0.2 degrees).
#[test]
fn sixteen_bit_normal_maps_keep_their_precision() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // An angle whose sine and cosine fall between 8-bit steps.
    let tilt = 27.3f32;
    let (s, c) = tilt.to_radians().sin_cos();
    let texel16 = [s, 0.0, c].map(|x| ((0.5 + 0.5 * x) * 65535.0).round() as u16);
    image::ImageBuffer::<image::Rgba<u16>, Vec<u16>>::from_fn(4, 4, |_, _| {
        image::Rgba([texel16[0], texel16[1], texel16[2], 65535])
    })
    .save(d.join("tilt16.png"))
    .unwrap();
    write_map(&d.join("tilt8.png"), [s, 0.0, c]);
    let plane = "{ type = \"plane\", width = 2, depth = 2 }";
    let hdr_centre = |scene: &Scene| {
        let run = common::render(scene, true);
        let hdr = run.hdr.unwrap();
        let p = common::pixel(&hdr, 24, 24);
        Vec::from(&p[..3])
    };
    let turned = hdr_centre(&scene(d, "forward", "", plane, -tilt));
    let error = |file: &str| {
        let mapped = hdr_centre(&scene(
            d,
            "forward",
            &format!("normal_map = \"{file}\""),
            plane,
            0.0,
        ));
        mapped
            .iter()
            .zip(&turned)
            .map(|(m, t)| ((m - t) / t).abs())
            .fold(0.0f32, f32::max)
    };
    let (e16, e8) = (error("tilt16.png"), error("tilt8.png"));
    println!("relative error of the mapped tilt: 16-bit {e16:.2e}, 8-bit {e8:.2e}");
    assert!(e16 < 2e-4, "16-bit map: {e16}");
    assert!(e16 < e8, "16 bits must beat 8: {e16} vs {e8}");
}

/// Gouraud lights per vertex, so a normal or height map cannot change its
/// lighting: the map is left out with a warning naming the field (an error
/// under `--strict`), the render is clean under validation (no stage
/// writes a tangent the next does not read), and the image equals the
/// same Gouraud material without the map, forward and deferred, with and
/// without a base-colour texture. Set through the `shading` knob, the same
/// warning names the knob.
#[test]
fn gouraud_leaves_maps_out_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(&d.join("tilt.png"), [0.5, 0.0, 0.866]);
    let ramp = image::GrayImage::from_fn(8, 8, |x, _| image::Luma([(x * 30) as u8]));
    ramp.save(d.join("ramp.png")).unwrap();
    let checker = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/checker.png");
    std::fs::copy(checker, d.join("checker.png")).unwrap();
    let sphere = "{ type = \"sphere\", radius = 1 }";
    let maps = [
        ("normal_map", "normal_map = \"tilt.png\""),
        (
            "height_map",
            "height_map = \"ramp.png\"\nheight_scale = 0.2",
        ),
    ];
    for (field, map) in maps {
        for lighting in ["forward", "deferred"] {
            for texture in ["", "texture = \"checker.png\"\n"] {
                let plain = format!("shading = \"gouraud\"\n{texture}");
                let without = scene(d, lighting, &plain, sphere, 0.0);
                assert!(without.warnings.is_empty());
                let with = scene(d, lighting, &format!("{plain}{map}"), sphere, 0.0);
                let what = format!("{field}, {lighting}, texture {:?}", texture);
                assert_eq!(with.warnings.len(), 1, "{what}");
                let w = &with.warnings[0];
                assert_eq!(w.field, format!("materials[0].{field}"), "{what}");
                assert!(w.to_string().contains("gouraud"), "{what}: {w}");
                assert!(with.strict().is_err(), "{what}");
                let plan_of = |s: &Scene| {
                    let g = aerial::render::geometry::SceneGeometry::new(s).unwrap();
                    aerial::render::FramePlan::new(s, &g, false)
                };
                let plan = plan_of(&with);
                assert!(
                    plan.maps.iter().all(|(kind, _)| *kind != MapKind::Normal),
                    "{what}"
                );
                let a = common::render(&with, false).output;
                let b = common::render(&without, false).output;
                common::assert_not_blank(&a, 0.1);
                assert!(a.data == b.data, "{what}: the map changed a Gouraud image");
            }
        }
    }
    // The knob sets Gouraud on a Phong material that has a map.
    let mut phong = scene(d, "forward", maps[0].1, sphere, 0.0);
    assert!(phong.warnings.is_empty());
    aerial::scene::Knob::find("shading")
        .unwrap()
        .set(&mut phong, "gouraud")
        .unwrap();
    assert_eq!(phong.warnings.len(), 1);
    assert!(phong.warnings[0]
        .to_string()
        .contains("--knob shading=gouraud"));
    common::assert_not_blank(&common::render(&phong, false).output, 0.1);
}
