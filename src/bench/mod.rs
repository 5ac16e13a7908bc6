//! Benchmarks: render scenes for a number of frames and summarise the
//! per-pass GPU time (timestamps) and whole-frame CPU time, next to the
//! empty pass (the driver's floor) at the same resolution.
//!
//! The library side does the measuring ([`run`]), the report types with
//! their JSON form ([`report`]) and the baseline comparison ([`baseline`]),
//! so tests and other tools can use them without the command line; the
//! `aerial bench` subcommand only parses arguments and prints.

pub mod baseline;
pub mod report;

pub use baseline::{compare, BaselineComparison, RatioRow, RowKey};
pub use report::{
    BenchReport, DeviceRecord, EmptyPassReport, PassReport, Resolution, SceneReport, CPU_FRAME,
    FORMAT, GPU_TOTAL,
};

use crate::app::{self, RenderRun, RenderSettings, RunError};
use crate::render::empty_pass;
use crate::report::stats::{summarise_passes, PassTimesError, Summary};
use crate::scene::{knob_settings, Scene, SceneError};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// The commit this binary was built from (see `build.rs`).
pub const COMMIT: &str = env!("AERIAL_COMMIT");

/// Why a benchmark could not run or a report could not be read.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    // The inner errors are shown in Display (not chained as a source), so
    // every message names the run or file once, however it is printed.
    #[error("{run}: {error}")]
    Render { run: String, error: RunError },
    #[error("{run}: {error}")]
    Validation {
        run: String,
        error: crate::vk::validation::ValidationFailed,
    },
    #[error("{run}: {what} has no finite samples")]
    BadSamples { run: String, what: String },
    #[error("{}: {error}", .path.display())]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error("{}: {reason}", .path.display())]
    Json { path: PathBuf, reason: String },
    #[error("{}: given twice; each scene file may appear once", .0.display())]
    DuplicateScene(PathBuf),
    #[error("--frames: must be at least 1")]
    NoFrames,
}

/// How every run of a benchmark is done.
#[derive(Clone, Debug)]
pub struct BenchSettings {
    /// Frames submitted and discarded before measuring.
    pub warmup: u32,
    /// Frames measured (at least 1).
    pub frames: u32,
    pub validate: crate::vk::validation::Validation,
    pub device: Option<String>,
}

/// A scene to benchmark: its file, the file's hash, and the scene as
/// loaded, which the caller may still change (size, knobs) before [`run`].
#[derive(Clone, Debug)]
pub struct BenchScene {
    pub path: PathBuf,
    /// SHA-256 of the file's bytes, lowercase hex.
    pub sha256: String,
    pub scene: Scene,
}

impl BenchScene {
    /// Reads the file once, so the hash is of exactly the bytes parsed.
    pub fn load(path: &Path) -> Result<BenchScene, BenchError> {
        let file = path.display().to_string();
        let io = |reason| SceneError::Io {
            file: file.clone(),
            reason,
        };
        let bytes = std::fs::read(path).map_err(io)?;
        let text = std::str::from_utf8(&bytes)
            .map_err(|e| io(std::io::Error::new(std::io::ErrorKind::InvalidData, e)))?;
        let base_dir = path.parent().unwrap_or_else(|| Path::new(""));
        let scene = Scene::from_toml(text, &file, base_dir)?;
        Ok(BenchScene {
            path: path.to_path_buf(),
            sha256: sha256_hex(&bytes),
            scene,
        })
    }

    fn resolution(&self) -> Resolution {
        Resolution {
            width: self.scene.output.width,
            height: self.scene.output.height,
        }
    }
}

/// Lowercase hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Receives progress while [`run`] works; every method defaults to nothing.
pub trait Progress {
    /// Called once, first, with the number of frames (warm-up included)
    /// the whole benchmark will submit.
    fn start(&mut self, _total_frames: u64) {}
    /// A run (a scene, or the empty pass at one resolution) begins.
    fn run(&mut self, _label: &str) {}
    /// One frame was submitted and finished.
    fn frame(&mut self) {}
}

/// No progress reporting.
impl Progress for () {}

