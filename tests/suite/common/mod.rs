//! Helpers shared by the integration tests: every render here runs under
//! the Khronos validation layer and fails on any message.

#![allow(dead_code)]

use aerial::render::Pixels;
use aerial::render_run::{self, RenderRun, RenderSettings};
use aerial::scene::Scene;
use glam::{DMat4, DVec3, DVec4};
use std::path::Path;

/// Parses a scene written inline in a test.
pub fn scene(toml: &str) -> Scene {
    Scene::from_toml(
        toml,
        "inline test scene",
        Path::new(env!("CARGO_MANIFEST_DIR")),
    )
    .unwrap_or_else(|e| panic!("test scene does not parse: {e}"))
}

/// Renders with validation on and asserts the layer said nothing.
pub fn render(scene: &Scene, keep_hdr: bool) -> RenderRun {
    let run = render_run::render(
        scene,
        &RenderSettings {
            keep_hdr,
            ..validated_settings()
        },
    )
    .unwrap_or_else(|e| panic!("render failed: {e}"));
    assert_no_validation_messages(&run);
    run
}

pub fn assert_no_validation_messages(run: &RenderRun) {
    assert!(
        run.validation.is_empty(),
        "validation messages:\n{}",
        run.validation
            .iter()
            .map(|m| m.to_string())
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// RGBA at pixel (x, y).
pub fn pixel<T: Copy>(p: &Pixels<T>, x: u32, y: u32) -> [T; 4] {
    let i = ((y * p.width + x) * 4) as usize;
    [p.data[i], p.data[i + 1], p.data[i + 2], p.data[i + 3]]
}

/// Fails on a blank or nearly blank image: at least `min_fraction` of the
/// pixels must differ from the top-left (background) pixel, and the image
/// must hold more than a handful of distinct colours.
pub fn assert_not_blank(p: &Pixels<u8>, min_fraction: f64) {
    let bg = pixel(p, 0, 0);
    let total = (p.width * p.height) as usize;
    let differing = p.data.chunks_exact(4).filter(|c| c[..3] != bg[..3]).count();
    let mut colours: Vec<[u8; 3]> = p.data.chunks_exact(4).map(|c| [c[0], c[1], c[2]]).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        differing as f64 >= min_fraction * total as f64,
        "only {differing} of {total} pixels differ from the background"
    );
    assert!(
        colours.len() > 16,
        "only {} distinct colours",
        colours.len()
    );
}

/// The scene the normal- and height-map tests compare against geometry: a
/// diffuse `shape` under one directional light, seen from straight above
/// (48x48, LDR output), with `material` lines added to its material and the
/// object turned by `rotate_z` degrees about +Z.
pub fn tilt_scene(dir: &Path, lighting: &str, material: &str, shape: &str, rotate_z: f32) -> Scene {
    let toml = format!(
        "ambient = [0.05, 0.05, 0.05]\n\
         [output]\nwidth = 48\nheight = 48\nlighting = \"{lighting}\"\n\
         [camera]\neye = [0, 4, 0]\nlook_at = [0, 0, 0]\nup = [0, 0, -1]\nfov_y = 30\n\
         [tone_map]\noperator = \"none\"\n\
         [[lights]]\ntype = \"directional\"\ndirection = [-0.6, -1, 0.3]\nintensity = 0.8\n\
         [[materials]]\nname = \"m\"\nkd = [0.8, 0.8, 0.8]\n{material}\n\
         [[objects]]\nname = \"o\"\nmaterial = \"m\"\nshape = {shape}\n\
         rotate = {{ axis = [0, 0, 1], degrees = {rotate_z} }}\n"
    );
    Scene::from_toml(&toml, "tilt test scene", dir).unwrap_or_else(|e| panic!("{e}"))
}

/// Mean RGB over the centre 8x8 pixels of a 48x48 image.
pub fn centre_rgb(p: &Pixels<u8>) -> [f32; 3] {
    let mut sum = [0.0; 3];
    for y in 20..28 {
        for x in 20..28 {
            let px = pixel(p, x, y);
            for c in 0..3 {
                sum[c] += f32::from(px[c]) / 64.0;
            }
        }
    }
    sum
}

/// Asserts that two colours from [`centre_rgb`] agree within 2/255 per
/// channel: 8-bit map texels quantize a direction to about 0.2 degrees.
pub fn assert_close(a: [f32; 3], b: [f32; 3], what: &str) {
    for c in 0..3 {
        assert!((a[c] - b[c]).abs() <= 2.0, "{what}: {a:?} vs {b:?}");
    }
}

/// The example scene `assets/scenes/NAME`, loaded as `aerial render`
/// loads it.
pub fn example(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Runs `command`, failing the test with its standard error unless it
/// exits 0.
pub fn succeed(command: &mut std::process::Command) -> std::process::Output {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The `aerial` binary built for these tests, ready for arguments,
/// without any job scheduler's variables from the environment the tests
/// run in (a sweep would take them for its shard).
pub fn aerial() -> std::process::Command {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_aerial"));
    for var in [
        "JOB_COMPLETION_INDEX",
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_MIN",
        "SLURM_ARRAY_TASK_COUNT",
    ] {
        command.env_remove(var);
    }
    command
}

/// `aerial bench` of `assets/bench/triangle.toml` at 32×18, `frames`
/// measured frames and no warm-up, under validation: the smallest bench
/// run, ready for more arguments.
pub fn tiny_triangle_bench(frames: u32) -> std::process::Command {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench/triangle.toml");
    let mut command = aerial();
    command
        .arg("bench")
        .arg(scene)
        .args(["--frames", &frames.to_string()])
        .args([
            "--warmup",
            "0",
            "--width",
            "32",
            "--height",
            "18",
            "--validate",
        ]);
    command
}

/// The world-space ray through the centre of pixel (x, y): two points of
/// the pixel unprojected with the inverse view-projection in f64.
pub fn pixel_ray(scene: &Scene, x: u32, y: u32) -> DVec3 {
    let (w, h) = (scene.output.width, scene.output.height);
    let vp = scene
        .camera
        .view_projection(scene.output.aspect())
        .as_dmat4();
    let inverse: DMat4 = vp.inverse();
    let ndc_x = (f64::from(x) + 0.5) / f64::from(w) * 2.0 - 1.0;
    let ndc_y = (f64::from(y) + 0.5) / f64::from(h) * 2.0 - 1.0;
    let unproject = |depth: f64| {
        let p = inverse * DVec4::new(ndc_x, ndc_y, depth, 1.0);
        p.truncate() / p.w
    };
    (unproject(0.5) - unproject(1.0)).normalize()
}

/// Pixel (x, y) of an HDR image as f64 RGB.
pub fn hdr_pixel(p: &Pixels<f32>, x: u32, y: u32) -> DVec3 {
    let c = pixel(p, x, y);
    DVec3::new(c[0].into(), c[1].into(), c[2].into())
}

/// The whole scene moved by `offset`: camera, point lights and objects
/// (what the camera sees is unchanged, up to rounding).
#[allow(dead_code)]
pub fn translated(mut scene: Scene, offset: DVec3) -> Scene {
    scene.camera.eye += offset;
    scene.camera.look_at += offset;
    for light in &mut scene.lights {
        if let aerial::scene::Light::Point { position, .. } = light {
            *position += offset;
        }
    }
    for object in &mut scene.objects {
        object.transform.translate += offset;
    }
    scene
}

/// A fresh, empty folder for one test, named by its `area`, `name` and
/// this process (so concurrent runs do not meet); whatever an earlier run
/// left there is removed first.
#[allow(dead_code)]
pub fn fresh_dir(area: &str, name: &str) -> std::path::PathBuf {
    let dir = absent_dir(area, name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Like [`fresh_dir`], but the folder does not exist yet: for commands
/// that must create it themselves.
#[allow(dead_code)]
pub fn absent_dir(area: &str, name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("aerial-{area}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A temporary folder for one test (`tempfile`'s, removed on drop), with
/// the path of a file in it and a sorted listing.
#[allow(dead_code)]
pub struct Scratch(tempfile::TempDir);

#[allow(dead_code)]
impl Scratch {
    pub fn new() -> Scratch {
        Scratch(tempfile::tempdir().unwrap())
    }

    /// The path of `name` inside the folder.
    pub fn path(&self, name: &str) -> std::path::PathBuf {
        self.0.path().join(name)
    }

    /// The names in the folder, sorted.
    pub fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(self.0.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

/// A sweep's CSV as one map (column name -> cell) per row. The sweep's
/// values hold no commas or quotes, so a plain split is enough.
#[allow(dead_code)]
pub fn read_csv(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{l}");
            header
                .iter()
                .zip(cells)
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

/// A Vulkan context with the validation layer's every check on, for tests
/// that drive a `Renderer` (or the context) by hand and read its log.
pub fn validated_context() -> std::sync::Arc<aerial::vk::Context> {
    aerial::vk::Context::new(&aerial::vk::ContextOptions {
        validate: aerial::vk::validation::Validation::All,
        device: None,
        display: None,
        ..Default::default()
    })
    .expect("a Vulkan device with the validation layer")
}

/// One frame, no warm-up, under validation with every check on: the
/// settings of the suite's renders.
pub fn validated_settings() -> RenderSettings {
    RenderSettings {
        validate: aerial::vk::validation::Validation::All,
        device: None,
        warmup: 0,
        frames: 1,
        keep_hdr: false,
        empty_pass_between_frames: false,
        ..Default::default()
    }
}

/// `values` (linear RGBA, one row) tone-mapped on the GPU by the tone-map
/// subpass, under validation (any message fails), as 8-bit RGBA.
#[allow(dead_code)]
pub fn tone_map_on_gpu(
    values: &[[f32; 4]],
    operator: aerial::scene::ToneMapOperator,
    exposure: f32,
) -> Vec<[u8; 4]> {
    let image = Pixels {
        width: values.len() as u32,
        height: 1,
        data: values.iter().flatten().copied().collect(),
    };
    let run = render_run::run(
        aerial::render_run::RunSource::HdrImage(
            &image,
            aerial::scene::ToneMap {
                operator,
                exposure: aerial::scene::Exposure::Fixed(exposure),
                bloom: None,
            },
        ),
        &validated_settings(),
        &mut || {},
    )
    .expect("tone map runs");
    assert_no_validation_messages(&run);
    run.output
        .data
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect()
}

/// Runs `aerial args` and returns its output and its own peak resident
/// memory (`VmHWM`, read while it runs: a high-water mark, so a late read
/// still holds the peak; not the child's rusage, which would start from
/// this large process's peak).
pub fn peak_memory(args: &[&std::ffi::OsStr]) -> (std::process::Output, u64) {
    let child = aerial()
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let status = format!("/proc/{}/status", child.id());
    let done = std::sync::atomic::AtomicBool::new(false);
    let mut peak = 0u64;
    let out = std::thread::scope(|scope| {
        let waiter = scope.spawn(|| {
            let out = child.wait_with_output().unwrap();
            done.store(true, std::sync::atomic::Ordering::SeqCst);
            out
        });
        while !done.load(std::sync::atomic::Ordering::SeqCst) {
            let hwm = std::fs::read_to_string(&status).ok().and_then(|s| {
                let line = s.lines().find(|l| l.starts_with("VmHWM:"))?.to_owned();
                line.split_whitespace().nth(1)?.parse::<u64>().ok()
            });
            peak = peak.max(hwm.unwrap_or(0) * 1024);
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        waiter.join().unwrap()
    });
    assert!(peak > 0, "no reading of the child's memory");
    (out, peak)
}
