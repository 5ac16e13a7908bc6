//! A mutation fuzzer for the input readers: the scene loader, the OBJ/MTL
//! loader with smoothing and tangent frames, the texture
//! readers (PNG and JPEG: header inspection and decoding as the renderer
//! does them, PNG metadata chunks, the image comparison's decoder) and the
//! OpenEXR readers (the tone-map input and the image comparison's decoder).
//!
//! Why this tool: it runs on stable Rust with nothing to install (cargo
//! fuzz needs a nightly compiler; AFL needs its own toolchain), so anyone
//! can run it and CI keeps it compiling and working. It is not coverage
//! guided, so its mutations are aimed: starting from real inputs (the
//! example scenes and bad scenes, PNG and EXR files the project writes),
//! it flips, inserts, deletes and duplicates bytes, splices two inputs, and
//! swaps numbers for extreme ones (0, -1, 1e308, NaN, u32 and i64 limits),
//! which reach the value checks a random byte rarely does.
//!
//! Each input must give `Ok` or `Err`, never a panic (or an abort, which
//! ends the run). `cargo test --test suite fuzz::` runs a short smoke run; the long
//! run is
//!
//! ```sh
//! CARGO_PROFILE_RELEASE_OVERFLOW_CHECKS=true AERIAL_FUZZ_ITERATIONS=1000000 \
//!     cargo test --release --test suite fuzz:: -- --ignored --nocapture
//! ```
//!
//! (`AERIAL_FUZZ_TARGETS=scene,obj,png,exr` picks targets, `AERIAL_FUZZ_SEED`
//! the seed)
//!
//! (overflow checks on, so an arithmetic overflow is a panic here rather
//! than a silently wrong value) and saves any input that panicked to
//! `target/fuzz-crashes/` for replay.

use aerial::image_io::{inspect_texture, read_exr, read_png_text, write_exr, write_png};
use aerial::mesh::obj::{model_meshes, parse_obj, ModelOptions};
use aerial::render::Pixels;
use aerial::report::image_diff::{compare_files, Metric};
use aerial::scene::Scene;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

/// xorshift64*: a small, seedable generator, so a failing run can be
/// repeated exactly from its seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const EXTREMES: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-308",
    "nan",
    "inf",
    "-0.0",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "3e38",
    "1e-45",
    "\"\"",
    "[]",
    "{}",
];

/// One mutation of `input`, using `other` for splicing.
fn mutate(rng: &mut Rng, input: &[u8], other: &[u8]) -> Vec<u8> {
    let mut v = input.to_vec();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        let len = v.len();
        match rng.below(8) {
            0 if len > 0 => {
                let i = rng.below(len);
                v[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                v[i] = rng.next() as u8;
            }
            2 => {
                let i = rng.below(len + 1);
                v.insert(i, rng.next() as u8);
            }
            3 if len > 0 => {
                let i = rng.below(len);
                let n = 1 + rng.below(16.min(len - i));
                v.drain(i..i + n);
            }
            4 if len > 0 => {
                // Duplicate a chunk (repeated keys, tables, PNG chunks).
                let i = rng.below(len);
                let n = 1 + rng.below(64.min(len - i));
                let chunk = v[i..i + n].to_vec();
                let at = rng.below(v.len() + 1);
                v.splice(at..at, chunk);
            }
            5 if !other.is_empty() => {
                // Splice: head of this input, tail of the other.
                let cut = rng.below(len + 1);
                let from = rng.below(other.len());
                v.truncate(cut);
                v.extend_from_slice(&other[from..]);
            }
            6 => {
                // Replace a number (a run of digits) with an extreme value.
                let starts: Vec<usize> = (0..len)
                    .filter(|&i| v[i].is_ascii_digit() && (i == 0 || !v[i - 1].is_ascii_digit()))
                    .collect();
                if !starts.is_empty() {
                    let s = starts[rng.below(starts.len())];
                    let mut e = s;
                    while e < v.len() && (v[e].is_ascii_digit() || v[e] == b'.') {
                        e += 1;
                    }
                    let x = EXTREMES[rng.below(EXTREMES.len())].as_bytes();
                    v.splice(s..e, x.iter().copied());
                }
            }
            _ if len > 4 => {
                // Overwrite a 32-bit field (sizes and offsets in binary headers).
                let i = rng.below(len - 3);
                let x = [0u32, 1, 0x7FFF_FFFF, 0xFFFF_FFFF, 100_000, 16385][rng.below(6)];
                v[i..i + 4].copy_from_slice(&x.to_le_bytes());
            }
            _ => {}
        }
    }
    v
}

