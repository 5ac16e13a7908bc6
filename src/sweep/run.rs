//! Running a sweep: parse and check the knob axes, list the combinations,
//! have the caller render each one (timed, then for its images), compare
//! it with its reference and mark the Pareto front.

use super::{ReferenceKind, Row, Shard, SweepError, SweepResult, TimeAxis};
use crate::render::cpu_renderer::CpuScene;
use crate::render::{FrameTiming, Pixels};
use crate::report::image_diff::{compare_images, ImageRef, Metric};
use crate::report::stats::{summarise_passes, Summary};
use crate::scene::{Best, Knob, Scene};
use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::rc::Rc;

/// Combinations a sweep may have unless the caller raises the limit: at a
/// few seconds per combination, more is an accident (a typo in a list, one
/// knob too many) rather than a plan.
pub const DEFAULT_MAX_COMBINATIONS: usize = 256;

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
    /// [`crate::render::render_on_cpu`] and `output` that image through
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
    /// What building the frame cost beyond its passes, by name (for
    /// example the optical-depth table's size and bake time); read from
    /// the timed run.
    pub setup: Vec<(String, f64)>,
    /// The empty pass timed between the timed frames (total ms of each),
    /// for [`Job::Timing`]; empty when the renderer times none.
    pub empty_pass_ms: Vec<f64>,
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
    scene_hash: String,
    base: Scene,
    axes: Vec<Axis>,
    combinations: Vec<Combination>,
    options: SweepOptions,
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
            scene_hash: String::new(),
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
    fn cpu_reference_scene(&self, values: &[String]) -> Result<CpuScene, SweepError> {
        CpuScene::new(&self.scene_for(values)?).map_err(|source| SweepError::NoCpuReference {
            what: self.describe(values),
            source,
        })
    }

    /// Records what identifies the scene across machines
    /// ([`super::scene_hash`] of its file), for telling shards of different
    /// sweeps apart.
    pub fn set_scene_hash(&mut self, hash: impl Into<String>) {
        self.scene_hash = hash.into();
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

    /// Refuses, before anything is rendered, a sweep whose estimated peak
    /// memory is over the budget (`AERIAL_MEMORY_BUDGET`). The peak is the
    /// images kept as references for later rows, plus the larger of the
    /// largest render (its image run reads the HDR image back, its timed
    /// run times the empty pass on the same device) and the largest
    /// comparison (the test's images and the comparison's working memory).
    /// Each render alone is also checked as `render` checks it. Without
    /// the references and the comparison, the estimate of a 1024x1024
    /// sweep fell 44 % short of its measured peak.
    fn check_memory(&self, chosen: &[(usize, &Combination)]) -> Result<(), SweepError> {
        use crate::render::preflight;
        let budget =
            crate::budget::MemoryBudget::from_env().map_err(|e| SweepError::Memory(e.into()))?;
        let pixels = |s: &Scene| u64::from(s.output.width) * u64::from(s.output.height);
        let (mut render, mut largest) = (0u64, (0u64, String::new()));
        let mut references: Vec<&[String]> = Vec::new();
        let mut cpu_references: Vec<CpuScene> = Vec::new();
        let mut kept = 0u64;
        for (_, c) in chosen {
            let scene = self.scene_for(&c.values)?;
            let bytes = preflight::scene_bytes(
                &scene,
                true,
                preflight::EMPTY_PASS_BYTES_PER_PIXEL,
                &budget,
            )
            .map_err(SweepError::Memory)?;
            render = render.max(bytes);
            if pixels(&scene) > largest.0 {
                largest = (pixels(&scene), self.describe(&c.values));
            }
            if self.options.reference == ReferenceKind::Cpu {
                let key = self.cpu_reference_scene(&c.values)?;
                if !cpu_references.contains(&key) {
                    cpu_references.push(key);
                    kept += IMAGES_BYTES_PER_PIXEL * pixels(&scene);
                }
            } else if !references.contains(&c.reference.as_slice()) {
                references.push(&c.reference);
                kept += IMAGES_BYTES_PER_PIXEL * pixels(&self.scene_for(&c.reference)?);
            }
        }
        let compare = largest.0 * (IMAGES_BYTES_PER_PIXEL + 2 * COMPARE_BYTES_PER_PIXEL);
        let need = kept.saturating_add(render.max(compare));
        budget
            .check(
                format!(
                    "the sweep ({} combinations, the largest image at {}; {} reference images kept)",
                    chosen.len(),
                    largest.1,
                    references.len() + cpu_references.len()
                ),
                need,
            )
            .map_err(|e| SweepError::Memory(e.into()))
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
        render: impl FnMut(&Scene, Job) -> Result<Rendered, E>,
        on_row: impl FnMut(usize, &Row),
    ) -> Result<SweepResult, SweepError>
    where
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
        self.run_shard(None, render, on_row)
    }

    /// Like [`Sweep::run`], for only the combinations of `shard` (all of
    /// them with `None`): their references are rendered here too, so the
    /// errors are those of the whole sweep. The result records the shard
    /// and, in every row, the combination's index in the whole sweep.
    pub fn run_shard<E>(
        &self,
        shard: Option<Shard>,
        mut render: impl FnMut(&Scene, Job) -> Result<Rendered, E>,
        mut on_row: impl FnMut(usize, &Row),
    ) -> Result<SweepResult, SweepError>
    where
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
        if let Some(s) = shard.filter(|s| s.count > self.combinations.len()) {
            return Err(SweepError::EmptyShard {
                index: s.index,
                count: s.count,
                combinations: self.combinations.len(),
            });
        }
        let chosen: Vec<(usize, &Combination)> = self
            .combinations
            .iter()
            .enumerate()
            .filter(|(k, _)| shard.is_none_or(|s| s.holds(*k)))
            .collect();
        self.check_memory(&chosen)?;
        let cpu = self.options.reference == ReferenceKind::Cpu;
        let mut state = ShardState {
            images: ComparisonImages {
                cpu,
                // GPU images kept because they serve as references (none
                // with a CPU reference: then every GPU image is compared
                // once).
                references: chosen
                    .iter()
                    .filter(|_| !cpu)
                    .map(|(_, c)| c.reference.as_slice())
                    .collect(),
                cache: HashMap::new(),
                cpu_cache: Vec::new(),
            },
            device: String::new(),
            passes: Vec::new(),
            setup_names: Vec::new(),
        };
        let mut rows = Vec::with_capacity(chosen.len());
        for (index, c) in chosen {
            let row = self.run_combination(index, c, &mut state, &mut render)?;
            on_row(index, &row);
            rows.push(row);
        }
        Ok(self.shard_result(shard, rows, state))
    }

    /// Times one combination, renders its images and its reference's, and
    /// measures the errors: its row, not yet marked on the Pareto front.
    fn run_combination<E>(
        &self,
        index: usize,
        c: &Combination,
        state: &mut ShardState<'_>,
        render: &mut impl FnMut(&Scene, Job) -> Result<Rendered, E>,
    ) -> Result<Row, SweepError>
    where
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
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
        if state.device.is_empty() {
            state.device = timed.device.clone();
        }
        add_new_names(&mut state.passes, &timed.passes);
        add_new_names(
            &mut state.setup_names,
            timed.setup.iter().map(|(name, _)| name),
        );
        let setup = timed.setup.clone();
        let empty_median_ms = Summary::of(&timed.empty_pass_ms).map(|s| s.median);
        drop(timed);

        let images = &mut state.images;
        let test = self.gpu_images(images, render, &c.values)?;
        let (reference, ref_name) = if images.cpu {
            let reference = self.cpu_reference_images(images, render, &scene, &c.values, &what)?;
            (reference, format!("CPU reference ({what})"))
        } else {
            let name = format!("reference ({})", self.describe(&c.reference));
            (self.gpu_images(images, render, &c.reference)?, name)
        };
        let errors = image_errors(&ref_name, &reference, &what, &test)?;
        Ok(Row {
            index,
            settings: self.pairs(&c.values),
            reference: self.pairs(&c.reference),
            is_reference: !images.cpu && c.values == c.reference,
            pass_median_ms,
            gpu_x_empty: empty_median_ms
                .filter(|&e| e > 0.0)
                .map(|e| gpu_ms.median / e),
            empty_median_ms,
            gpu_ms,
            cpu_ms,
            rmse: errors.rmse,
            max_rel_error: errors.max_rel_error,
            flip_mean: errors.flip_mean,
            flip_p99: errors.flip_p99,
            setup,
            pareto: false,
        })
    }

    /// The GPU images of the combination `values`: from the cache if it is
    /// a reference already rendered, else rendered now.
    fn gpu_images<E>(
        &self,
        images: &mut ComparisonImages<'_>,
        render: &mut impl FnMut(&Scene, Job) -> Result<Rendered, E>,
        values: &[String],
    ) -> Result<Rc<Images>, SweepError>
    where
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
        if let Some(hit) = images.cache.get(values) {
            return Ok(hit.clone());
        }
        let what = self.describe(values);
        let run = render(&self.scene_for(values)?, Job::Images)
            .map_err(|e| render_error(&what, "image run", e))?;
        let hdr = run.hdr.ok_or_else(|| SweepError::Render {
            what: what.clone(),
            reason: "the image run returned no HDR image".into(),
        })?;
        let rendered = Rc::new(Images {
            output: run.output,
            hdr,
        });
        // Only references are needed again; other images are
        // dropped after their one comparison.
        if images.references.contains(values) {
            images.cache.insert(values.to_vec(), rendered.clone());
        }
        Ok(rendered)
    }

    /// The CPU reference of the combination `values` (its `scene`), shared
    /// by every combination it does not depend on.
    fn cpu_reference_images<E>(
        &self,
        images: &mut ComparisonImages<'_>,
        render: &mut impl FnMut(&Scene, Job) -> Result<Rendered, E>,
        scene: &Scene,
        values: &[String],
        what: &str,
    ) -> Result<Rc<Images>, SweepError>
    where
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
        let key = self.cpu_reference_scene(values)?;
        if let Some((_, hit)) = images.cpu_cache.iter().find(|(k, _)| *k == key) {
            return Ok(hit.clone());
        }
        let run =
            render(scene, Job::Reference).map_err(|e| render_error(what, "CPU reference", e))?;
        let hdr = run.hdr.ok_or_else(|| SweepError::Render {
            what: format!("{what} (CPU reference)"),
            reason: "no HDR image was returned".into(),
        })?;
        let rendered = Rc::new(Images {
            output: run.output,
            hdr,
        });
        images.cpu_cache.push((key, rendered.clone()));
        Ok(rendered)
    }

    /// The sweep's result from the shard's rows, the front marked.
    fn shard_result(
        &self,
        shard: Option<Shard>,
        mut rows: Vec<Row>,
        state: ShardState<'_>,
    ) -> SweepResult {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (TimeAxis::GpuMedianMs.of(r), r.rmse))
            .collect();
        for (row, on_front) in rows.iter_mut().zip(pareto_front(&points)) {
            row.pareto = on_front;
        }
        let device = state.device;
        SweepResult {
            aerial_version: env!("CARGO_PKG_VERSION").to_string(),
            scene: self.scene_name.clone(),
            scene_hash: self.scene_hash.clone(),
            device: device.clone(),
            frames: self.options.frames.max(1),
            warmup: self.options.warmup,
            reference: self.options.reference,
            knobs: self.axes.iter().map(|a| a.knob.name.to_string()).collect(),
            axes: self.axes.iter().map(|a| format!("{a:?}")).collect(),
            combinations: self.combinations.len(),
            shard,
            shards: shard
                .map(|s| super::ShardSource {
                    index: s.index,
                    device,
                })
                .into_iter()
                .collect(),
            time_axis: TimeAxis::GpuMedianMs,
            passes: state.passes,
            setup: state.setup_names,
            asset_warnings: self.base.warnings.len(),
            rows,
        }
    }
}

