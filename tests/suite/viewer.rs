//! `aerial view` in a virtual X server (Xvfb, installed by
//! `scripts/setup.sh`), driven by scripts, every run under the validation
//! layer (swapchain and presentation included):
//! - the first frame, before any input, is bit-identical to `aerial render`
//!   of the same scene at the same size (PNG and EXR): the viewer draws
//!   with the same renderer and plan, and the camera is the scene's own
//!   until something moves it;
//! - W held for 30 frames moves the camera forward by 30 fixed steps at the
//!   height-proportional speed, the image changes, and the `[camera]` the
//!   screenshot records renders the same image with `aerial render`;
//! - resizing mid-script keeps drawing, at the new size, what `render`
//!   draws at that size;
//! - bad scripts are refused with file, line and reason.

use crate::common;

use aerial::image_io::{read_exr, read_png_text};
use aerial::render::Pixels;
use aerial::scene::Scene;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A virtual X server on a free display, stopped when dropped.
struct Xvfb {
    child: Child,
    display: String,
    /// Where the server keeps its screen as an XWD file (`-fbdir`).
    fbdir: tempfile::TempDir,
}

impl Xvfb {
    fn start() -> Xvfb {
        // Tests run in parallel and other X servers may be up: try display
        // numbers until one starts. Each test of this process takes its own
        // numbers: two tests trying the same one could both see the socket
        // of the server only one of them started, and the other's viewer
        // would lose its display when that test ends.
        static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let first = 200 + std::process::id() % 300;
        for _ in 0..100 {
            let n = first + NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed) % 1000;
            if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
                || Path::new(&format!("/tmp/.X{n}-lock")).exists()
            {
                continue;
            }
            let fbdir = tempfile::tempdir().unwrap();
            let mut child = Command::new("Xvfb")
                .args([
                    &format!(":{n}"),
                    "-screen",
                    "0",
                    "1024x768x24",
                    "-nolisten",
                    "tcp",
                ])
                .arg("-fbdir")
                .arg(fbdir.path())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("Xvfb runs (install it with scripts/setup.sh)");
            let deadline = Instant::now() + Duration::from_secs(10);
            while Instant::now() < deadline {
                if let Ok(Some(_)) = child.try_wait() {
                    break; // lost the race for this display
                }
                if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                    return Xvfb {
                        child,
                        display: format!(":{n}"),
                        fbdir,
                    };
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
        panic!("no free X display to start Xvfb on");
    }

    /// Runs `aerial view ARGS` on this display, with validation, and
    /// returns its output.
    /// Runs the viewer on `scene` with `extra` arguments and `script` (written
    /// into `dir`), and checks it exited 0.
    fn run_script(&self, dir: &Path, scene: &Path, extra: &[&str], script: &str) -> Output {
        let path = dir.join("script.txt");
        std::fs::write(&path, script).unwrap();
        let mut args = vec![scene.to_str().unwrap()];
        args.extend_from_slice(extra);
        args.extend(["--script", path.to_str().unwrap()]);
        let out = self.view(&args);
        assert!(out.status.success(), "{}", text(&out));
        out
    }

    fn view(&self, args: &[&str]) -> Output {
        common::aerial()
            .arg("view")
            .args(args)
            .args(["--validate", "--present-mode", "immediate"])
            .env("DISPLAY", &self.display)
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap()
    }
}

impl Xvfb {
    /// The screen as the X server holds it now: RGBA, top row first.
    fn screen(&self) -> Pixels<u8> {
        // XWD: a header of big-endian u32 fields, the window name, the
        // colour map (12 bytes an entry), then the pixels.
        let bytes = std::fs::read(self.fbdir.path().join("Xvfb_screen0")).unwrap();
        let field = |i: usize| u32::from_be_bytes(bytes[i * 4..i * 4 + 4].try_into().unwrap());
        let (header, width, height) = (field(0) as usize, field(4), field(5));
        let (byte_order, bits_per_pixel, bytes_per_line) =
            (field(7), field(11), field(12) as usize);
        let (red_mask, green_mask, blue_mask) = (field(14), field(15), field(16));
        let colours = field(19) as usize;
        assert_eq!(bits_per_pixel, 32, "a 24-bit screen keeps 32-bit pixels");
        let start = header + colours * 12;
        let mut data = Vec::with_capacity((width * height * 4) as usize);
        for y in 0..height as usize {
            for x in 0..width as usize {
                let p = &bytes[start + y * bytes_per_line + x * 4..][..4];
                let v = if byte_order == 0 {
                    u32::from_le_bytes(p.try_into().unwrap())
                } else {
                    u32::from_be_bytes(p.try_into().unwrap())
                };
                let channel = |mask: u32| ((v & mask) >> mask.trailing_zeros()) as u8;
                data.extend_from_slice(&[
                    channel(red_mask),
                    channel(green_mask),
                    channel(blue_mask),
                    255,
                ]);
            }
        }
        Pixels {
            width,
            height,
            data,
        }
    }
}

/// The part of `screen` at (x0, y0) of `image`'s size, compared with
/// `image` (RGB): the number of differing pixels and the largest channel
/// difference.
fn compare_on_screen(screen: &Pixels<u8>, image: &Pixels<u8>, x0: u32, y0: u32) -> (usize, u8) {
    let mut differing = 0;
    let mut worst = 0;
    for y in 0..image.height {
        for x in 0..image.width {
            let i = ((y * image.width + x) * 4) as usize;
            let j = (((y0 + y) * screen.width + x0 + x) * 4) as usize;
            let d = (0..3)
                .map(|c| image.data[i + c].abs_diff(screen.data[j + c]))
                .max()
                .unwrap();
            if d > 0 {
                differing += 1;
                worst = worst.max(d);
            }
        }
    }
    (differing, worst)
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        // SIGTERM lets the server remove its socket and lock file (SIGKILL
        // would leave them, and later runs would skip that display).
        // SAFETY: kill(2) on our own child's pid, which it still is: the
        // child has not been waited for.
        unsafe { libc::kill(self.child.id() as libc::pid_t, libc::SIGTERM) };
        let deadline = Instant::now() + Duration::from_secs(5);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A ground plane with a sphere and a box on it; the camera 2 m above the
/// ground looks level along -Z, so the nearest surface while flying
/// forward is the ground, 2 m below.
const SCENE: &str = r#"
ambient = [0.05, 0.05, 0.05]
[output]
width = 160
height = 90
[[lights]]
type = "directional"
direction = [-0.5, -1.0, -0.3]
[[lights]]
type = "point"
position = [2.0, 4.0, -6.0]
intensity = 8.0
[[materials]]
name = "ground"
kd = [0.6, 0.6, 0.55]
[[materials]]
name = "red"
kd = [0.8, 0.1, 0.1]
ks = [0.4, 0.4, 0.4]
[[objects]]
name = "ground"
material = "ground"
shape = { type = "plane", width = 200.0, depth = 200.0 }
[[objects]]
name = "ball"
material = "red"
shape = { type = "sphere", radius = 1.0 }
translate = [0.5, 1.0, -12.0]
[[objects]]
name = "ring"
material = "red"
shape = { type = "torus", major_radius = 1.0, minor_radius = 0.3 }
translate = [-2.5, 0.3, -9.0]
"#;

const CAMERA: &str = "[camera]\neye = [0, 2, 0]\nlook_at = [0, 2, -10]\nup = [0, 1, 0]\n";

fn write_scene(dir: &Path) -> PathBuf {
    let path = dir.join("scene.toml");
    std::fs::write(&path, format!("{SCENE}{CAMERA}")).unwrap();
    path
}

fn read_png(path: &Path) -> Pixels<u8> {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8();
    Pixels {
        width: img.width(),
        height: img.height(),
        data: img.into_raw(),
    }
}

fn text(output: &Output) -> String {
    format!(
        "exit {:?}\nstdout:\n{}\nstderr:\n{}",
        output.status.code(),
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// Runs `aerial render` on `scene` at `w`x`h` with validation and returns
/// the PNG and EXR paths.
fn render(scene: &Path, w: u32, h: u32, dir: &Path, name: &str) -> (PathBuf, PathBuf) {
    let png = dir.join(format!("{name}.png"));
    let exr = dir.join(format!("{name}.exr"));
    let out = common::aerial()
        .arg("render")
        .arg(scene)
        .args([
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--validate",
        ])
        .arg("--out")
        .arg(&png)
        .arg("--hdr")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    (png, exr)
}

fn metadata(path: &Path, key: &str) -> String {
    read_png_text(path)
        .unwrap()
        .into_iter()
        .find(|(k, _)| k == key)
        .unwrap_or_else(|| panic!("{} has no {key}", path.display()))
        .1
}

fn differing_pixels(a: &Pixels<u8>, b: &Pixels<u8>) -> usize {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.data
        .chunks_exact(4)
        .zip(b.data.chunks_exact(4))
        .filter(|(p, q)| p != q)
        .count()
}

#[test]
fn first_frame_equals_render_and_w_moves_the_camera_forward() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let first = dir.path().join("first.png");
    let moved = dir.path().join("moved.png");
    // Frame 0 is drawn before any input; W is held while frames 1..=30 are
    // drawn, so the camera makes 30 steps of 1/60 s.
    let x = Xvfb::start();
    let out = x.run_script(
        dir.path(),
        &scene,
        &[],
        &format!(
            "0 screenshot {}\n1 press W\n31 release W\n31 screenshot {}\n32 quit\n",
            first.display(),
            moved.display()
        ),
    );
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("validation"),
        "{}",
        text(&out)
    );

    // Before any input: bit-identical to `aerial render`, PNG and EXR. The
    // same renderer, plan and camera give the same commands on the same
    // driver, so nothing may differ.
    let (render_png, render_exr) = render(&scene, 160, 90, dir.path(), "render");
    let shot = read_png(&first);
    let reference = read_png(&render_png);
    common::assert_not_blank(&reference, 0.3);
    assert_eq!(
        differing_pixels(&shot, &reference),
        0,
        "PNG differs from render"
    );
    let shot_hdr = read_exr(&first.with_extension("exr")).unwrap();
    let reference_hdr = read_exr(&render_exr).unwrap();
    assert_eq!(shot_hdr.data.len(), reference_hdr.data.len());
    assert!(
        shot_hdr
            .data
            .iter()
            .zip(&reference_hdr.data)
            .all(|(a, b)| a.to_bits() == b.to_bits()),
        "EXR differs from render"
    );

    // W: forward (-Z) by 30 steps of 1/60 s at 2 m/s (the height above the
    // ground), i.e. 1 m; nothing else about the camera changed.
    let camera_toml = metadata(&moved, "aerial:camera");
    let with_camera = format!("{SCENE}{camera_toml}");
    let moved_scene = Scene::from_toml(&with_camera, "moved", dir.path()).unwrap();
    let c = moved_scene.camera;
    let expected = glam::DVec3::new(0.0, 2.0, -1.0);
    assert!(
        c.eye.distance(expected) < 1e-5,
        "eye {} after 30 frames of W, expected {expected}",
        c.eye
    );
    let direction = (c.look_at - c.eye).normalize();
    assert!(direction.distance(glam::DVec3::NEG_Z) < 1e-6, "{direction}");
    assert_eq!((c.up, c.fov_y_degrees), (glam::Vec3::Y, 45.0));

    // The image changed: the objects came closer.
    let after = read_png(&moved);
    let changed = differing_pixels(&after, &shot);
    assert!(
        changed > (160 * 90) / 20,
        "only {changed} pixels changed after moving 1 m"
    );
    // And the recorded camera reproduces it with `aerial render`.
    let moved_path = dir.path().join("moved.toml");
    std::fs::write(&moved_path, &with_camera).unwrap();
    let (again, _) = render(&moved_path, 160, 90, dir.path(), "again");
    assert_eq!(differing_pixels(&after, &read_png(&again)), 0);
}

#[test]
fn resizing_mid_script_keeps_rendering_at_the_new_size() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let big = dir.path().join("big.png");
    let small = dir.path().join("small.png");
    let x = Xvfb::start();
    x.run_script(
        dir.path(),
        &scene,
        &[],
        &format!(
            "2 resize 240 135\n3 screenshot {}\n4 resize 96 64\n6 screenshot {}\n7 quit\n",
            big.display(),
            small.display()
        ),
    );
    for (path, w, h) in [(&big, 240, 135), (&small, 96, 64)] {
        let shot = read_png(path);
        assert_eq!((shot.width, shot.height), (w, h), "{}", path.display());
        let (reference, _) = render(&scene, w, h, dir.path(), &format!("render{w}"));
        assert_eq!(
            differing_pixels(&shot, &read_png(&reference)),
            0,
            "{} differs from render at {w}x{h}",
            path.display()
        );
    }
}

#[test]
fn a_bad_script_is_refused_with_file_line_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("bad.txt");
    std::fs::write(&script, "0 press W\n# fine\n12 hover 3\n").unwrap();
    // Refused before a window is opened, so no X server is needed.
    let out = common::aerial()
        .args(["view", "--script"])
        .arg(&script)
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!("{}:3: unknown action 'hover'", script.display())),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    // An endless script stops at the bound, with a message naming it.
    let out = common::aerial()
        .args(["view", "--script", "/dev/zero"])
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("/dev/zero") && stderr.contains("reading stopped"),
        "{stderr}"
    );
}