/// Runs `target` on `iterations` mutations of `seeds`; returns how many
/// inputs panicked (each saved under `crash_dir`).
fn fuzz(
    name: &str,
    seeds: &[Vec<u8>],
    iterations: u64,
    seed: u64,
    crash_dir: &Path,
    mut target: impl FnMut(&[u8]),
) -> usize {
    assert!(!seeds.is_empty(), "{name}: no seed inputs");
    let mut rng = Rng(seed | 1);
    let mut crashes = 0;
    let mut pool: Vec<Vec<u8>> = seeds.to_vec();
    for i in 0..iterations {
        let a = rng.below(pool.len());
        let b = rng.below(pool.len());
        let input = mutate(&mut rng, &pool[a], &pool[b]);
        let outcome = catch_unwind(AssertUnwindSafe(|| target(&input)));
        if outcome.is_err() {
            crashes += 1;
            std::fs::create_dir_all(crash_dir).unwrap();
            let path = crash_dir.join(format!("{name}-{seed}-{i}.bin"));
            std::fs::write(&path, &input).unwrap();
            eprintln!("{name}: input {i} panicked; saved to {}", path.display());
        }
        // Keep some mutants as new starting points, so mutations compound.
        if rng.below(64) == 0 && input.len() < 1 << 16 {
            if pool.len() < 256 {
                pool.push(input);
            } else {
                let slot = seeds.len() + rng.below(pool.len() - seeds.len());
                pool[slot] = input;
            }
        }
    }
    crashes
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every scene file the project ships or tests with.
fn scene_seeds() -> Vec<Vec<u8>> {
    let mut seeds = Vec::new();
    for dir in [
        "assets/scenes",
        "assets/bench",
        "assets/sweep",
        "tests/bad_scenes",
    ] {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        paths.sort();
        seeds.extend(paths.iter().map(|p| std::fs::read(p).unwrap()));
    }
    seeds
}

/// Small PNG and EXR files as the renderer writes them, plus the repository's.
fn image_seeds(dir: &Path) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
    let pixels = |w: u32, h: u32| Pixels {
        width: w,
        height: h,
        data: (0..w * h * 4).map(|i| (i % 251) as u8).collect::<Vec<u8>>(),
    };
    let mut pngs = Vec::new();
    for (w, h) in [(1, 1), (4, 3), (17, 5)] {
        let path = dir.join(format!("seed_{w}x{h}.png"));
        write_png(
            &path,
            &pixels(w, h),
            &[("aerial:device", "fuzz seed".to_string())],
        )
        .unwrap();
        pngs.push(std::fs::read(&path).unwrap());
    }
    pngs.push(std::fs::read(root().join("assets/textures/checker.png")).unwrap());
    // JPEG seeds share the texture target: textures are PNG or JPEG,
    // recognised by content.
    for (w, h) in [(8, 8), (13, 5)] {
        let img = image::RgbImage::from_fn(w, h, |x, y| {
            image::Rgb([(x * 17) as u8, (y * 29) as u8, 90])
        });
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
        pngs.push(bytes);
    }
    let mut exrs = Vec::new();
    for (w, h) in [(1, 1), (3, 2), (8, 8)] {
        let path = dir.join(format!("seed_{w}x{h}.exr"));
        let image = Pixels {
            width: w,
            height: h,
            data: (0..w * h * 4).map(|i| i as f32 * 0.37 - 1.0).collect(),
        };
        write_exr(&path, &image).unwrap();
        exrs.push(std::fs::read(&path).unwrap());
    }
    (pngs, exrs)
}

/// Whether `target` is selected by `AERIAL_FUZZ_TARGETS` (a comma-separated
/// list of scene, obj, png, exr; all when unset).
fn selected(target: &str) -> bool {
    std::env::var("AERIAL_FUZZ_TARGETS").map_or(true, |v| v.split(',').any(|t| t.trim() == target))
}

