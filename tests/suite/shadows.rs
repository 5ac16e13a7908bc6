//! Shadows (`shadows = true` on a directional light): the shadow pass
//! draws the casters from the light into a map of its own size, in its own
//! render pass, and the surfaces look it up. Checked against closed forms:
//! the shadow of a sphere on a plane is an ellipse of known area; a plane
//! with nothing over it is lit as without shadows; the frame holds the pass
//! and the map only when asked; bad values are errors naming the field.
//! Every render runs under validation (core, synchronization, best
//! practices).

use crate::common;

use aerial::render::passes::shadow_map;
use aerial::render::plan::attachment;
use aerial::render::{FramePlan, Pixels, SceneGeometry};
use aerial::scene::{Scene, KNOBS};

/// Light travelling at `tilt` degrees from straight down, towards +x.
fn light_direction(tilt: f64) -> [f64; 3] {
    let t = tilt.to_radians();
    [t.sin(), -t.cos(), 0.0]
}

/// A plane at y = 0 seen from straight above (camera at height `height`,
/// `fov` degrees, image rows along -z), lit by a directional light at
/// `tilt` degrees with `shadows`, and `extra` objects.
fn top_view(width: u32, shadows: bool, tilt: f64, filter: &str, extra: &str) -> Scene {
    let [dx, dy, dz] = light_direction(tilt);
    common::scene(&format!(
        "ambient = [0.1, 0.1, 0.1]\n\
         [output]\nwidth = {width}\nheight = {h}\nhdr_format = \"rgba32f\"\n\
         shadow_map = 2048\nshadow_filter = \"{filter}\"\n\
         [camera]\neye = [1.0, 10.0, 0.0]\nlook_at = [1.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
         fov_y = 30.0\n\
         [[lights]]\ntype = \"directional\"\ndirection = [{dx}, {dy}, {dz}]\nshadows = {shadows}\n\
         [[materials]]\nname = \"ground\"\nkd = [0.8, 0.8, 0.8]\n\
         [[materials]]\nname = \"ball\"\nkd = [0.8, 0.3, 0.2]\n\
         [[objects]]\nname = \"ground\"\nmaterial = \"ground\"\n\
         shape = {{ type = \"plane\", width = 12.0, depth = 12.0 }}\ntessellation = [8, 8]\n\
         {extra}",
        h = width * 9 / 16,
    ))
}

const BALL: &str = "[[objects]]\nname = \"ball\"\nmaterial = \"ball\"\n\
                    shape = { type = \"sphere\", radius = 0.5 }\ntessellation = [128, 64]\n\
                    translate = [0.0, 1.5, 0.0]\n";

fn hdr(scene: &Scene) -> Pixels<f32> {
    common::render(scene, true)
        .hdr
        .expect("the HDR image is kept")
}

/// The shadowed area in world units: each pixel's missing fraction of the
/// light, `1 - (shadowed - ambient) / (lit - ambient)` in the red channel,
/// summed over the pixels that the light reaches without shadows, times
/// the world area a pixel covers on the plane (which faces the camera).
fn shadow_area(with: &Pixels<f32>, without: &Pixels<f32>, ambient: f32, pixel_area: f64) -> f64 {
    let mut missing = 0.0f64;
    for (on, off) in with.data.chunks_exact(4).zip(without.data.chunks_exact(4)) {
        let lit = off[0] - ambient;
        if lit > 1e-3 {
            missing += f64::from(1.0 - ((on[0] - ambient) / lit).clamp(0.0, 1.0));
        }
    }
    missing * pixel_area
}

/// A sphere of radius r = 0.5 at height 1.5 over the plane, the light 45
/// degrees from vertical: the shadow is an ellipse with semi-axes r (across
/// the light) and r / cos 45° (along it), area pi r^2 / cos 45° = 1.1107,
/// beside the sphere as the camera above sees it (the sphere hides none of
/// it). The map's shadow (2048 texels, PCF 3x3) covers that area within
/// 2 %. Left out by the closed form: nothing (the sun is a direction, so
/// the shadow is sharp); the rendered sphere is a 128x64 polygon (0.1 %
/// less area).
#[test]
fn a_sphere_casts_the_ellipse_of_the_closed_form() {
    ellipse_area_within_two_percent(None);
}