/// The viewer moves the view of a live renderer instead of building a new
/// one each frame; what it then draws must be what a new renderer for the
/// moved view draws, bit for bit, whether only the uniforms were rewritten
/// (camera, sky) or the frame had to be built again (draw order, deferred
/// light tiles). Headless: no window needed.
#[test]
fn moving_the_view_draws_what_a_new_renderer_draws() {
    use aerial::render::{Renderer, ViewChange};
    use aerial::scene::Knob;

    let ctx = common::validated_context();
    let log = ctx.validation_log().expect("validation on");
    let mut changes = Vec::new();
    for (file, knob) in [
        ("default.toml", None),
        ("earth_sunset.toml", None),
        ("transparency.toml", None),
        ("many_lights.toml", Some(("lighting", "deferred"))),
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes")
            .join(file);
        let mut scene = Scene::load(&path).unwrap();
        scene.set_output_size(Some(64), Some(36)).unwrap();
        if let Some((name, value)) = knob {
            Knob::find(name).unwrap().set(&mut scene, value).unwrap();
        }
        let mut moved = scene.clone();
        let step = glam::DVec3::new(0.3, 0.2, -0.4);
        moved.camera.eye += step;
        moved.camera.look_at += step + glam::DVec3::new(0.2, 0.0, 0.0);
        if let Some(sky) = &mut moved.sky {
            sky.sun.direction = (sky.sun.direction + glam::DVec3::new(0.0, 0.05, 0.02)).normalize();
        }

        let mut live = Renderer::new(&ctx, &scene, true).unwrap();
        live.render_frame().unwrap();
        let before = live.output();
        let change = live.set_view(&moved).unwrap();
        live.render_frame().unwrap();
        let (after, after_hdr) = (live.output(), live.hdr().unwrap());
        drop(live);
        let mut fresh = Renderer::new(&ctx, &moved, true).unwrap();
        fresh.render_frame().unwrap();
        let (expected, expected_hdr) = (fresh.output(), fresh.hdr().unwrap());
        drop(fresh);

        assert!(
            differing_pixels(&before, &after) > 0,
            "{file}: the view did not change"
        );
        assert_eq!(
            differing_pixels(&after, &expected),
            0,
            "{file} ({change:?})"
        );
        assert!(
            after_hdr
                .data
                .iter()
                .zip(&expected_hdr.data)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "{file} ({change:?}): HDR differs"
        );
        changes.push((file, change));
    }
    // Small moves keep every resource: the sky's uniforms are rewritten,
    // and where the move reorders the draws the frame is recorded again.
    assert_eq!(changes[0], ("default.toml", ViewChange::Recorded));
    assert_eq!(changes[1], ("earth_sunset.toml", ViewChange::Updated));
    drop(ctx);
    let messages = log.messages();
    assert!(messages.is_empty(), "{messages:?}");
    println!("{changes:?}");
}

