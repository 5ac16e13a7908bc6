//! Error against run time: render every combination of some knob settings,
//! time each one, measure how far its image is from a reference, and find
//! the combinations worth using (the Pareto front).
//!
//! # The reference
//!
//! A combination is compared with the same scene rendered with every *swept*
//! knob at its [`Best`] value:
//!
//! - [`Best::Fixed`]`(v)`: `v`, whether or not the sweep lists it;
//! - [`Best::LastListed`]: the last value listed for that knob in this sweep,
//!   so **list values cheapest first** (e.g. `tessellation=0.25,0.5,1,2`);
//! - [`Best::Unchanged`] (image size): the combination's own value, so both
//!   images always have the same size. Each size then has its own reference.
//!
//! Knobs that are not swept keep the scene's own setting in the combination
//! and in its reference alike: a tessellation sweep of a scene that mixes
//! shading models must not be measured against an all-Phong version of it.
//! Each distinct reference is rendered once. A combination that is its own
//! reference is compared with its own image, so its error is exactly 0.
//!
//! With [`ReferenceKind::Cpu`] the reference is instead the exact image of
//! the combination's *own* scene ([`crate::render::render_reference`]):
//! every knob is applied first, because some (`lights`, `light_cutoff`)
//! change what the exact image is, and the rest (tessellation, HDR format)
//! only change how far the GPU is from it. References are cached by
//! [`ReferenceScene`], everything the CPU renderer reads, so a sweep over
//! tessellation and format renders each size's reference once or, where
//! the tessellation moves a bounding sphere across a light's cutoff, once
//! per light set. No combination is its own reference then, and every
//! error is above 0. A scene the CPU renderer cannot draw (a torus, a
//! texture, ...) is refused before anything is rendered.
//!
//! # Measurements
//!
//! - GPU time: per frame the sum of the pass times; the median (and p95)
//!   over the timed frames, plus the median of each pass. The timed run does
//!   not read the HDR image back: that copy is a cost of measuring, not of
//!   rendering, and as it is twice as large in `rgba32f` it would make that
//!   format look slower than it is. The images come from a second,
//!   single-frame run with the HDR readback on.
//! - `rmse`, the primary error: whole-image RMSE of the linear HDR images
//!   over all pixels and the R, G, B channels (alpha ignored), in the scene's
//!   linear radiance units.
//! - `flip_mean` and `flip_p99`: FLIP of the tone-mapped 8-bit sRGB outputs
//!   (what a viewer sees), mean and 99th percentile over the pixels.
//!
//! See [`super::image_diff`] for the exact metric definitions.
//!
//! # Pareto front
//!
//! A combination is on the front when no other combination is at least as
//! fast and at least as accurate (by `rmse`) and strictly better in one of
//! the two; see [`pareto_front`].
//!
//! Rendering is left to the caller (a closure taking a scene and a [`Job`]),
//! which keeps this module free of Vulkan and lets it be tested without a
//! device.

use super::image_diff::{compare_images, CompareError, ImageRef, Metric};
use super::plot::{self, PlotError, PlotPoint};
use super::stats::Summary;
use crate::render::reference::{ReferenceError, ReferenceScene};
use crate::render::{FrameTiming, Pixels};
use crate::scene::{Best, Knob, KnobError, Scene};
use serde::{Serialize, Serializer};
use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Combinations a sweep may have unless the caller raises the limit: at a
/// few seconds per combination, more is an accident (a typo in a list, one
/// knob too many) rather than a plan.
pub const DEFAULT_MAX_COMBINATIONS: usize = 256;

/// Everything that can stop a sweep. Each message names the knob, value,
/// combination or file involved.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("--knob '{arg}': {reason} (expected NAME=VALUE[,VALUE...])")]
    Syntax { arg: String, reason: &'static str },
    #[error(transparent)]
    Knob(#[from] KnobError),
    #[error("--reference cpu: {what}: {source}")]
    NoCpuReference {
        what: String,
        #[source]
        source: ReferenceError,
    },
    #[error("knob {knob} is given twice; list all its values in one --knob")]
    DuplicateKnob { knob: &'static str },
    #[error("knob {knob}: value '{value}' is listed twice")]
    DuplicateValue { knob: &'static str, value: String },
    #[error("nothing to sweep: give at least one --knob NAME=VALUE[,VALUE...]")]
    NoKnobs,
    #[error("the sweep has {count} combinations, more than the limit of {max} (raise it with --max-combinations)")]
    TooMany { count: String, max: usize },
    #[error("rendering {what} failed: {reason}")]
    Render { what: String, reason: String },
    #[error("{what}: the device recorded no pass timings (no timestamp queries), so there is no GPU time to plot")]
    NoTimings { what: String },
    #[error("{what}: frame timings are not finite numbers")]
    BadTimings { what: String },
    #[error("comparing {what} with its reference: {source}")]
    Compare {
        what: String,
        #[source]
        source: CompareError,
    },
    // The OS error is in the message, not a chained source, so that
    // reporters walking the chain print it once.
    #[error("cannot create output folder {}: {error}", path.display())]
    CreateDir {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error(transparent)]
    Write(CompareError),
    #[error(transparent)]
    File(crate::files::FileError),
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error("cannot serialise the sweep as JSON: {0}")]
    Json(#[from] serde_json::Error),
}

/// One swept knob and its values, in the order given.
#[derive(Clone)]
pub struct Axis {
    pub knob: &'static Knob,
    pub values: Vec<String>,
}

impl std::fmt::Debug for Axis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", self.knob.name, self.values.join(","))
    }
}

impl Axis {
    /// Parses `NAME=VALUE[,VALUE...]`; the knob must exist. Values are
    /// checked against a scene by [`Sweep::new`].
    pub fn parse(arg: &str) -> Result<Axis, SweepError> {
        let syntax = |reason| SweepError::Syntax {
            arg: arg.to_string(),
            reason,
        };
        let (name, list) = arg.split_once('=').ok_or_else(|| syntax("no '='"))?;
        let knob = Knob::find(name.trim())?;
        let mut values: Vec<String> = Vec::new();
        for value in list.split(',').map(str::trim) {
            if value.is_empty() {
                return Err(syntax("empty value"));
            }
            if values.iter().any(|v| v == value) {
                return Err(SweepError::DuplicateValue {
                    knob: knob.name,
                    value: value.to_string(),
                });
            }
            values.push(value.to_string());
        }
        Ok(Axis { knob, values })
    }
}

/// What each combination's error is measured against (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceKind {
    /// The GPU image with every swept knob at its [`Best`] value.
    #[default]
    GpuBest,
    /// The exact CPU image of the combination's own scene.
    Cpu,
}