/// The same with the view split into 2 and 4 cascades, each in its tile of
/// the map: the plane under the sphere reaches into every cascade.
#[test]
fn cascades_cast_the_same_ellipse() {
    for count in [2, 4] {
        ellipse_area_within_two_percent(Some(count));
    }
}

fn ellipse_area_within_two_percent(cascades: Option<u32>) {
    let width = 1280;
    let scene = |shadows: bool| {
        let mut scene = top_view(width, shadows, 45.0, "pcf3", BALL);
        if let Some(n) = cascades {
            let knob = KNOBS
                .iter()
                .find(|k| k.name == "shadow_cascades")
                .expect("a knob");
            (knob.apply)(&mut scene, &n.to_string()).expect("a count");
        }
        scene
    };
    if let Some(n) = cascades {
        let shadow_scene = scene(true);
        let plan = FramePlan::new(
            &shadow_scene,
            &SceneGeometry::new(&shadow_scene).expect("geometry"),
            false,
        );
        assert_eq!(
            plan.shadow.as_ref().map(|s| s.cascades.len()),
            Some(n as usize)
        );
    }
    let on = hdr(&scene(true));
    let off = hdr(&scene(false));
    // The plane faces the camera: a pixel covers (2 d tan(fov / 2) / h)^2.
    let per_pixel = 2.0 * 10.0 * 15f64.to_radians().tan() / f64::from(on.height);
    let area = shadow_area(&on, &off, 0.1 * 0.8, per_pixel * per_pixel);
    let expected = std::f64::consts::PI * 0.25 / 45f64.to_radians().cos();
    let error = (area - expected).abs() / expected;
    eprintln!("{cascades:?} cascades: shadow area {area:.5}, closed form {expected:.5}");
    assert!(
        error < 0.02,
        "{cascades:?} cascades: shadow area {area:.4}, closed form {expected:.4} ({:.2} %)",
        100.0 * error
    );
    // The ellipse is centred 1.5 tan 45° = 1.5 along +x from the sphere:
    // the image's centre column is x = 1, so it lies right of centre
    // (+x is to the right with the image's up along -z).
    let row = on.height / 2;
    let at = |x_world: f64| {
        let x = f64::from(on.width) / 2.0 + (x_world - 1.0) / per_pixel;
        common::pixel(&on, x as u32, row)[0]
    };
    assert!(at(1.5) < 0.1, "the ellipse's centre is lit: {}", at(1.5));
    assert!(at(2.4) > 0.3, "beyond the ellipse is dark: {}", at(2.4));
}

/// A sphere under the plane's edge, in the frustum and not wholly behind
/// the plane as the camera sees it: the plane may shadow what of it shows
/// past the edge, so the plane is drawn into the map (a plane with nothing
/// behind it, or only what it hides, is left out,
/// `shadow_view::may_shadow`). The image ends just short of the edge.
const UNDER: &str = "[[objects]]\nname = \"under\"\nmaterial = \"ball\"\n\
                     shape = { type = \"sphere\", radius = 0.5 }\ntranslate = [6.0, -0.6, 0.0]\n";

/// The same sphere right under the plane's middle, which hides it from
/// the camera: the plane can shadow nothing the camera sees.
const HIDDEN: &str = "[[objects]]\nname = \"under\"\nmaterial = \"ball\"\n\
                      shape = { type = \"sphere\", radius = 0.5 }\ntranslate = [1.0, -2.0, 0.0]\n";