/// Number keys cycle the knobs that apply (listed in this order for a
/// scene with objects and no textures: 1 shading, 2 lighting, 3
/// hdr_format, 4 tone_map); the frame after a change is what `render`
/// draws with those knob settings, and the screenshot records them.
#[test]
fn number_keys_cycle_knobs_and_rebuild_the_frame() {
    use aerial::scene::Knob;
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_scene(dir.path());
    let shot = dir.path().join("knobs.png");
    let x = Xvfb::start();
    let out = x.run_script(
        dir.path(),
        &scene_path,
        &[],
        &format!(
            "0 press 2\n0 press 4\n0 screenshot {}\n1 quit\n",
            shot.display()
        ),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("lighting=deferred") && stdout.contains("tone_map=aces"),
        "{stdout}"
    );
    let knobs = metadata(&shot, "aerial:knobs");
    assert!(
        knobs.contains("lighting=deferred") && knobs.contains("tone_map=aces"),
        "{knobs}"
    );
    let mut scene = Scene::load(&scene_path).unwrap();
    Knob::find("lighting")
        .unwrap()
        .set(&mut scene, "deferred")
        .unwrap();
    Knob::find("tone_map")
        .unwrap()
        .set(&mut scene, "aces")
        .unwrap();
    let expected = common::render(&scene, false).output;
    let plain = common::render(&Scene::load(&scene_path).unwrap(), false).output;
    let got = read_png(&shot);
    assert_eq!(differing_pixels(&got, &expected), 0);
    assert!(
        differing_pixels(&got, &plain) > 0,
        "the knobs changed nothing"
    );
}