impl ReferenceKind {
    /// How tables, plots and the CSV name it.
    pub fn name(self) -> &'static str {
        match self {
            ReferenceKind::GpuBest => "gpu_best",
            ReferenceKind::Cpu => "cpu",
        }
    }
}

/// How each combination is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SweepOptions {
    /// Timed frames per combination (at least 1; 0 counts as 1).
    pub frames: u32,
    /// Frames rendered and discarded before the timed ones.
    pub warmup: u32,
    /// Refuse sweeps with more combinations than this.
    pub max_combinations: usize,
    /// What the errors are measured against.
    pub reference: ReferenceKind,
}

impl Default for SweepOptions {
    fn default() -> Self {
        SweepOptions {
            frames: 10,
            warmup: 2,
            max_combinations: DEFAULT_MAX_COMBINATIONS,
            reference: ReferenceKind::GpuBest,
        }
    }
}

/// A render the sweep asks its caller for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Job {
    /// Measure time: `warmup` discarded frames, then `frames` timed ones,
    /// *without* reading the HDR image back (see the module docs).
    Timing { warmup: u32, frames: u32 },
    /// One frame with the HDR image read back, for the error metrics.
    Images,
    /// The exact image of the scene, for [`ReferenceKind::Cpu`]: `hdr` from
    /// [`crate::render::render_reference`] and `output` that image through
    /// the renderer's tone-map pass, so the FLIP columns compare like with
    /// like. `frames` and `passes` are not read.
    Reference,
}

/// What the caller's render closure hands back.
pub struct Rendered {
    /// The device, for the report.
    pub device: String,
    /// Pass names in the order of each `FrameTiming::pass_ms`.
    pub passes: Vec<String>,
    pub frames: Vec<FrameTiming>,
    pub output: Pixels<u8>,
    /// Required for [`Job::Images`] and [`Job::Reference`].
    pub hdr: Option<Pixels<f32>>,
}

/// One combination and the reference it is compared with, as values in
/// the order of the sweep's axes (with a CPU reference, the combination's
/// own values: the reference is the exact image of its own scene).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Combination {
    pub values: Vec<String>,
    pub reference: Vec<String>,
}

/// A validated sweep, ready to run.
pub struct Sweep {
    scene_name: String,
    base: Scene,
    axes: Vec<Axis>,
    combinations: Vec<Combination>,
    options: SweepOptions,
}

/// One measured combination.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Knob name and value, in the order of the sweep's axes.
    #[serde(serialize_with = "ordered_map")]
    pub settings: Vec<(String, String)>,
    /// The settings of the scene the reference image was made from (with a
    /// CPU reference, the row's own).
    #[serde(serialize_with = "ordered_map")]
    pub reference: Vec<(String, String)>,
    /// Whether this combination is its own reference (error 0; never with
    /// a CPU reference).
    pub is_reference: bool,
    /// Median GPU time of each pass, in ms.
    #[serde(serialize_with = "ordered_map")]
    pub pass_median_ms: Vec<(String, f64)>,
    /// Per-frame GPU time (sum of the passes), in ms.
    pub gpu_ms: Summary,
    /// Per-frame CPU time from submit to fence, in ms.
    pub cpu_ms: Summary,
    /// Whole-image RMSE of the linear HDR image against the reference.
    pub rmse: f64,
    /// Mean FLIP of the sRGB output against the reference's.
    pub flip_mean: f64,
    /// 99th percentile of the per-pixel FLIP.
    pub flip_p99: f64,
    /// On the Pareto front of (GPU median, rmse).
    pub pareto: bool,
}

/// A finished sweep: what `sweep.json` holds.
#[derive(Clone, Debug, Serialize)]
pub struct SweepResult {
    pub scene: String,
    pub device: String,
    pub frames: u32,
    pub warmup: u32,
    /// What the errors are measured against: `"gpu_best"` or `"cpu"`.
    pub reference: ReferenceKind,
    /// Swept knob names, in axis order.
    pub knobs: Vec<String>,
    /// Every pass name seen, in frame order.
    pub passes: Vec<String>,
    pub rows: Vec<Row>,
}

/// Serialises `(key, value)` pairs as a JSON object in their own order
/// (serde_json's `Map` would sort the keys).
fn ordered_map<S: Serializer, V: Serialize>(
    pairs: &[(String, V)],
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_map(pairs.iter().map(|(k, v)| (k, v)))
}