/// Fuzzes every selected target for `iterations` inputs each, printing each
/// target's time; returns the total number of panicking inputs.
fn run_all(iterations: u64, seed: u64) -> usize {
    let work = tempfile::tempdir().unwrap();
    let crash_dir = root().join("target/fuzz-crashes");
    // Panics are expected to be caught and counted here; the default hook
    // would print a backtrace for each.
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut crashes = 0;

    let timed = |name: &str, run: &mut dyn FnMut() -> usize| {
        let start = std::time::Instant::now();
        let n = run();
        println!(
            "{name}: {iterations} inputs, {n} panicked, {:.1} s",
            start.elapsed().as_secs_f64()
        );
        n
    };

    if selected("scene") {
        let scenes = scene_seeds();
        let base = root().join("assets/scenes");
        crashes += timed("scene", &mut || {
            fuzz("scene", &scenes, iterations, seed, &crash_dir, |input| {
                let text = String::from_utf8_lossy(input);
                let _ = Scene::from_toml(&text, "fuzz.toml", &base);
            })
        });
    }
    if selected("obj") {
        let models = root().join("assets/models");
        let mut seeds: Vec<Vec<u8>> = Vec::new();
        for name in ["cut_sphere.obj", "cut_torus.obj"] {
            seeds.push(std::fs::read(models.join(name)).unwrap());
        }
        // Small hand-made cases: polygons, negative indices, missing parts.
        seeds.push(
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nf 1/1 2/2 3/1 4/2\n".to_vec(),
        );
        seeds.push(b"o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf -3//1 -2//1 -1//1\n".to_vec());
        crashes += timed("obj", &mut || {
            fuzz("obj", &seeds, iterations, seed, &crash_dir, |input| {
                let text = String::from_utf8_lossy(input);
                if let Ok(model) = parse_obj(&text, "fuzz.obj", &models) {
                    let _ = model_meshes(&model, &ModelOptions::default(), "fuzz.obj");
                }
            })
        });
    }
    let (pngs, exrs) = image_seeds(work.path());
    let input_path = work.path().join("input");
    if selected("png") {
        let reference = work.path().join("seed_4x3.png");
        crashes += timed("png", &mut || {
            fuzz("png", &pngs, iterations, seed, &crash_dir, |input| {
                std::fs::write(&input_path, input).unwrap();
                // As the renderer does: the header first, then a full
                // decode of what is small enough.
                if let Ok(info) = inspect_texture(&input_path) {
                    if u64::from(info.width) * u64::from(info.height) <= 1 << 20 {
                        let _ = aerial::image_io::decode(&input_path);
                    }
                }
                let _ = read_png_text(&input_path);
                let _ = compare_files(&reference, &input_path, Metric::Rmse);
            })
        });
    }
    if selected("exr") {
        let reference = work.path().join("seed_3x2.exr");
        crashes += timed("exr", &mut || {
            fuzz("exr", &exrs, iterations, seed, &crash_dir, |input| {
                std::fs::write(&input_path, input).unwrap();
                let _ = read_exr(&input_path);
                let _ = compare_files(&reference, &input_path, Metric::Rmse);
            })
        });
    }
    std::panic::set_hook(previous);
    crashes
}

/// A short run on every target, so the harness keeps compiling and the
/// readers stay panic-free on the inputs it reaches quickly.
#[test]
fn readers_survive_a_short_fuzz_run() {
    assert_eq!(run_all(1500, 0x5EED), 0, "see target/fuzz-crashes/");
}

/// The long run: `AERIAL_FUZZ_ITERATIONS` inputs per target (default 10^6)
/// and `AERIAL_FUZZ_SEED`.
#[test]
#[ignore = "long; run explicitly (see the module documentation)"]
fn readers_survive_a_long_fuzz_run() {
    let iterations = std::env::var("AERIAL_FUZZ_ITERATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let seed = std::env::var("AERIAL_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let start = std::time::Instant::now();
    let crashes = run_all(iterations, seed);
    println!(
        "seed {seed}: {crashes} panicked in all, {:.0} s",
        start.elapsed().as_secs_f64()
    );
    assert_eq!(crashes, 0, "see target/fuzz-crashes/");
}