/// L held for 30 frames lowers the sun by 30 steps of 1/60 s at 10°/s:
/// 5°, along its arc over the local vertical; the screenshot records the
/// new direction, and `render` with it draws the same sky.
#[test]
fn the_sun_key_turns_the_sun_by_the_expected_angle() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/earth_noon.toml");
    let shot = dir.path().join("sun.png");
    let x = Xvfb::start();
    x.run_script(
        dir.path(),
        &scene_path,
        &["--width", "64", "--height", "36"],
        &format!(
            "0 press L\n30 release L\n30 screenshot {}\n31 quit\n",
            shot.display()
        ),
    );
    let mut scene = Scene::load(&scene_path).unwrap();
    scene.set_output_size(Some(64), Some(36)).unwrap();
    let before = scene.sky.as_ref().unwrap().sun.direction;
    let recorded = metadata(&shot, "aerial:sun_direction");
    let v: Vec<f64> = recorded
        .trim_matches(|c| c == '[' || c == ']')
        .split(',')
        .map(|t| t.trim().parse().unwrap())
        .collect();
    let after = glam::DVec3::new(v[0], v[1], v[2]);
    let angle = before.angle_between(after).to_degrees();
    assert!((angle - 5.0).abs() < 1e-6, "turned {angle}°");
    assert!(after.y < before.y, "L lowers the sun");
    // Along its arc: the azimuth stays.
    let azimuth = |d: glam::DVec3| d.z.atan2(d.x);
    assert!((azimuth(after) - azimuth(before)).abs() < 1e-9);
    scene.sky.as_mut().unwrap().sun.direction = after;
    let expected = common::render(&scene, false).output;
    assert_eq!(differing_pixels(&read_png(&shot), &expected), 0);
}