impl Sweep {
    /// Checks the axes against `base` (every value is applied to a copy of
    /// the scene, so a bad value fails before anything is rendered) and
    /// lists the combinations, the last axis changing fastest.
    /// `scene_name` is only for the report.
    pub fn new(
        scene_name: impl Into<String>,
        base: Scene,
        axes: Vec<Axis>,
        options: SweepOptions,
    ) -> Result<Sweep, SweepError> {
        if axes.is_empty() {
            return Err(SweepError::NoKnobs);
        }
        let mut seen = HashSet::new();
        for axis in &axes {
            if !seen.insert(axis.knob.name) {
                return Err(SweepError::DuplicateKnob {
                    knob: axis.knob.name,
                });
            }
        }
        // Count in u128 so a typo like 1000 values x 1000 values x ... gives
        // a clear error instead of an overflow or an enormous allocation.
        let count = axes
            .iter()
            .try_fold(1u128, |n, a| n.checked_mul(a.values.len() as u128));
        if count.is_none_or(|c| c > options.max_combinations as u128) {
            return Err(SweepError::TooMany {
                count: count.map_or_else(|| "too many".into(), |c| c.to_string()),
                max: options.max_combinations,
            });
        }
        for axis in &axes {
            let best = match axis.knob.best {
                Best::Fixed(v) => Some(v),
                Best::LastListed | Best::Unchanged => None,
            };
            for value in axis.values.iter().map(String::as_str).chain(best) {
                axis.knob.set(&mut base.clone(), value)?;
            }
        }

        let mut combinations = vec![Vec::new()];
        for axis in &axes {
            combinations = combinations
                .into_iter()
                .flat_map(|prefix: Vec<String>| {
                    axis.values.iter().map(move |v| {
                        let mut c = prefix.clone();
                        c.push(v.clone());
                        c
                    })
                })
                .collect();
        }
        let combinations: Vec<Combination> = combinations
            .into_iter()
            .map(|values| {
                let reference = match options.reference {
                    ReferenceKind::GpuBest => reference_values(&axes, &values),
                    ReferenceKind::Cpu => values.clone(),
                };
                Combination { values, reference }
            })
            .collect();
        let sweep = Sweep {
            scene_name: scene_name.into(),
            base,
            axes,
            combinations,
            options,
        };
        if options.reference == ReferenceKind::Cpu {
            // Refuse a scene the CPU cannot draw now, not after minutes of
            // GPU timing.
            for c in &sweep.combinations {
                sweep.cpu_reference_scene(&c.values)?;
            }
        }
        Ok(sweep)
    }

    /// What the CPU reference of combination `values` depends on.
    fn cpu_reference_scene(&self, values: &[String]) -> Result<ReferenceScene, SweepError> {
        ReferenceScene::new(&self.scene_for(values)?).map_err(|source| SweepError::NoCpuReference {
            what: self.describe(values),
            source,
        })
    }

    pub fn combinations(&self) -> &[Combination] {
        &self.combinations
    }

    /// The base scene with the knobs set to `values` (in axis order).
    pub fn scene_for(&self, values: &[String]) -> Result<Scene, SweepError> {
        let mut scene = self.base.clone();
        for (axis, value) in self.axes.iter().zip(values) {
            axis.knob.set(&mut scene, value)?;
        }
        Ok(scene)
    }

    /// `name=value` pairs for `values`, for labels and errors.
    fn describe(&self, values: &[String]) -> String {
        self.axes
            .iter()
            .zip(values)
            .map(|(a, v)| format!("{}={v}", a.knob.name))
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn pairs(&self, values: &[String]) -> Vec<(String, String)> {
        self.axes
            .iter()
            .zip(values)
            .map(|(a, v)| (a.knob.name.to_string(), v.clone()))
            .collect()
    }

    /// Renders and measures every combination. `render` does the GPU work
    /// for one scene (see [`Job`]); `on_row` is called after each
    /// combination with its index, for progress output.
    pub fn run<E>(
        &self,
        mut render: impl FnMut(&Scene, Job) -> Result<Rendered, E>,
        mut on_row: impl FnMut(usize, &Row),
    ) -> Result<SweepResult, SweepError>
    where
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
        let cpu = self.options.reference == ReferenceKind::Cpu;
        // GPU images kept because they serve as references (none with a
        // CPU reference: then every GPU image is compared once).
        let references: HashSet<&[String]> = self
            .combinations
            .iter()
            .filter(|_| !cpu)
            .map(|c| c.reference.as_slice())
            .collect();
        let mut cache: HashMap<Vec<String>, Rc<Images>> = HashMap::new();
        // CPU references by what they depend on; a short list, searched
        // linearly (`ReferenceScene` holds floats, so it is not `Hash`).
        let mut cpu_cache: Vec<(ReferenceScene, Rc<Images>)> = Vec::new();
        let mut device = String::new();
        let mut passes: Vec<String> = Vec::new();
        let mut rows = Vec::with_capacity(self.combinations.len());

        for (index, c) in self.combinations.iter().enumerate() {
            let what = self.describe(&c.values);
            let scene = self.scene_for(&c.values)?;
            let job = Job::Timing {
                warmup: self.options.warmup,
                frames: self.options.frames.max(1),
            };
            let timed = render(&scene, job).map_err(|e| render_error(&what, "timed run", e))?;
            let Timings {
                pass_median_ms,
                gpu_ms,
                cpu_ms,
            } = timings(&what, &timed)?;
            if device.is_empty() {
                device = timed.device.clone();
            }
            for name in &timed.passes {
                if !passes.contains(name) {
                    passes.push(name.clone());
                }
            }
            drop(timed);

            let mut images = |values: &[String]| -> Result<Rc<Images>, SweepError> {
                if let Some(hit) = cache.get(values) {
                    return Ok(hit.clone());
                }
                let what = self.describe(values);
                let run = render(&self.scene_for(values)?, Job::Images)
                    .map_err(|e| render_error(&what, "image run", e))?;
                let hdr = run.hdr.ok_or_else(|| SweepError::Render {
                    what: what.clone(),
                    reason: "the image run returned no HDR image".into(),
                })?;
                let images = Rc::new(Images {
                    output: run.output,
                    hdr,
                });
                // Only references are needed again; other images are
                // dropped after their one comparison.
                if references.contains(values) {
                    cache.insert(values.to_vec(), images.clone());
                }
                Ok(images)
            };
            let test = images(&c.values)?;
            let (reference, ref_name) = if cpu {
                let key = self.cpu_reference_scene(&c.values)?;
                let hit = cpu_cache.iter().find(|(k, _)| *k == key);
                let reference = match hit {
                    Some((_, images)) => images.clone(),
                    None => {
                        let run = render(&scene, Job::Reference)
                            .map_err(|e| render_error(&what, "CPU reference", e))?;
                        let hdr = run.hdr.ok_or_else(|| SweepError::Render {
                            what: format!("{what} (CPU reference)"),
                            reason: "no HDR image was returned".into(),
                        })?;
                        let images = Rc::new(Images {
                            output: run.output,
                            hdr,
                        });
                        cpu_cache.push((key, images.clone()));
                        images
                    }
                };
                (reference, format!("CPU reference ({what})"))
            } else {
                let name = format!("reference ({})", self.describe(&c.reference));
                (images(&c.reference)?, name)
            };
            let compare_err = |source| SweepError::Compare {
                what: what.clone(),
                source,
            };
            let rmse = compare_images(
                &ref_name,
                linear(&reference.hdr),
                &what,
                linear(&test.hdr),
                Metric::Rmse,
            )
            .map_err(compare_err)?;
            let flip = compare_images(
                &ref_name,
                srgb(&reference.output),
                &what,
                srgb(&test.output),
                Metric::Flip,
            )
            .map_err(compare_err)?;

            let row = Row {
                settings: self.pairs(&c.values),
                reference: self.pairs(&c.reference),
                is_reference: !cpu && c.values == c.reference,
                pass_median_ms,
                gpu_ms,
                cpu_ms,
                rmse: rmse.mean,
                flip_mean: flip.mean,
                flip_p99: flip.p99,
                pareto: false,
            };
            on_row(index, &row);
            rows.push(row);
        }

        let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.gpu_ms.median, r.rmse)).collect();
        for (row, on_front) in rows.iter_mut().zip(pareto_front(&points)) {
            row.pareto = on_front;
        }
        Ok(SweepResult {
            scene: self.scene_name.clone(),
            device,
            frames: self.options.frames.max(1),
            warmup: self.options.warmup,
            reference: self.options.reference,
            knobs: self.axes.iter().map(|a| a.knob.name.to_string()).collect(),
            passes,
            rows,
        })
    }
}