/// What a shard's run gathers across its combinations.
struct ShardState<'a> {
    images: ComparisonImages<'a>,
    /// The device of the first timed run.
    device: String,
    /// Pass names, in the order first seen.
    passes: Vec<String>,
    /// Setup step names, in the order first seen.
    setup_names: Vec<String>,
}

/// The images rendered for comparison, and the references kept for reuse.
struct ComparisonImages<'a> {
    /// Whether the references are the CPU's.
    cpu: bool,
    /// The combinations whose GPU images serve as references.
    references: HashSet<&'a [String]>,
    cache: HashMap<Vec<String>, Rc<Images>>,
    /// CPU references by what they depend on; a short list, searched
    /// linearly (`CpuScene` holds floats, so it is not `Hash`).
    cpu_cache: Vec<(CpuScene, Rc<Images>)>,
}

/// A combination's errors against its reference.
struct ImageErrors {
    rmse: f64,
    max_rel_error: f64,
    flip_mean: f64,
    flip_p99: f64,
}

/// RMSE (linear HDR), the largest relative error, and FLIP (sRGB output)
/// of `test` against `reference`.
fn image_errors(
    ref_name: &str,
    reference: &Images,
    what: &str,
    test: &Images,
) -> Result<ImageErrors, SweepError> {
    let compare = |reference, test, metric| {
        compare_images(ref_name, reference, what, test, metric).map_err(|source| {
            SweepError::Compare {
                what: what.to_string(),
                source,
            }
        })
    };
    let rmse = compare(linear(&reference.hdr), linear(&test.hdr), Metric::Rmse)?;
    let max_rel_error = super::max_relative_error(&reference.hdr, &test.hdr);
    let flip = compare(srgb(&reference.output), srgb(&test.output), Metric::Flip)?;
    Ok(ImageErrors {
        rmse: rmse.mean,
        max_rel_error,
        flip_mean: flip.mean,
        flip_p99: flip.p99,
    })
}

