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

pub use baseline::{compare, BaselineComparison, RatioRow, RowKey, Verdict};
pub use report::{
    BenchReport, CountReport, DeviceRecord, EmptyPassReport, Metric, PassReport, Resolution,
    SceneReport, CPU_FRAME, FORMAT, GPU_TOTAL,
};

use crate::render::empty_pass;
use crate::render_run::{self, RenderRun, RenderSettings, RunError, RunSource};
use crate::report::stats::{summarise_passes, PassTimesError, Summary};
use crate::scene::{knob_settings, Scene, SceneError};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

pub use crate::COMMIT;

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
    /// An input that is not a regular file, or is longer than its bound.
    #[error("{}: {reason}", .path.display())]
    Input { path: PathBuf, reason: String },
    #[error(
        "{}: given twice (also as {}); each scene file may appear once",
        .second.display(),
        .first.display()
    )]
    DuplicateScene { first: PathBuf, second: PathBuf },
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
    /// Where the device's pipeline cache is kept between runs.
    pub pipeline_cache: crate::vk::PipelineCacheStore,
    /// What to measure; time always is (see [`Metric`]).
    pub metrics: Vec<Metric>,
    /// Count instructions in this process, which must have been started
    /// under callgrind by [`crate::callgrind::spawn_counting_run`]:
    /// every run counts each frame prefix instead of timing frames, and the
    /// report's rows carry [`PassReport::instructions`].
    pub counting: bool,
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
    /// The file must be a regular file of at most
    /// [`MAX_SCENE_FILE_BYTES`](crate::scene::MAX_SCENE_FILE_BYTES), as
    /// for `aerial render`.
    pub fn load(path: &Path) -> Result<BenchScene, BenchError> {
        let file = path.display().to_string();
        let text = read_bounded_text(path, crate::scene::MAX_SCENE_FILE_BYTES, "a scene file")?;
        let base_dir = path.parent().unwrap_or_else(|| Path::new(""));
        let scene = Scene::from_toml(&text, &file, base_dir)?;
        Ok(BenchScene {
            path: path.to_path_buf(),
            sha256: sha256_hex(text.as_bytes()),
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

/// The text of the input file `path` (`what` names it in messages, e.g.
/// "a benchmark report"), read up to `limit` bytes. A path that is not a
/// regular file (a folder, a FIFO, a device such as `/dev/zero`, a link to
/// one) is refused before it is opened, so an endless or blocking input
/// can neither fill memory nor hang the run; a longer file is refused
/// naming the bound.
pub(crate) fn read_bounded_text(path: &Path, limit: u64, what: &str) -> Result<String, BenchError> {
    use crate::safe_files::TextReadError;
    let bound = crate::budget::Bytes(limit);
    let refuse = |reason: String| BenchError::Input {
        path: path.to_path_buf(),
        reason,
    };
    if let Some(problem) = crate::safe_files::input_file_problem(path) {
        // The problem ends with the path, which the error starts with.
        let shown = path.display().to_string();
        let problem = problem
            .strip_suffix(&shown)
            .map_or(problem.as_str(), |p| p.trim_end_matches([':', ' ']));
        // Something is there, but not a file to read: say what is read.
        return Err(refuse(if std::fs::metadata(path).is_ok() {
            format!("{problem}; {what} is read from a regular file of at most {bound}")
        } else {
            problem.to_string()
        }));
    }
    crate::safe_files::read_text(path, limit).map_err(|e| match e {
        TextReadError::Io(error) => BenchError::Io {
            path: path.to_path_buf(),
            error,
        },
        TextReadError::TooLong(_) => refuse(format!(
            "longer than {bound}, the most read of {what} (reading stopped there)"
        )),
        e @ TextReadError::NotUtf8 { .. } => refuse(format!("{e}; {what} is UTF-8 text")),
    })
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
    refuse_duplicate_scenes(scenes)?;
    let mut resolutions: Vec<Resolution> = Vec::new();
    for s in scenes {
        if !resolutions.contains(&s.resolution()) {
            resolutions.push(s.resolution());
        }
    }
    let runs = (resolutions.len() + scenes.len()) as u64;
    progress.start(runs * (settings.warmup as u64 + settings.frames as u64));
    let render_settings = render_settings(settings);

    let mut device = None;
    let mut empty_passes = Vec::new();
    for resolution in resolutions {
        let empty_pass = bench_empty_pass(resolution, &render_settings, progress, &mut device)?;
        empty_passes.push(empty_pass);
    }
    let mut reports = Vec::new();
    for s in scenes {
        reports.push(bench_scene(s, &render_settings, progress, &mut device)?);
    }

    let mut report = BenchReport {
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
        metrics: settings.metrics.clone(),
        empty_passes,
        scenes: reports,
    };
    set_multiples(&mut report);
    Ok(report)
}

/// Refuses a scene given twice. Compared as files, so `s.toml` and
/// `./s.toml` (or a link to it) are one scene: the report would list it
/// twice under two names.
fn refuse_duplicate_scenes(scenes: &[BenchScene]) -> Result<(), BenchError> {
    for (i, s) in scenes.iter().enumerate() {
        if let Some(t) = scenes[..i]
            .iter()
            .find(|t| crate::safe_files::same_file(&t.path, &s.path))
        {
            return Err(BenchError::DuplicateScene {
                first: t.path.clone(),
                second: s.path.clone(),
            });
        }
    }
    Ok(())
}

/// The settings of every run of the benchmark.
fn render_settings(settings: &BenchSettings) -> RenderSettings {
    RenderSettings {
        validate: settings.validate,
        device: settings.device.clone(),
        pipeline_cache: settings.pipeline_cache.clone(),
        warmup: settings.warmup,
        frames: settings.frames,
        keep_hdr: false,
        // Counted runs need no floor timed between frames: the empty
        // pass's count does not drift.
        empty_pass_between_frames: !settings.counting,
        count_work: settings.metrics.contains(&Metric::Work) && !settings.counting,
        count_instructions: settings.counting,
    }
}

/// Benchmarks the empty pass at `resolution`; `device` is set to the run's
/// device if it is the first run.
fn bench_empty_pass(
    resolution: Resolution,
    render_settings: &RenderSettings,
    progress: &mut dyn Progress,
    device: &mut Option<DeviceRecord>,
) -> Result<EmptyPassReport, BenchError> {
    let label = baseline::empty_pass_scene(resolution);
    progress.run(&label);
    let run = render_run::run(
        RunSource::EmptyPass {
            width: resolution.width,
            height: resolution.height,
        },
        render_settings,
        &mut || progress.frame(),
    )
    .map_err(|error| BenchError::Render {
        run: label.clone(),
        error,
    })?;
    check_validation(&label, &run)?;
    let (mut passes, _, cpu_frame) = summarise(&label, &run)?;
    device.get_or_insert_with(|| DeviceRecord::from(&run.device));
    if let Some(c) = passes.first_mut().and_then(|p| p.instructions.as_mut()) {
        c.empty_pass_multiple = Some(1.0);
    }
    Ok(EmptyPassReport {
        resolution,
        gpu: passes.pop(),
        cpu_frame,
    })
}

/// Benchmarks one scene; `device` is set to the run's device if it is the
/// first run.
fn bench_scene(
    s: &BenchScene,
    render_settings: &RenderSettings,
    progress: &mut dyn Progress,
    device: &mut Option<DeviceRecord>,
) -> Result<SceneReport, BenchError> {
    let label = s.path.display().to_string();
    progress.run(&label);
    let run = render_run::run(RunSource::Scene(&s.scene), render_settings, &mut || {
        progress.frame()
    })
    .map_err(|error| BenchError::Render {
        run: label.clone(),
        error,
    })?;
    check_validation(&label, &run)?;
    let (passes, gpu_total, cpu_frame) = summarise(&label, &run)?;
    let between = run
        .empty_pass_frames
        .iter()
        .filter_map(|f| f.pass_ms.first().copied())
        .collect::<Vec<f64>>();
    let empty_pass_between_frames = if between.is_empty() {
        None
    } else {
        Some(PassReport::timed(
            empty_pass::PASS_NAME,
            &between,
            Summary::of(&between).ok_or_else(|| BenchError::BadSamples {
                run: label.clone(),
                what: "empty pass between frames".to_string(),
            })?,
        ))
    };
    let report = SceneReport {
        file: label,
        sha256: s.sha256.clone(),
        resolution: s.resolution(),
        triangles: s.scene.triangle_count(),
        knobs: knob_settings(&s.scene)
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
        passes,
        gpu_total,
        cpu_frame,
        empty_pass_between_frames,
        asset_warnings: s.scene.warnings.len(),
    };
    device.get_or_insert_with(|| DeviceRecord::from(&run.device));
    Ok(report)
}

/// Copies the instruction counts of `counted` (a report of the same scenes
/// from the counting run under valgrind) into `report`'s matching rows.
pub fn merge_counts(report: &mut BenchReport, counted: &BenchReport) {
    fn copy<'a>(to: impl Iterator<Item = &'a mut PassReport>, from: &[&PassReport]) {
        for row in to {
            if let Some(c) = from.iter().find(|c| c.name == row.name) {
                row.instructions = c.instructions.clone();
            }
        }
    }
    for e in &mut report.empty_passes {
        if let Some(c) = counted.empty_pass(e.resolution) {
            copy(e.gpu.iter_mut(), &c.gpu.iter().collect::<Vec<_>>());
        }
    }
    for s in &mut report.scenes {
        if let Some(c) = counted.scenes.iter().find(|c| c.file == s.file) {
            let from: Vec<&PassReport> = c.passes.iter().chain(&c.gpu_total).collect();
            copy(s.passes.iter_mut().chain(s.gpu_total.as_mut()), &from);
        }
    }
    if !report.metrics.contains(&Metric::Instructions) {
        report.metrics.push(Metric::Instructions);
    }
}

/// One report of several runs of the same benchmark (the rounds of
/// `--against`): each row's frames pooled and its summaries and multiples
/// computed again from them. The first report gives everything else.
pub fn pool(reports: &[BenchReport]) -> Result<BenchReport, BenchError> {
    let Some(first) = reports.first() else {
        return Err(BenchError::NoFrames);
    };
    let mut out = first.clone();
    let pool_row = |row: &mut PassReport, from: Vec<&PassReport>| {
        let times: Vec<f64> = from.iter().flat_map(|r| r.samples_ms.clone()).collect();
        if let Some(ms) = Summary::of(&times) {
            row.ms = ms;
            row.samples_ms = times;
        }
        let counts: Vec<u64> = from
            .iter()
            .filter_map(|r| r.instructions.as_ref())
            .flat_map(|c| c.samples.clone())
            .collect();
        if row.instructions.is_some() {
            row.instructions = CountReport::of(counts);
        }
    };
    for e in &mut out.empty_passes {
        let theirs: Vec<&EmptyPassReport> = reports
            .iter()
            .filter_map(|r| r.empty_pass(e.resolution))
            .collect();
        if let Some(gpu) = e.gpu.as_mut() {
            pool_row(gpu, theirs.iter().filter_map(|t| t.gpu.as_ref()).collect());
            if let Some(c) = gpu.instructions.as_mut() {
                c.empty_pass_multiple = Some(1.0);
            }
        }
        pool_row(
            &mut e.cpu_frame,
            theirs.iter().map(|t| &t.cpu_frame).collect(),
        );
    }
    for s in &mut out.scenes {
        let theirs: Vec<&SceneReport> = reports
            .iter()
            .filter_map(|r| r.scenes.iter().find(|t| t.file == s.file))
            .collect();
        for row in s
            .passes
            .iter_mut()
            .chain(s.gpu_total.as_mut())
            .chain(std::iter::once(&mut s.cpu_frame))
        {
            let name = row.name.clone();
            pool_row(
                row,
                theirs
                    .iter()
                    .filter_map(|t| t.rows().find(|p| p.name == name))
                    .collect(),
            );
        }
        if let Some(floor) = s.empty_pass_between_frames.as_mut() {
            pool_row(
                floor,
                theirs
                    .iter()
                    .filter_map(|t| t.empty_pass_between_frames.as_ref())
                    .collect(),
            );
        }
    }
    set_multiples(&mut out);
    Ok(out)
}

/// Each scene row's multiples of the empty pass: its median time over the
/// median of the empty pass timed between its frames, its median count
/// over the empty pass's count at its resolution. The time floor is timed
/// between the scene's frames because on a CPU driver the machine's speed
/// drifts by more than 10 % within seconds, and a floor measured in other
/// seconds moved the ratio by up to 2x between identical runs; counts do
/// not drift.
fn set_multiples(report: &mut BenchReport) {
    for s in &mut report.scenes {
        let floor = s
            .empty_pass_between_frames
            .as_ref()
            .map(|e| e.ms.median)
            .filter(|m| *m > 0.0);
        let count_floor = report
            .empty_passes
            .iter()
            .find(|e| e.resolution == s.resolution)
            .and_then(|e| e.gpu.as_ref()?.instructions.as_ref())
            .map(|c| c.summary.median)
            .filter(|m| *m > 0.0);
        for p in s.passes.iter_mut().chain(s.gpu_total.as_mut()) {
            if let Some(floor) = floor {
                p.empty_pass_multiple = Some(p.ms.median / floor);
            }
            if let (Some(floor), Some(c)) = (count_floor, p.instructions.as_mut()) {
                c.empty_pass_multiple = Some(c.summary.median / floor);
            }
        }
    }
}

fn check_validation(label: &str, run: &RenderRun) -> Result<(), BenchError> {
    crate::vk::validation::check(&run.validation).map_err(|error| BenchError::Validation {
        run: label.to_string(),
        error,
    })
}

/// Per-pass GPU rows, the GPU total row (both only with timestamps) and
/// the CPU frame row of one run, with their work and instruction counts
/// when the run took them.
fn summarise(
    label: &str,
    run: &RenderRun,
) -> Result<(Vec<PassReport>, Option<PassReport>, PassReport), BenchError> {
    let bad = |what: &str| BenchError::BadSamples {
        run: label.to_string(),
        what: what.to_string(),
    };
    let column = |i: usize| -> Vec<f64> {
        run.frames
            .iter()
            .filter_map(|f| f.pass_ms.get(i).copied())
            .collect()
    };
    let gpu = summarise_passes(&run.passes, run.frames.iter().map(|f| f.pass_ms.as_slice()))
        .map_err(|e| match e {
            PassTimesError::Pass(name) => bad(&name),
            PassTimesError::Total => bad(GPU_TOTAL),
        })?;
    let (mut passes, mut gpu_total) = match gpu {
        Some(gpu) => {
            let totals: Vec<f64> = run.frames.iter().map(|f| f.pass_ms.iter().sum()).collect();
            (
                gpu.passes
                    .iter()
                    .enumerate()
                    .map(|(i, (name, ms))| PassReport::timed(name, &column(i), *ms))
                    .collect::<Vec<_>>(),
                Some(PassReport::timed(GPU_TOTAL, &totals, gpu.total)),
            )
        }
        None => (Vec::new(), None),
    };
    // Pipeline statistics are exact: every frame counts the same, so the
    // last frame's stand for all.
    if let Some(work) = run.frames.last().map(|f| &f.work) {
        for (p, w) in passes.iter_mut().zip(work) {
            p.work = Some(*w);
        }
    }
    if !run.instruction_frames.is_empty() {
        let per_pass: Vec<Vec<u64>> = run
            .instruction_frames
            .iter()
            .map(|prefixes| crate::callgrind::pass_counts(prefixes))
            .collect();
        for (i, p) in passes.iter_mut().enumerate() {
            p.instructions =
                CountReport::of(per_pass.iter().filter_map(|f| f.get(i).copied()).collect());
        }
        if let Some(total) = gpu_total.as_mut() {
            total.instructions = CountReport::of(
                run.instruction_frames
                    .iter()
                    .filter_map(|f| f.last().copied())
                    .collect(),
            );
        }
    }
    let cpu: Vec<f64> = run.frames.iter().map(|f| f.cpu_ms).collect();
    let cpu_frame = PassReport::timed(
        CPU_FRAME,
        &cpu,
        Summary::of(&cpu).ok_or_else(|| bad(CPU_FRAME))?,
    );
    Ok((passes, gpu_total, cpu_frame))
}

#[cfg(test)]
mod tests;