/// The images of one render, kept while they may serve as a reference.
struct Images {
    output: Pixels<u8>,
    hdr: Pixels<f32>,
}

fn linear(p: &Pixels<f32>) -> ImageRef<'_> {
    ImageRef::Linear {
        width: p.width,
        height: p.height,
        rgba: &p.data,
    }
}

fn srgb(p: &Pixels<u8>) -> ImageRef<'_> {
    ImageRef::Srgb8 {
        width: p.width,
        height: p.height,
        rgba: &p.data,
    }
}

/// The reference's values for a combination's `values`: see the module docs.
fn reference_values(axes: &[Axis], values: &[String]) -> Vec<String> {
    axes.iter()
        .zip(values)
        .map(|(axis, own)| match axis.knob.best {
            Best::Fixed(v) => v.to_string(),
            Best::LastListed => axis.values.last().unwrap_or(own).clone(),
            Best::Unchanged => own.clone(),
        })
        .collect()
}

/// A render error with its whole cause chain in one line.
fn render_error(
    what: &str,
    run: &str,
    e: impl Into<Box<dyn std::error::Error + Send + Sync>>,
) -> SweepError {
    let e = e.into();
    let mut reason = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let _ = write!(reason, ": {s}");
        source = s.source();
    }
    SweepError::Render {
        what: format!("{what} ({run})"),
        reason,
    }
}

/// The timing columns of a row.
struct Timings {
    pass_median_ms: Vec<(String, f64)>,
    gpu_ms: Summary,
    cpu_ms: Summary,
}

/// Per-pass medians, the per-frame GPU total and the CPU frame time.
fn timings(what: &str, run: &Rendered) -> Result<Timings, SweepError> {
    if run.frames.is_empty() || run.frames.iter().any(|f| f.pass_ms.is_empty()) {
        return Err(SweepError::NoTimings { what: what.into() });
    }
    let bad = || SweepError::BadTimings { what: what.into() };
    let mut pass_median_ms = Vec::new();
    for (i, name) in run.passes.iter().enumerate() {
        let samples: Vec<f64> = run
            .frames
            .iter()
            .filter_map(|f| f.pass_ms.get(i).copied())
            .collect();
        pass_median_ms.push((name.clone(), Summary::of(&samples).ok_or_else(bad)?.median));
    }
    let totals: Vec<f64> = run.frames.iter().map(|f| f.pass_ms.iter().sum()).collect();
    let cpu: Vec<f64> = run.frames.iter().map(|f| f.cpu_ms).collect();
    Ok(Timings {
        pass_median_ms,
        gpu_ms: Summary::of(&totals).ok_or_else(bad)?,
        cpu_ms: Summary::of(&cpu).ok_or_else(bad)?,
    })
}

/// Which of the `(time, error)` points are on the Pareto front: point `i`
/// is unless some other point is no slower and no less accurate, and
/// strictly better in at least one. Identical points do not dominate each
/// other, so duplicates are on the front together. A point with a NaN
/// coordinate compares false with everything: it neither dominates nor is
/// dominated (the sweep never produces one).
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| {
            !points
                .iter()
                .any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e))
        })
        .collect()
}