/// No self-shadowing: a plane with nothing over it (only a sphere under
/// it, out of sight) is lit the same with shadows on and off (within
/// 1/255 in the 8-bit output), at a grazing light (75° from vertical)
/// where depth bias matters most, for every filter.
#[test]
fn a_plane_alone_does_not_shadow_itself() {
    let geometry_plan =
        |scene: &Scene| FramePlan::new(scene, &SceneGeometry::new(scene).expect("geometry"), false);
    let shadowed = top_view(320, true, 75.0, "pcf3", UNDER);
    let casters = geometry_plan(&shadowed)
        .shadow
        .expect("a shadow view")
        .casters;
    assert!(
        casters.iter().any(|d| d.object == 0),
        "the plane is not drawn into the map"
    );
    let hidden = geometry_plan(&top_view(320, true, 75.0, "pcf3", HIDDEN));
    assert!(
        hidden
            .shadow
            .expect("a shadow view")
            .casters
            .iter()
            .all(|d| d.object != 0),
        "the plane is drawn though it hides all that is behind it"
    );
    let off = common::render(&top_view(320, false, 75.0, "pcf3", UNDER), false).output;
    for filter in ["none", "pcf3", "pcf5"] {
        let on = common::render(&top_view(320, true, 75.0, filter, UNDER), false).output;
        let worst = largest_difference(&on, &off);
        assert!(worst <= 1, "{filter}: a pixel moved by {worst}/255");
        // Lit: kd (0.8) times cos 75° plus the ambient 0.08, tone-mapped,
        // far above the ambient alone.
        let centre = common::pixel(&on, on.width / 2, on.height / 2);
        assert!(centre[0] > 60, "{filter}: the plane is dark: {centre:?}");
    }
}

/// The frame holds the shadow pass and the map only with a shadow-casting
/// light and a caster; the map is its own size and its own render pass.
#[test]
fn the_frame_holds_the_shadow_pass_only_when_asked() {
    let plan = |scene: &Scene| {
        let geometry = SceneGeometry::new(scene).expect("geometry");
        FramePlan::new(scene, &geometry, false)
    };
    let with = plan(&top_view(320, true, 45.0, "pcf3", BALL));
    assert!(with.has(shadow_map::PASS));
    let map = with.attachment(attachment::SHADOW_MAP).expect("a map");
    assert_eq!(with.attachment_extent(map), (2048, 2048));
    assert_eq!(with.render_pass_count(), 2);
    assert!(with.shadow.as_ref().is_some_and(|s| s.casters.len() == 1));

    let without = plan(&top_view(320, false, 45.0, "pcf3", BALL));
    assert!(!without.has(shadow_map::PASS));
    assert!(!without.has_attachment(attachment::SHADOW_MAP));
    assert_eq!(without.render_pass_count(), 1);

    // A ground plane with everything on its lit side casts nothing onto
    // them: left out of the map.
    assert!(with
        .shadow
        .as_ref()
        .is_some_and(|s| s.casters.iter().all(|d| d.object != 0)));

    // Nothing casts: no pass either.
    let mut no_casters = top_view(320, true, 45.0, "pcf3", BALL);
    for o in &mut no_casters.objects {
        o.casts_shadows = false;
    }
    assert!(!plan(&no_casters).has(shadow_map::PASS));
}

/// `casts_shadows = false` takes an object out of the map: the plane
/// under it is lit as without shadows.
#[test]
fn an_object_that_casts_no_shadow_leaves_the_plane_lit() {
    let ball = BALL.replace("translate", "casts_shadows = false\ntranslate");
    let on = common::render(&top_view(320, true, 45.0, "pcf3", &ball), false).output;
    let off = common::render(&top_view(320, false, 45.0, "pcf3", BALL), false).output;
    let worst = largest_difference(&on, &off);
    assert!(worst <= 1, "a pixel moved by {worst}/255");
}