/// Appends the names in `names` that `seen` does not hold yet, in order.
pub(super) fn add_new_names<'a>(
    seen: &mut Vec<String>,
    names: impl IntoIterator<Item = &'a String>,
) {
    for name in names {
        if !seen.contains(name) {
            seen.push(name.clone());
        }
    }
}

/// Bytes per pixel of one render's [`Images`]: the 8-bit output and the
/// f32 HDR image.
const IMAGES_BYTES_PER_PIXEL: u64 = 4 + 16;

/// Working memory of comparing images already in memory, per pixel of each
/// image: the bound `compare` uses for images it decodes itself.
const COMPARE_BYTES_PER_PIXEL: u64 = crate::report::image_diff::BYTES_PER_PIXEL;

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
pub(super) fn reference_values(axes: &[Axis], values: &[String]) -> Vec<String> {
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
    let bad = || SweepError::BadTimings { what: what.into() };
    let gpu = summarise_passes(&run.passes, run.frames.iter().map(|f| f.pass_ms.as_slice()))
        .map_err(|_| bad())?
        .ok_or_else(|| SweepError::NoTimings { what: what.into() })?;
    let cpu: Vec<f64> = run.frames.iter().map(|f| f.cpu_ms).collect();
    Ok(Timings {
        pass_median_ms: gpu
            .passes
            .into_iter()
            .map(|(name, s)| (name, s.median))
            .collect(),
        gpu_ms: gpu.total,
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