/// RFC 4180 field: quoted when it holds a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The sweep as CSV: one row per combination, knob columns first, then the
/// reference's settings, per-pass and total times in ms, the error metrics
/// and the Pareto flag. Times are rounded to 0.1 µs (far below the noise
/// between frames); errors keep every digit.
pub fn to_csv(result: &SweepResult) -> String {
    let mut header: Vec<String> = result.knobs.clone();
    header.push("reference".into());
    header.push("is_reference".into());
    header.extend(result.passes.iter().map(|p| format!("{p}_median_ms")));
    header.extend(
        [
            "gpu_median_ms",
            "gpu_p95_ms",
            "cpu_median_ms",
            "rmse",
            "flip_mean",
            "flip_p99",
            "pareto",
        ]
        .map(String::from),
    );
    let mut out = String::new();
    let line = |out: &mut String, fields: Vec<String>| {
        let fields: Vec<String> = fields.iter().map(|f| csv_field(f)).collect();
        out.push_str(&fields.join(","));
        out.push('\n');
    };
    line(&mut out, header);
    for row in &result.rows {
        let mut fields: Vec<String> = result
            .knobs
            .iter()
            .map(|k| {
                row.settings
                    .iter()
                    .find(|(name, _)| name == k)
                    .map(|(_, v)| v.clone())
                    .unwrap_or_default()
            })
            .collect();
        // A CPU reference is the exact image of the row's own settings,
        // so the settings would only repeat the row.
        fields.push(match result.reference {
            ReferenceKind::Cpu => ReferenceKind::Cpu.name().to_string(),
            ReferenceKind::GpuBest => row
                .reference
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(" "),
        });
        fields.push(row.is_reference.to_string());
        // A pass this combination does not have is an empty cell.
        fields.extend(result.passes.iter().map(|p| {
            row.pass_median_ms
                .iter()
                .find(|(name, _)| name == p)
                .map(|(_, ms)| format!("{ms:.4}"))
                .unwrap_or_default()
        }));
        fields.extend([
            format!("{:.4}", row.gpu_ms.median),
            format!("{:.4}", row.gpu_ms.p95),
            format!("{:.4}", row.cpu_ms.median),
            row.rmse.to_string(),
            row.flip_mean.to_string(),
            row.flip_p99.to_string(),
            row.pareto.to_string(),
        ]);
        line(&mut out, fields);
    }
    out
}