/// The largest difference of one channel between two 8-bit images.
fn largest_difference(a: &Pixels<u8>, b: &Pixels<u8>) -> u8 {
    a.data
        .iter()
        .zip(&b.data)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

/// Bad values name the field and the reason.
#[test]
fn shadow_settings_are_checked() {
    let base = |light: &str, output: &str| {
        format!(
            "[output]\n{output}\n[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n{light}"
        )
    };
    let directional = "[[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\n";
    let cases = [
        (
            base(
                &format!("{directional}shadows = true\n"),
                "shadow_cascades = 5",
            ),
            "output.shadow_cascades",
        ),
        (
            base(
                &format!("{directional}shadows = true\n"),
                "shadow_cascades = \"many\"",
            ),
            "output.shadow_cascades",
        ),
        (
            base(
                &format!("{directional}shadows = true\n{directional}shadows = true\n"),
                "",
            ),
            "lights[1].shadows",
        ),
        (
            base(
                &format!("{directional}shadows = true\n"),
                "lighting = \"deferred\"",
            ),
            "lights[0].shadows",
        ),
        (
            base(
                &format!("{directional}shadows = true\n"),
                "shadow_map = 100",
            ),
            "output.shadow_map",
        ),
    ];
    for (text, field) in cases {
        let err = Scene::from_toml(&text, "bad.toml", std::path::Path::new("."))
            .expect_err("the scene is refused")
            .to_string();
        assert!(err.contains("bad.toml") && err.contains(field), "{err}");
    }
    // The knobs check their values too.
    let mut scene = top_view(64, true, 45.0, "pcf3", BALL);
    let knob = |name: &str| KNOBS.iter().find(|k| k.name == name).expect("a knob");
    assert!((knob("shadow_map").apply)(&mut scene, "100").is_err());
    assert!((knob("shadow_filter").apply)(&mut scene, "pcf4").is_err());
    assert!((knob("lighting").apply)(&mut scene, "deferred").is_err());
    assert!((knob("shadow_filter").apply)(&mut scene, "pcf5").is_ok());
    assert!((knob("shadow_cascades").apply)(&mut scene, "0").is_err());
    assert!((knob("shadow_cascades").apply)(&mut scene, "auto").is_ok());
    // A point light may cast shadows (through a cube map).
    let point = base(
        "[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nshadows = true\n",
        "",
    );
    assert!(Scene::from_toml(&point, "point.toml", std::path::Path::new(".")).is_ok());
}

/// A sphere of radius 2 resting on the planet, seen from 30 m straight
/// above, under an Earth atmosphere's sun 30° up: `shadows` on `[sun]`.
fn sun_scene(shadows: bool) -> Scene {
    let s = 30f64.to_radians();
    let (up, across) = (s.sin(), s.cos() / 2f64.sqrt());
    common::scene(&format!(
        "[output]\nwidth = 320\nheight = 180\nhdr_format = \"rgba32f\"\n\
         [tone_map]\nexposure = 4.0\n\
         [camera]\neye = [0.0, 30.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
         [[materials]]\nname = \"grey\"\nkd = [0.5, 0.5, 0.5]\n\
         [[objects]]\nname = \"ball\"\nmaterial = \"grey\"\n\
         shape = {{ type = \"sphere\", radius = 2.0 }}\ntranslate = [0.0, 2.0, 0.0]\n\
         [sun]\ndirection = [{}, {up}, {across}]\nshadows = {shadows}\n\
         [atmosphere]\n",
        -across
    ))
}

/// The sun's shadow falls on the planet's ground (drawn by the atmosphere
/// pass, not an object): where the line through the sphere's centre along
/// the sunlight meets the ground, 2 / tan 30° = 3.46 m from its foot
/// (away from the sun), the ground keeps only the sky's light; on the
/// sun's side it is unchanged.
#[test]
fn the_sun_shadows_the_planet_s_ground() {
    let on = hdr(&sun_scene(true));
    let off = hdr(&sun_scene(false));
    // Ground units per pixel from 30 m with a 45° field of view.
    let per_pixel = 2.0 * 30.0 * 22.5f64.to_radians().tan() / f64::from(on.height);
    let at = |image: &Pixels<f32>, x: f64, z: f64| {
        let col = f64::from(image.width) / 2.0 + x / per_pixel;
        let row = f64::from(image.height) / 2.0 + z / per_pixel;
        common::pixel(image, col as u32, row as u32)
    };
    let reach = 2.0 / 30f64.to_radians().tan() / 2f64.sqrt();
    let (shadow, lit) = (at(&on, reach, -reach), at(&off, reach, -reach));
    for c in 0..3 {
        assert!(
            shadow[c] < 0.8 * lit[c] && shadow[c] > 0.0,
            "channel {c}: {} in the shadow, {} without shadows",
            shadow[c],
            lit[c]
        );
    }
    let (sunny, sunny_off) = (at(&on, -5.0, 5.0), at(&off, -5.0, 5.0));
    for c in 0..3 {
        assert!(
            (sunny[c] - sunny_off[c]).abs() <= 1e-6 * sunny_off[c].abs().max(1.0),
            "channel {c} on the sun's side moved: {} against {}",
            sunny[c],
            sunny_off[c]
        );
    }
}

/// No peter-panning: an upright cylinder (radius 0.3, height 2) standing
/// on the plane, the light 45° from vertical towards +x, seen from above
/// at 1280x720: the shadow touches the cylinder's base. The first whole
/// pixel of ground beyond the base on the shadow's side is in shadow
/// (less than half the light reaches it), so any gap is under a pixel.
#[test]
fn a_shadow_touches_the_base_of_its_caster() {
    let post = "[[objects]]\nname = \"post\"\nmaterial = \"ball\"\n\
                shape = { type = \"cylinder\", radius = 0.3, height = 2.0 }\n\
                tessellation = [256, 4]\ntranslate = [0.0, 1.0, 0.0]\n";
    let on = hdr(&top_view(1280, true, 45.0, "pcf3", post));
    let off = hdr(&top_view(1280, false, 45.0, "pcf3", post));
    let per_pixel = 2.0 * 10.0 * 15f64.to_radians().tan() / f64::from(on.height);
    // The base at x = 0.3 on the centre row; the wall above it projects
    // further left, so the pixels right of it are ground.
    let base = f64::from(on.width) / 2.0 + (0.3 - 1.0) / per_pixel;
    let row = on.height / 2;
    let ambient = 0.1 * 0.8;
    let first = base.ceil() as u32 + 1;
    for col in first..first + 3 {
        let lit = common::pixel(&off, col, row)[0] - ambient;
        let seen = common::pixel(&on, col, row)[0] - ambient;
        assert!(
            lit > 0.1 && seen < 0.5 * lit,
            "column {col} ({:.2} px beyond the base): {seen} of {lit} reaches it",
            f64::from(col) - base
        );
    }
}

/// Automatic cascades follow the view's depth: one for objects at about
/// the same distance, several for earth_objects' spheres from 40 m to
/// 13 km (the map then holds one tile per cascade).
#[test]
fn automatic_cascades_follow_the_depth_of_the_view() {
    let plan =
        |scene: &Scene| FramePlan::new(scene, &SceneGeometry::new(scene).expect("geometry"), false);
    let near = plan(&top_view(320, true, 45.0, "pcf3", BALL));
    assert_eq!(near.shadow.as_ref().map(|s| s.cascades.len()), Some(1));

    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/earth_objects.toml");
    let mut deep = Scene::load(&path).expect("earth_objects loads");
    deep.shadow_light = Some(aerial::scene::ShadowLight::Sun);
    let deep = plan(&deep);
    let view = deep.shadow.as_ref().expect("a shadow view");
    assert!(view.cascades.len() >= 3, "{} cascades", view.cascades.len());
    // Nearer cascades are finer.
    for pair in view.cascades.windows(2) {
        assert!(pair[0].texel < pair[1].texel && pair[0].reach < pair[1].reach);
    }
    let map = deep.attachment(attachment::SHADOW_MAP).expect("a map");
    let (across, down) = view.tiles;
    assert_eq!(deep.attachment_extent(map), (2048 * across, 2048 * down));
}

/// The top view lit by a point light at (-3, 4, 0) (no fall-off) with
/// `shadows`, over the sphere of [`BALL`] and a post.
fn point_view(width: u32, shadows: bool) -> Scene {
    let mut scene = top_view(width, false, 45.0, "pcf3", BALL);
    let text = format!(
        "[[lights]]\ntype = \"point\"\nposition = [-3.0, 4.0, 0.0]\nattenuation = [1.0, 0.0, 0.0]\n\
         shadows = {shadows}\n"
    );
    let lights = common::scene(&format!(
        "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n{text}"
    ));
    scene.lights = lights.lights;
    scene.shadow_light = lights.shadow_light;
    scene
}

/// Point-light shadows through the six faces of a cube map, against the
/// exact CPU reference (the shadow ray cast to the light in double
/// precision): the shadowed area on the plane agrees within 2 %, and no
/// seam shows where the faces meet (the shadow spans the -y face and the
/// +x face: the light is above and to the left).
#[test]
fn a_point_light_casts_the_shadow_of_the_exact_reference() {
    let width = 960;
    let on = hdr(&point_view(width, true));
    let off = hdr(&point_view(width, false));
    let per_pixel = 2.0 * 10.0 * 15f64.to_radians().tan() / f64::from(on.height);
    let area = |with: &Pixels<f32>, without: &Pixels<f32>| {
        shadow_area(with, without, 0.1 * 0.8, per_pixel * per_pixel)
    };
    let gpu = area(&on, &off);
    let cpu_on = aerial::render::cpu_renderer::render_on_cpu(&point_view(width, true))
        .expect("the reference renders");
    let cpu_off = aerial::render::cpu_renderer::render_on_cpu(&point_view(width, false))
        .expect("the reference renders");
    let exact = area(&cpu_on, &cpu_off);
    let error = (gpu - exact).abs() / exact;
    eprintln!("point-light shadow area {gpu:.5}, exact {exact:.5}");
    assert!(exact > 0.5, "the reference has no shadow: {exact}");
    assert!(
        error < 0.02,
        "shadow area {gpu:.4}, exact {exact:.4} ({:.2} %)",
        100.0 * error
    );
    // Seams: no lit pixel inside the exact shadow's core, more than 6
    // pixels from its edge (the faces -y and +x meet across it, at x = 1,
    // the image's centre column). The edge itself moves by a few pixels
    // where the light grazes the plane: the lookup's normal offset lifts
    // the point by two texels, which the light carries sideways.
    let w = on.width as usize;
    let dark = |img: &Pixels<f32>, i: usize| img.data[i * 4] < 0.1 * 0.8 + 1e-3;
    let mut checked = 0;
    for y in 6..on.height as usize - 6 {
        for x in 6..w - 6 {
            let i = y * w + x;
            let core = (0..13).all(|dy| {
                (0..13).all(|dx| {
                    let j = (y + dy - 6) * w + (x + dx - 6);
                    dark(&cpu_on, j) && cpu_off.data[j * 4] > 0.2
                })
            });
            if core {
                checked += 1;
                assert!(dark(&on, i), "a lit pixel at ({x}, {y}) inside the shadow");
            }
        }
    }
    assert!(checked > 1000, "only {checked} core pixels");
}

/// A point light's cube faces draw only the casters that reach into them
/// (`Cascade::drawn`): the ball (radius 0.5, centre 4.5 from the light
/// along +x) is drawn into the +x face alone; the ground plane, whose
/// bounding sphere (radius 8.5) holds the light, into all six: the test
/// is by bounding spheres, so it keeps what it cannot rule out.
#[test]
fn a_cube_face_draws_only_the_casters_that_reach_into_it() {
    let mut scene = point_view(320, true);
    scene.objects[1].transform.translate = glam::DVec3::new(1.5, 4.0, 0.0);
    let geometry = SceneGeometry::new(&scene).expect("geometry");
    let view = FramePlan::new(&scene, &geometry, false)
        .shadow
        .expect("a shadow view");
    let faces_with = |object: usize| -> Vec<usize> {
        let caster = view
            .casters
            .iter()
            .position(|d| d.object == object)
            .expect("a caster");
        (0..view.cascades.len())
            .filter(|&f| {
                view.cascades[f]
                    .drawn
                    .as_ref()
                    .expect("a face's list")
                    .contains(&caster)
            })
            .collect()
    };
    assert_eq!(faces_with(1), vec![0], "the ball's faces");
    assert_eq!(faces_with(0), vec![0, 1, 2, 3, 4, 5], "the ground's faces");
}