/// Benchmarks the empty pass at every resolution the scenes use, then each
/// scene, each on its own device (like `aerial render`), and returns the
/// report. Fails on the first error, and under validation on the first run
/// with any validation message.
pub fn run(
    scenes: &[BenchScene],
    settings: &BenchSettings,
    progress: &mut dyn Progress,
) -> Result<BenchReport, BenchError> {
    if settings.frames == 0 {
        return Err(BenchError::NoFrames);
    }
    for (i, s) in scenes.iter().enumerate() {
        if scenes[..i].iter().any(|t| t.path == s.path) {
            return Err(BenchError::DuplicateScene(s.path.clone()));
        }
    }
    let mut resolutions: Vec<Resolution> = Vec::new();
    for s in scenes {
        if !resolutions.contains(&s.resolution()) {
            resolutions.push(s.resolution());
        }
    }
    let runs = (resolutions.len() + scenes.len()) as u64;
    progress.start(runs * (settings.warmup as u64 + settings.frames as u64));
    let render_settings = RenderSettings {
        validate: settings.validate,
        device: settings.device.clone(),
        warmup: settings.warmup,
        frames: settings.frames,
        keep_hdr: false,
        empty_pass_between_frames: true,
    };

    let mut device = None;
    let mut empty_passes = Vec::new();
    for resolution in resolutions {
        let label = baseline::empty_pass_scene(resolution);
        progress.run(&label);
        let run = app::render_empty_pass(
            resolution.width,
            resolution.height,
            &render_settings,
            &mut || progress.frame(),
        )
        .map_err(|error| BenchError::Render {
            run: label.clone(),
            error,
        })?;
        check_validation(&label, &run)?;
        let (mut passes, _, cpu_frame) = summarise(&label, &run)?;
        device.get_or_insert_with(|| DeviceRecord::from(&run.device));
        empty_passes.push(EmptyPassReport {
            resolution,
            gpu: passes.pop(),
            cpu_frame,
        });
    }

    let mut reports = Vec::new();
    for s in scenes {
        let label = s.path.display().to_string();
        progress.run(&label);
        let run = app::render_with_progress(&s.scene, &render_settings, &mut || progress.frame())
            .map_err(|error| BenchError::Render {
            run: label.clone(),
            error,
        })?;
        check_validation(&label, &run)?;
        let (mut passes, mut gpu_total, cpu_frame) = summarise(&label, &run)?;
        // The floor is the empty pass timed between this scene's frames:
        // on a CPU driver the machine's speed drifts by more than 10 %
        // within seconds, and a floor measured in other seconds moved the
        // ratio by up to 2x between identical runs.
        let between = run
            .empty_pass_frames
            .iter()
            .filter_map(|f| f.pass_ms.first().copied())
            .collect::<Vec<f64>>();
        let empty_pass_between_frames = if between.is_empty() {
            None
        } else {
            Some(PassReport {
                name: empty_pass::PASS_NAME.to_string(),
                ms: Summary::of(&between).ok_or_else(|| BenchError::BadSamples {
                    run: label.clone(),
                    what: "empty pass between frames".to_string(),
                })?,
                empty_pass_multiple: None,
            })
        };
        let floor = empty_pass_between_frames
            .as_ref()
            .map(|e| e.ms.median)
            .filter(|m| *m > 0.0);
        if let Some(floor) = floor {
            for p in passes.iter_mut().chain(gpu_total.as_mut()) {
                p.empty_pass_multiple = Some(p.ms.median / floor);
            }
        }
        reports.push(SceneReport {
            file: label,
            sha256: s.sha256.clone(),
            resolution: s.resolution(),
            triangles: (0..s.scene.objects.len())
                .map(|i| s.scene.object_mesh(i).triangle_count() as u64)
                .sum(),
            knobs: knob_settings(&s.scene)
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
            passes,
            gpu_total,
            cpu_frame,
            empty_pass_between_frames,
            asset_warnings: s.scene.warnings.len(),
        });
        device.get_or_insert_with(|| DeviceRecord::from(&run.device));
    }

    Ok(BenchReport {
        format: FORMAT.to_string(),
        commit: COMMIT.to_string(),
        aerial_version: env!("CARGO_PKG_VERSION").to_string(),
        build: if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
        .to_string(),
        // Every run above succeeded, and there is at least one when a scene
        // was given; with none, nothing ran and no device was opened.
        device: device.unwrap_or_else(|| DeviceRecord {
            name: "none".into(),
            driver_name: String::new(),
            driver_info: String::new(),
            driver_version: 0,
            api_version: String::new(),
        }),
        warmup: settings.warmup,
        frames: settings.frames,
        validate: settings.validate.is_on(),
        empty_passes,
        scenes: reports,
    })
}

fn check_validation(label: &str, run: &RenderRun) -> Result<(), BenchError> {
    crate::vk::validation::check(&run.validation).map_err(|error| BenchError::Validation {
        run: label.to_string(),
        error,
    })
}

/// Per-pass GPU rows, the GPU total row (both only with timestamps) and
/// the CPU frame row of one run.
fn summarise(
    label: &str,
    run: &RenderRun,
) -> Result<(Vec<PassReport>, Option<PassReport>, PassReport), BenchError> {
    let bad = |what: &str| BenchError::BadSamples {
        run: label.to_string(),
        what: what.to_string(),
    };
    let pass_report = |name: &str, ms: Summary| PassReport {
        name: name.to_string(),
        ms,
        empty_pass_multiple: None,
    };
    let gpu = summarise_passes(&run.passes, run.frames.iter().map(|f| f.pass_ms.as_slice()))
        .map_err(|e| match e {
            PassTimesError::Pass(name) => bad(&name),
            PassTimesError::Total => bad(GPU_TOTAL),
        })?;
    let (passes, gpu_total) = match gpu {
        Some(gpu) => (
            gpu.passes
                .iter()
                .map(|(name, ms)| pass_report(name, *ms))
                .collect(),
            Some(pass_report(GPU_TOTAL, gpu.total)),
        ),
        None => (Vec::new(), None),
    };
    let cpu: Vec<f64> = run.frames.iter().map(|f| f.cpu_ms).collect();
    let cpu_frame = pass_report(CPU_FRAME, Summary::of(&cpu).ok_or_else(|| bad(CPU_FRAME))?);
    Ok((passes, gpu_total, cpu_frame))
}

#[cfg(test)]
mod tests;