/// The window shows the rendered image exactly, and closing it (the
/// WM_DELETE_WINDOW message a window manager sends for the close button)
/// ends the viewer with status 0 and a clean validation log.
#[test]
fn the_window_shows_the_image_and_closing_it_exits_0() {
    use x11rb::connection::Connection as _;
    use x11rb::protocol::xproto::{AtomEnum, ClientMessageEvent, ConnectionExt as _, EventMask};

    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let shot = dir.path().join("alive.png");
    // No quit: the viewer runs until the window is closed.
    let script = dir.path().join("stay.txt");
    std::fs::write(&script, format!("3 screenshot {}\n", shot.display())).unwrap();
    let x = Xvfb::start();
    let mut viewer = common::aerial()
        .arg("view")
        .arg(&scene)
        .args(["--script", script.to_str().unwrap()])
        .args(["--validate", "--present-mode", "immediate"])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(60);
    while !shot.exists() {
        assert!(Instant::now() < deadline, "the viewer drew no frame");
        if let Ok(Some(status)) = viewer.try_wait() {
            panic!("the viewer ended early: {status}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }

    let (conn, screen) = x11rb::connect(Some(&x.display)).unwrap();
    let root = conn.setup().roots[screen].root;
    let atom = |name: &[u8]| conn.intern_atom(false, name).unwrap().reply().unwrap().atom;
    let (protocols, delete) = (atom(b"WM_PROTOCOLS"), atom(b"WM_DELETE_WINDOW"));
    let windows: Vec<_> = conn
        .query_tree(root)
        .unwrap()
        .reply()
        .unwrap()
        .children
        .into_iter()
        .filter(|&w| {
            let asks = conn
                .get_property(false, w, protocols, AtomEnum::ATOM, 0, 64)
                .unwrap()
                .reply()
                .unwrap();
            asks.value32().is_some_and(|mut v| v.any(|a| a == delete))
        })
        .collect();
    assert!(!windows.is_empty(), "no window takes WM_DELETE_WINDOW");

    // The window shows the frame the screenshot saved (nothing moves, so
    // every frame is the same), pixel for pixel: the copy to the swapchain
    // (a blit where the window's channel order differs) changes nothing.
    let saved = read_png(&shot);
    let screen_now = x.screen();
    let shown = windows.iter().any(|&w| {
        let at = conn
            .translate_coordinates(w, root, 0, 0)
            .unwrap()
            .reply()
            .unwrap();
        let (x0, y0) = (at.dst_x as u32, at.dst_y as u32);
        let (differing, worst) = compare_on_screen(&screen_now, &saved, x0, y0);
        eprintln!("window at ({x0}, {y0}): {differing} pixels differ, by up to {worst}");
        differing == 0
    });
    assert!(shown, "the window does not show the screenshot's pixels");

    for &window in &windows {
        let message = ClientMessageEvent::new(32, window, protocols, [delete, 0, 0, 0, 0]);
        conn.send_event(false, window, EventMask::NO_EVENT, message)
            .unwrap();
    }
    conn.flush().unwrap();

    while viewer.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = viewer.kill();
            panic!("the viewer did not end after its window was closed");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = viewer.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("validation"),
        "{}",
        text(&out)
    );
}

/// `aerial view MODEL.obj` shows the scene `aerial render MODEL.obj` draws
/// (camera, lights, ground built around the model), from the first frame.
#[test]
fn a_model_is_viewed_in_the_scene_render_builds_around_it() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("box.obj");
    std::fs::write(
        &model,
        "v -1 0 -1\nv 1 0 -1\nv 1 2 -1\nv -1 2 -1\nv -1 0 1\nv 1 0 1\nv 1 2 1\nv -1 2 1\n\
         f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n",
    )
    .unwrap();
    let shot = dir.path().join("shot.png");
    let x = Xvfb::start();
    x.run_script(
        dir.path(),
        &model,
        &["--width", "160", "--height", "90", "--ground"],
        &format!("0 screenshot {}\n1 quit\n", shot.display()),
    );
    let png = dir.path().join("render.png");
    let out = common::aerial()
        .arg("render")
        .arg(&model)
        .args(["--width", "160", "--height", "90", "--ground", "--validate"])
        .arg("--out")
        .arg(&png)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    let reference = read_png(&png);
    let lit = reference
        .data
        .chunks_exact(4)
        .filter(|p| p[..3] != [0, 0, 0])
        .count();
    assert!(lit > 160 * 90 / 10, "only {lit} pixels drawn");
    assert_eq!(differing_pixels(&read_png(&shot), &reference), 0);
}

/// An interrupt stops the viewer at a safe point with status 130, and the
/// message names the screenshots written before it (they stay, whole).
#[test]
fn an_interrupted_viewer_names_the_screenshots_it_wrote() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let shot = dir.path().join("before.png");
    let script = dir.path().join("stay.txt");
    std::fs::write(&script, format!("2 screenshot {}\n", shot.display())).unwrap();
    let x = Xvfb::start();
    let viewer = common::aerial()
        .arg("view")
        .arg(&scene)
        .args(["--script", script.to_str().unwrap()])
        .args(["--validate", "--present-mode", "immediate"])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(60);
    while !shot.exists() {
        assert!(Instant::now() < deadline, "the viewer drew no frame");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(300));
    // SAFETY: kill(2) on our own child, not yet waited for.
    unsafe { libc::kill(viewer.id() as libc::pid_t, libc::SIGINT) };
    let out = viewer.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("written before it") && stderr.contains(&shot.display().to_string()),
        "{stderr}"
    );
    assert!(read_png(&shot).width > 0);
}