/// The sweep as a fixed-width table for the terminal.
pub fn to_table(result: &SweepResult) -> String {
    let labels: Vec<Vec<&str>> = result
        .rows
        .iter()
        .map(|r| r.settings.iter().map(|(_, v)| v.as_str()).collect())
        .collect();
    let widths: Vec<usize> = result
        .knobs
        .iter()
        .enumerate()
        .map(|(i, k)| {
            labels
                .iter()
                .filter_map(|l| l.get(i).map(|v| v.len()))
                .chain([k.len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    if result.reference == ReferenceKind::Cpu {
        // GPU-best tables mark their reference row; a CPU reference has
        // none, so say once what the errors are against.
        out.push_str("errors against the exact CPU image of each row's own scene\n");
    }
    for (k, w) in result.knobs.iter().zip(&widths) {
        let _ = write!(out, "{k:<w$}  ");
    }
    let _ = writeln!(
        out,
        "{:>10} {:>10} {:>11} {:>9} {:>9}  pareto",
        "gpu ms", "p95 ms", "rmse", "flip", "flip p99"
    );
    for (row, label) in result.rows.iter().zip(&labels) {
        for (v, w) in label.iter().zip(&widths) {
            let _ = write!(out, "{v:<w$}  ");
        }
        let _ = writeln!(
            out,
            "{:>10.3} {:>10.3} {:>11.4e} {:>9.5} {:>9.5}  {}{}",
            row.gpu_ms.median,
            row.gpu_ms.p95,
            row.rmse,
            row.flip_mean,
            row.flip_p99,
            if row.pareto { "*" } else { "" },
            if row.is_reference { " (reference)" } else { "" },
        );
    }
    out
}

/// The plot's points: labelled with the values of the knobs that vary (a
/// knob with one value says nothing about a point).
fn plot_points(result: &SweepResult) -> Vec<PlotPoint> {
    let varying: Vec<bool> = (0..result.knobs.len())
        .map(|i| {
            let mut values = result.rows.iter().filter_map(|r| r.settings.get(i));
            let first = values.next();
            values.any(|v| Some(v) != first)
        })
        .collect();
    result
        .rows
        .iter()
        .map(|r| {
            let parts: Vec<&str> = r
                .settings
                .iter()
                .zip(&varying)
                .filter(|(_, &v)| v)
                .map(|((_, value), _)| value.as_str())
                .collect();
            PlotPoint {
                x: r.gpu_ms.median,
                y: r.rmse,
                label: if parts.is_empty() {
                    r.settings
                        .iter()
                        .map(|(_, v)| v.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                } else {
                    parts.join(", ")
                },
                pareto: r.pareto,
                reference: r.is_reference,
            }
        })
        .collect()
}

/// The SVG plot of the sweep: error (log) against GPU time.
pub fn to_svg(result: &SweepResult) -> Result<String, SweepError> {
    let varying: Vec<&str> = result
        .knobs
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            let mut values = result.rows.iter().filter_map(|r| r.settings.get(*i));
            let first = values.next();
            values.any(|v| Some(v) != first)
        })
        .map(|(_, k)| k.as_str())
        .collect();
    let fixed: Vec<String> = result
        .knobs
        .iter()
        .enumerate()
        .filter(|(_, k)| !varying.contains(&k.as_str()))
        .filter_map(|(i, k)| {
            let v = result.rows.first()?.settings.get(i)?;
            Some(format!("{k}={}", v.1))
        })
        .collect();
    let mut subtitle = format!(
        "points labelled {}; median of {} frames on {}",
        varying.join(", "),
        result.frames,
        result.device
    );
    if !fixed.is_empty() {
        let _ = write!(subtitle, "; {}", fixed.join(", "));
    }
    if result.reference == ReferenceKind::Cpu {
        subtitle.push_str("; reference: exact CPU image");
    }
    Ok(plot::error_vs_time_svg(&plot::Plot {
        title: &format!("{}: error against GPU time", result.scene),
        subtitle: &subtitle,
        x_label: "GPU time per frame, median (ms)",
        y_label: match result.reference {
            ReferenceKind::GpuBest => "RMSE of linear HDR vs reference (log)",
            ReferenceKind::Cpu => "RMSE of linear HDR vs exact CPU image (log)",
        },
        points: &plot_points(result),
    })?)
}

/// Writes `sweep.csv`, `sweep.json` and `sweep.svg` into `dir` (created if
/// missing), each to a temporary name first and renamed into place, so an
/// interrupted run leaves no half-written file. Returns the paths written.
pub fn write_outputs(result: &SweepResult, dir: &Path) -> Result<Vec<PathBuf>, SweepError> {
    // Build everything before touching the disk, so a failure to plot
    // leaves no partial set of files.
    let mut json = serde_json::to_string_pretty(result)?;
    json.push('\n');
    let files = [
        ("sweep.csv", to_csv(result)),
        ("sweep.json", json),
        ("sweep.svg", to_svg(result)?),
    ];
    std::fs::create_dir_all(dir).map_err(|error| SweepError::CreateDir {
        path: dir.to_path_buf(),
        error,
    })?;
    // All three are written before any is renamed into place, so a failure
    // leaves none of them.
    let mut pending = Vec::new();
    for (name, text) in files {
        let path = dir.join(name);
        let file = crate::files::PendingFile::create(&path).map_err(SweepError::File)?;
        std::io::Write::write_all(&mut file.file(), text.as_bytes())
            .map_err(|e| SweepError::File(file.io_error(e)))?;
        pending.push(file);
    }
    crate::files::commit_all(pending).map_err(SweepError::File)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;

    fn axes(args: &[&str]) -> Vec<Axis> {
        args.iter().map(|a| Axis::parse(a).unwrap()).collect()
    }

    fn summary(ms: f64) -> Summary {
        Summary::of(&[ms]).unwrap()
    }

    fn row(values: &[(&str, &str)], ms: f64, rmse: f64, pareto: bool) -> Row {
        let pairs = |v: &[(&str, &str)]| {
            v.iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect::<Vec<_>>()
        };
        Row {
            settings: pairs(values),
            reference: pairs(&[("tessellation", "1"), ("hdr_format", "rgba32f")]),
            is_reference: rmse == 0.0,
            pass_median_ms: vec![("opaque".into(), ms * 0.75), ("tonemap".into(), ms * 0.25)],
            gpu_ms: summary(ms),
            cpu_ms: summary(ms + 1.0),
            rmse,
            flip_mean: rmse / 2.0,
            flip_p99: rmse,
            pareto,
        }
    }

    #[test]
    fn pareto_front_by_hand() {
        // (time, error): a is fastest, d most accurate, b between them on
        // the front; c is dominated by b (slower and worse); e duplicates b.
        let points = [
            (1.0, 0.5),  // a
            (2.0, 0.2),  // b
            (3.0, 0.3),  // c: b is faster and better
            (4.0, 0.0),  // d
            (2.0, 0.2),  // e: same as b, neither dominates the other
            (4.0, 0.1),  // f: d is as fast and better
            (1.0, 0.6),  // g: a is as fast and better
            (0.5, 0.55), // h: fastest of all
        ];
        assert_eq!(
            pareto_front(&points),
            [true, true, false, true, true, false, false, true]
        );
        assert_eq!(pareto_front(&[]), Vec::<bool>::new());
        assert_eq!(pareto_front(&[(1.0, 1.0)]), [true]);
    }

    #[test]
    fn csv_has_a_header_and_one_line_per_row() {
        let result = SweepResult {
            scene: "s.toml".into(),
            device: "dev".into(),
            frames: 1,
            warmup: 0,
            reference: ReferenceKind::GpuBest,
            knobs: vec!["tessellation".into(), "hdr_format".into()],
            passes: vec!["opaque".into(), "tonemap".into(), "transparent".into()],
            rows: vec![
                row(
                    &[("tessellation", "0.5"), ("hdr_format", "rgba16f")],
                    2.0,
                    0.25,
                    true,
                ),
                row(
                    &[("tessellation", "1"), ("hdr_format", "rgba32f")],
                    4.0,
                    0.0,
                    true,
                ),
            ],
        };
        let csv = to_csv(&result);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines,
            [
                "tessellation,hdr_format,reference,is_reference,opaque_median_ms,\
                 tonemap_median_ms,transparent_median_ms,gpu_median_ms,gpu_p95_ms,\
                 cpu_median_ms,rmse,flip_mean,flip_p99,pareto",
                "0.5,rgba16f,tessellation=1 hdr_format=rgba32f,false,\
                 1.5000,0.5000,,2.0000,2.0000,3.0000,0.25,0.125,0.25,true",
                "1,rgba32f,tessellation=1 hdr_format=rgba32f,true,\
                 3.0000,1.0000,,4.0000,4.0000,5.0000,0,0,0,true",
            ]
        );
        assert!(csv.ends_with('\n'));
    }

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(csv_field("plain"), "plain");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(csv_field("two\nlines"), "\"two\nlines\"");
    }

    #[test]
    fn json_keeps_knob_order_and_has_the_metrics() {
        let result = SweepResult {
            scene: "s.toml".into(),
            device: "dev".into(),
            frames: 1,
            warmup: 0,
            reference: ReferenceKind::GpuBest,
            knobs: vec!["tessellation".into(), "hdr_format".into()],
            passes: vec!["opaque".into()],
            rows: vec![row(
                &[("tessellation", "1"), ("hdr_format", "rgba32f")],
                4.0,
                0.0,
                true,
            )],
        };
        let json = serde_json::to_string(&result).unwrap();
        assert!(
            json.contains(r#""settings":{"tessellation":"1","hdr_format":"rgba32f"}"#),
            "{json}"
        );
        for key in [
            "\"rmse\":0.0",
            "\"pareto\":true",
            "\"gpu_ms\":{",
            "\"p95\":",
        ] {
            assert!(json.contains(key), "{key} missing: {json}");
        }
    }

    #[test]
    fn axis_parsing_errors_name_the_knob_and_value() {
        let msg = |arg: &str| Axis::parse(arg).unwrap_err().to_string();
        assert!(msg("nope=1,2").contains("nope"), "{}", msg("nope=1,2"));
        assert!(msg("tessellation").contains("tessellation"));
        assert!(msg("tessellation=1,,2").contains("empty value"));
        let dup = msg("tessellation=1,2,1");
        assert!(dup.contains("tessellation") && dup.contains("'1'"), "{dup}");
        let a = Axis::parse(" tessellation = 0.5, 1 ").unwrap();
        assert_eq!(
            (a.knob.name, a.values),
            ("tessellation", vec!["0.5".into(), "1".into()])
        );
    }

    #[test]
    fn bad_sweeps_are_refused_before_rendering() {
        let scene = Scene::default_scene();
        let new = |args: &[&str], max| {
            Sweep::new(
                "default",
                scene.clone(),
                axes(args),
                SweepOptions {
                    max_combinations: max,
                    ..SweepOptions::default()
                },
            )
            .err()
            .map(|e| e.to_string())
        };
        let bad = new(&["tessellation=1,-2"], 256).unwrap();
        assert!(bad.contains("tessellation=-2"), "{bad}");
        let twice = new(&["tessellation=1", "tessellation=2"], 256).unwrap();
        assert!(
            twice.contains("tessellation") && twice.contains("twice"),
            "{twice}"
        );
        let many = new(&["tessellation=1,2,3", "hdr_format=rgba16f,rgba32f"], 5).unwrap();
        assert!(
            many.contains("6 combinations") && many.contains("--max-combinations"),
            "{many}"
        );
        assert!(new(&["tessellation=1,2,3", "hdr_format=rgba16f,rgba32f"], 6).is_none());
        assert!(new(&[], 256).unwrap().contains("nothing to sweep"));
    }

    #[test]
    fn references_follow_best() {
        let sweep = Sweep::new(
            "default",
            Scene::default_scene(),
            axes(&[
                "size=64x32,32x16",
                "tessellation=0.5,2,1",
                "hdr_format=rgba32f,rgba16f",
            ]),
            SweepOptions::default(),
        )
        .unwrap();
        let c = sweep.combinations();
        assert_eq!(c.len(), 12);
        // Last axis fastest.
        assert_eq!(c[1].values, ["64x32", "0.5", "rgba16f"]);
        // Size unchanged, tessellation last listed (1, not the largest),
        // hdr_format fixed.
        assert_eq!(c[1].reference, ["64x32", "1", "rgba32f"]);
        assert_eq!(c[11].values, ["32x16", "1", "rgba16f"]);
        assert_eq!(c[11].reference, ["32x16", "1", "rgba32f"]);
        assert_eq!(c[10].values, c[10].reference);
    }

    /// A stand-in renderer: a flat image whose value depends on the
    /// tessellation and format, and times that grow with tessellation.
    fn fake_render(scene: &Scene, job: Job) -> Result<Rendered, String> {
        let tris: u32 = scene
            .objects
            .iter()
            .map(|o| o.tessellation.0 * o.tessellation.1)
            .sum();
        // The exact image is the limit of infinite tessellation, 1.
        let mut value = 1.0 - 1.0 / tris as f32;
        if job == Job::Reference {
            value = 1.0;
        } else if scene.output.hdr_format == crate::scene::HdrFormat::Rgba16F {
            value += 1e-6;
        }
        let (w, h) = (scene.output.width, scene.output.height);
        let n = (w * h) as usize;
        let frames = match job {
            Job::Timing { frames, .. } => frames,
            Job::Images | Job::Reference => 1,
        };
        Ok(Rendered {
            device: "fake".into(),
            passes: vec!["opaque".into(), "tonemap".into()],
            frames: (0..frames)
                .map(|i| FrameTiming {
                    pass_ms: vec![tris as f64 / 100.0 + i as f64 * 0.01, 1.0],
                    cpu_ms: 1.0,
                })
                .collect(),
            output: Pixels {
                width: w,
                height: h,
                data: [(value * 200.0) as u8, 0, 0, 255].repeat(n),
            },
            hdr: (!matches!(job, Job::Timing { .. })).then(|| Pixels {
                width: w,
                height: h,
                data: [value, 0.0, 0.0, 1.0].repeat(n),
            }),
        })
    }

    #[test]
    fn run_renders_each_reference_once_and_scores_it_zero() {
        let sweep = Sweep::new(
            "default",
            Scene::default_scene(),
            axes(&["size=32x16", "tessellation=0.5,1", "hdr_format=rgba16f"]),
            SweepOptions {
                frames: 3,
                warmup: 0,
                max_combinations: 4,
                reference: ReferenceKind::GpuBest,
            },
        )
        .unwrap();
        let jobs = RefCell::new(Vec::new());
        let result = sweep
            .run(
                |scene, job| {
                    let key = (scene.output.hdr_format, scene.objects[0].tessellation);
                    jobs.borrow_mut().push((key, job));
                    fake_render(scene, job)
                },
                |_, _| {},
            )
            .unwrap();
        let jobs = jobs.into_inner();
        // 2 timed runs, 2 image runs, and the rgba32f reference (not in
        // the sweep) once, though both rows use it.
        assert_eq!(jobs.len(), 5, "{jobs:?}");
        assert_eq!(jobs.iter().filter(|(_, j)| *j == Job::Images).count(), 3);
        assert!(jobs.iter().all(|(_, j)| *j == Job::Images
            || *j
                == Job::Timing {
                    warmup: 0,
                    frames: 3
                }));
        assert_eq!(result.rows.len(), 2);
        assert!(result.rows.iter().all(|r| !r.is_reference));
        // Median of 3 frames: the middle one.
        let r = &result.rows[0];
        assert_eq!(r.gpu_ms.count, 3);
        assert!((r.gpu_ms.median - (r.pass_median_ms[0].1 + 1.0)).abs() < 1e-9);
        // Coarser is faster and worse: both on the front.
        assert!(result.rows[0].rmse > result.rows[1].rmse);
        assert!(result.rows[1].rmse > 0.0);
        assert!(result.rows.iter().all(|r| r.pareto));

        // Sweeping the reference itself: error exactly 0, rendered once
        // for its images.
        let sweep = Sweep::new(
            "default",
            Scene::default_scene(),
            axes(&["size=32x16", "tessellation=0.5,1"]),
            SweepOptions::default(),
        )
        .unwrap();
        let image_runs = RefCell::new(0);
        let result = sweep
            .run(
                |scene, job| {
                    *image_runs.borrow_mut() += usize::from(job == Job::Images);
                    fake_render(scene, job)
                },
                |_, _| {},
            )
            .unwrap();
        assert_eq!(image_runs.into_inner(), 2);
        assert!(result.rows[1].is_reference);
        assert_eq!((result.rows[1].rmse, result.rows[1].flip_mean), (0.0, 0.0));
        assert!(result.rows[0].rmse > 0.0);
    }

    #[test]
    fn render_failures_name_the_combination() {
        let sweep = Sweep::new(
            "default",
            Scene::default_scene(),
            axes(&["size=32x16", "tessellation=0.5"]),
            SweepOptions::default(),
        )
        .unwrap();
        let err = sweep
            .run(|_, _| Err::<Rendered, _>("device lost"), |_, _| {})
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("tessellation=0.5") && err.contains("device lost"),
            "{err}"
        );

        let err = sweep
            .run(
                |scene, job| {
                    let mut r = fake_render(scene, job)?;
                    r.frames.iter_mut().for_each(|f| f.pass_ms.clear());
                    Ok::<_, String>(r)
                },
                |_, _| {},
            )
            .unwrap_err()
            .to_string();
        assert!(err.contains("no pass timings"), "{err}");
    }

    /// A phong sphere on a plane, every light reaching everything
    /// (light_cutoff 0), so the light sets do not depend on tessellation.
    const CPU_SCENE: &str = r#"
light_cutoff = 0.0
[camera]
eye = [0.0, 1.0, 4.0]
look_at = [0.0, 0.5, 0.0]
[[lights]]
type = "point"
position = [2.0, 3.0, 2.0]
intensity = 5.0
[[lights]]
type = "directional"
direction = [0.0, -1.0, -1.0]
[[materials]]
name = "m"
kd = [0.5, 0.4, 0.3]
ks = [0.2, 0.2, 0.2]
[[objects]]
name = "ball"
material = "m"
shape = { type = "sphere", radius = 0.5 }
translate = [0.0, 0.5, 0.0]
[[objects]]
name = "floor"
material = "m"
shape = { type = "plane", width = 4.0, depth = 4.0 }
"#;

    fn cpu_sweep(args: &[&str]) -> Result<Sweep, SweepError> {
        let scene = Scene::from_toml(CPU_SCENE, "cpu.toml", Path::new(".")).unwrap();
        Sweep::new(
            "cpu.toml",
            scene,
            axes(args),
            SweepOptions {
                frames: 1,
                warmup: 0,
                reference: ReferenceKind::Cpu,
                ..SweepOptions::default()
            },
        )
    }

    #[test]
    fn cpu_reference_is_per_scene_and_never_the_row_itself() {
        let sweep = cpu_sweep(&[
            "size=16x8",
            "tessellation=0.5,1",
            "hdr_format=rgba16f,rgba32f",
        ])
        .unwrap();
        let c = sweep.combinations();
        assert!(c.iter().all(|c| c.values == c.reference));
        let references = RefCell::new(0);
        let result = sweep
            .run(
                |scene, job| {
                    *references.borrow_mut() += usize::from(job == Job::Reference);
                    fake_render(scene, job)
                },
                |_, _| {},
            )
            .unwrap();
        // Neither tessellation nor format changes the exact image: one
        // reference for all four rows.
        assert_eq!(references.into_inner(), 1);
        assert_eq!(result.reference, ReferenceKind::Cpu);
        assert!(result.rows.iter().all(|r| !r.is_reference && r.rmse > 0.0));
        assert!(result.rows[0].rmse > result.rows[2].rmse);
        let csv = to_csv(&result);
        assert!(
            csv.lines().skip(1).all(|l| l.contains(",cpu,false,")),
            "{csv}"
        );
        let json = serde_json::to_string(&result).unwrap();
        assert!(json.contains(r#""reference":"cpu""#), "{json}");
        assert!(to_table(&result).starts_with("errors against the exact CPU image"));
        let svg = to_svg(&result).unwrap();
        assert!(svg.contains("exact CPU image") && !svg.contains("(reference)"));

        // Fewer lights is another exact image: one reference per count.
        let sweep = cpu_sweep(&["size=16x8", "lights=1,2", "hdr_format=rgba16f,rgba32f"]).unwrap();
        let references = RefCell::new(0);
        sweep
            .run(
                |scene, job| {
                    *references.borrow_mut() += usize::from(job == Job::Reference);
                    fake_render(scene, job)
                },
                |_, _| {},
            )
            .unwrap();
        assert_eq!(references.into_inner(), 2);
    }

    #[test]
    fn cpu_reference_refuses_unsupported_scenes_before_rendering() {
        let err = Sweep::new(
            "default",
            Scene::default_scene(),
            axes(&["tessellation=0.5,1"]),
            SweepOptions {
                reference: ReferenceKind::Cpu,
                ..SweepOptions::default()
            },
        )
        .err()
        .map(|e| e.to_string())
        .unwrap();
        assert!(
            err.contains("--reference cpu") && err.contains("'ring'") && err.contains("torus"),
            "{err}"
        );
        let err = cpu_sweep(&["shading=phong,toon"])
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("shading=toon") && err.contains("toon shading"),
            "{err}"
        );
    }

    #[test]
    fn outputs_are_written_whole() {
        let dir = std::env::temp_dir().join(format!("aerial-sweep-unit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let sweep = Sweep::new(
            "default",
            Scene::default_scene(),
            axes(&[
                "size=32x16",
                "tessellation=0.5,1",
                "hdr_format=rgba16f,rgba32f",
            ]),
            SweepOptions {
                frames: 2,
                ..SweepOptions::default()
            },
        )
        .unwrap();
        let result = sweep.run(fake_render, |_, _| {}).unwrap();
        let written = write_outputs(&result, &dir).unwrap();
        assert_eq!(written.len(), 3);
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["sweep.csv", "sweep.json", "sweep.svg"]);
        let svg = std::fs::read_to_string(dir.join("sweep.svg")).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("0.5, rgba16f"), "labels use the varying knobs");
        assert!(
            !svg.contains("32x16, 0.5"),
            "fixed knobs are not in the labels"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
