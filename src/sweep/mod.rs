//! Error against run time: render every combination of some knob settings,
//! time each one, measure how far its image is from a reference, and find
//! the combinations worth using (the Pareto front).
//!
//! # The reference
//!
//! A combination is compared with the same scene rendered with every *swept*
//! knob at its [`Best`](crate::scene::Best) value:
//!
//! - [`Best::Fixed`](crate::scene::Best::Fixed)`(v)`: `v`, whether or not the sweep lists it;
//! - [`Best::LastListed`](crate::scene::Best::LastListed): the last value listed for that knob in this sweep,
//!   so **list values cheapest first** (e.g. `tessellation=0.25,0.5,1,2`);
//! - [`Best::Unchanged`](crate::scene::Best::Unchanged) (image size): the combination's own value, so both
//!   images always have the same size. Each size then has its own reference.
//!
//! Knobs that are not swept keep the scene's own setting in the combination
//! and in its reference alike: a tessellation sweep of a scene that mixes
//! shading models must not be measured against an all-Phong version of it.
//! Each distinct reference is rendered once. A combination that is its own
//! reference is compared with its own image, so its error is exactly 0.
//!
//! With [`ReferenceKind::Cpu`] the reference is instead the exact image of
//! the combination's *own* scene ([`crate::render::render_on_cpu`]):
//! every knob is applied first, because some (`lights`, `light_cutoff`)
//! change what the exact image is, and the rest (tessellation, HDR format)
//! only change how far the GPU is from it. References are cached by
//! [`CpuScene`](crate::render::cpu_renderer::CpuScene), everything the CPU renderer reads, so a sweep over
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
//! - `max_rel_error`: the largest per-pixel relative error of the linear HDR
//!   image ([`max_relative_error`]).
//! - `flip_mean` and `flip_p99`: FLIP of the tone-mapped 8-bit sRGB outputs
//!   (what a viewer sees), mean and 99th percentile over the pixels.
//! - Setup measures the renderer reports beyond its passes, by name: the
//!   CPU time recording the frame's command buffer took (`record_ms`, wall
//!   clock, once per build); with objects, the geometry and instance
//!   buffers' sizes (`geometry_kib`, `instances_kib`); with an atmosphere,
//!   the optical-depth table's size (`od_table_kib`) and bake time
//!   (`od_table_bake_ms`, wall clock).
//!
//! See [`crate::report::image_diff`] for the exact metric definitions.
//!
//! # Pareto front
//!
//! A combination is on the front when no other combination is at least as
//! fast and at least as accurate (by `rmse`) and strictly better in one of
//! the two; see [`pareto_front`].
//!
//! # Layout
//!
//! [`run`] lists and measures the combinations; [`output`] turns the result
//! into the terminal table, `sweep.csv`, `sweep.json` and `sweep.svg`;
//! [`shard`] splits a sweep into deterministic slices and merges the
//! slices' results back into one. This file holds what they share: the
//! errors and the result types.
//!
//! # Time against the floor
//!
//! Besides milliseconds, each combination's timed run also times the empty
//! pass at the combination's output size after each frame, on the same
//! device and over the same seconds (see
//! [`RenderSettings::empty_pass_between_frames`](crate::render_run::RenderSettings::empty_pass_between_frames)).
//! `gpu_x_empty` is the GPU median divided by that floor's median: a
//! ratio that stays comparable between machines, which is what a sweep
//! merged from shards run on different hosts is plotted and ranked by.
//!
//! Rendering is left to the caller (a closure taking a scene and a [`Job`]),
//! which keeps this module free of Vulkan and lets it be tested without a
//! device.

pub mod output;
pub mod run;
pub mod shard;

pub use output::{to_csv, to_svg, to_table, write_outputs};
pub use run::{
    pareto_front, Axis, Combination, Job, Rendered, Sweep, SweepOptions, DEFAULT_MAX_COMBINATIONS,
};
pub use shard::{merge, read_shard, scene_hash, Shard, ShardError, ShardSource};

use crate::render::cpu_renderer::CpuRenderError;
use crate::render::Pixels;
use crate::report::image_diff::CompareError;
use crate::report::plot::PlotError;
use crate::report::stats::Summary;
use crate::scene::KnobError;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::path::PathBuf;

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
        source: CpuRenderError,
    },
    #[error("knob {knob} is given twice; list all its values in one --knob")]
    DuplicateKnob { knob: &'static str },
    #[error("knob {knob}: value '{value}' is listed twice")]
    DuplicateValue { knob: &'static str, value: String },
    #[error("nothing to sweep: give at least one --knob NAME=VALUE[,VALUE...]")]
    NoKnobs,
    #[error("the sweep has {count} combinations, more than the limit of {max} (raise it with --max-combinations)")]
    TooMany { count: String, max: usize },
    #[error("--shard {index}/{count}: the sweep has only {combinations} combinations, so some shards would have none (use at most {combinations} shards)")]
    EmptyShard {
        index: usize,
        count: usize,
        combinations: usize,
    },
    #[error("rendering {what} failed: {reason}")]
    Render { what: String, reason: String },
    /// The sweep, or one of its renders, does not fit the memory budget
    /// (or a texture cannot be sized).
    #[error(transparent)]
    Memory(crate::render::RenderError),
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
    File(crate::safe_files::FileError),
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error("cannot serialise the sweep as JSON: {0}")]
    Json(#[from] serde_json::Error),
    #[error("cannot write the sweep as CSV: {0}")]
    Csv(#[from] csv::Error),
}

/// What each combination's error is measured against (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceKind {
    /// The GPU image with every swept knob at its [`Best`](crate::scene::Best) value.
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

/// One measured combination.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// The combination's index in the whole sweep (the last axis changing
    /// fastest), whichever shard measured it.
    pub index: usize,
    /// Knob name and value, in the order of the sweep's axes.
    #[serde(serialize_with = "ordered_map", deserialize_with = "ordered_pairs")]
    pub settings: Vec<(String, String)>,
    /// The settings of the scene the reference image was made from (with a
    /// CPU reference, the row's own).
    #[serde(serialize_with = "ordered_map", deserialize_with = "ordered_pairs")]
    pub reference: Vec<(String, String)>,
    /// Whether this combination is its own reference (error 0; never with
    /// a CPU reference).
    pub is_reference: bool,
    /// Median GPU time of each pass, in ms.
    #[serde(serialize_with = "ordered_map", deserialize_with = "ordered_pairs")]
    pub pass_median_ms: Vec<(String, f64)>,
    /// Per-frame GPU time (sum of the passes), in ms.
    pub gpu_ms: Summary,
    /// Per-frame CPU time from submit to fence, in ms.
    pub cpu_ms: Summary,
    /// Median of the empty pass timed between this combination's frames
    /// (at its output size, on the same device), in ms; `None` when the
    /// renderer reported none.
    pub empty_median_ms: Option<f64>,
    /// `gpu_ms.median / empty_median_ms`: GPU time as a multiple of the
    /// floor of the machine that measured it.
    pub gpu_x_empty: Option<f64>,
    /// Whole-image RMSE of the linear HDR image against the reference.
    pub rmse: f64,
    /// Largest per-pixel relative error of the linear HDR image
    /// ([`max_relative_error`]).
    pub max_rel_error: f64,
    /// Mean FLIP of the sRGB output against the reference's.
    pub flip_mean: f64,
    /// 99th percentile of the per-pixel FLIP.
    pub flip_p99: f64,
    /// Setup measures of the timed run, by name (see the module docs).
    #[serde(serialize_with = "ordered_map", deserialize_with = "ordered_pairs")]
    pub setup: Vec<(String, f64)>,
    /// On the Pareto front of (GPU median, rmse).
    pub pareto: bool,
}

/// A finished sweep: what `sweep.json` holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SweepResult {
    /// The `aerial` version that measured it.
    pub aerial_version: String,
    pub scene: String,
    /// What identifies the scene across machines: see [`scene_hash`].
    pub scene_hash: String,
    /// The device (for a merged sweep, every shard's device, distinct
    /// names joined by `"; "`).
    pub device: String,
    pub frames: u32,
    pub warmup: u32,
    /// What the errors are measured against: `"gpu_best"` or `"cpu"`.
    pub reference: ReferenceKind,
    /// Swept knob names, in axis order.
    pub knobs: Vec<String>,
    /// Every axis as `NAME=V1,V2,...`, in order: the whole sweep, also in a
    /// shard's result, which holds only some of the values.
    pub axes: Vec<String>,
    /// Combinations in the whole sweep.
    pub combinations: usize,
    /// Which slice this result is, for the output of `--shard`; `None` for
    /// a whole sweep, run at once or merged.
    pub shard: Option<Shard>,
    /// Where the rows were measured: one entry per shard (with its own
    /// device), empty for a sweep run at once.
    pub shards: Vec<ShardSource>,
    /// What the Pareto front and the plot rank time by: `gpu_median_ms` for
    /// a sweep measured on one machine at once, `gpu_x_empty` for one
    /// merged from shards (milliseconds of different hosts do not compare).
    pub time_axis: TimeAxis,
    /// Every pass name seen, in frame order.
    pub passes: Vec<String>,
    /// Every setup measure name seen, in order.
    pub setup: Vec<String>,
    /// Asset warnings of the scene's models (missing MTL libraries and
    /// textures drawn with defaults and placeholders).
    pub asset_warnings: usize,
    pub rows: Vec<Row>,
}

/// Which time column ranks the rows (see [`SweepResult::time_axis`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeAxis {
    /// The median GPU time per frame, in ms.
    #[default]
    GpuMedianMs,
    /// The median GPU time per frame as a multiple of the empty pass.
    GpuXEmpty,
}

impl TimeAxis {
    /// The row's time on this axis (NaN when the row has no floor, which
    /// puts it on no front and off the plot's scale).
    pub fn of(self, row: &Row) -> f64 {
        match self {
            TimeAxis::GpuMedianMs => row.gpu_ms.median,
            TimeAxis::GpuXEmpty => row.gpu_x_empty.unwrap_or(f64::NAN),
        }
    }
}

/// Serialises `(key, value)` pairs as a JSON object in their own order
/// (serde_json's `Map` would sort the keys).
fn ordered_map<S: Serializer, V: Serialize>(
    pairs: &[(String, V)],
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_map(pairs.iter().map(|(k, v)| (k, v)))
}

/// Reads a JSON object into `(key, value)` pairs in the file's order (the
/// inverse of [`ordered_map`]).
fn ordered_pairs<'de, D: Deserializer<'de>, V: Deserialize<'de>>(
    d: D,
) -> Result<Vec<(String, V)>, D::Error> {
    struct Pairs<V>(std::marker::PhantomData<V>);
    impl<'de, V: Deserialize<'de>> serde::de::Visitor<'de> for Pairs<V> {
        type Value = Vec<(String, V)>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("an object")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> Result<Self::Value, A::Error> {
            let mut pairs = Vec::new();
            while let Some(pair) = map.next_entry()? {
                pairs.push(pair);
            }
            Ok(pairs)
        }
    }
    d.deserialize_map(Pairs(std::marker::PhantomData))
}

/// The largest relative error of `test` against `reference` (linear RGBA
/// images of one size): per pixel, the largest |test − reference| over R, G
/// and B, divided by the reference pixel's brightest channel. A pixel darker
/// than a thousandth of the reference's 99th-percentile brightness is
/// divided by that floor instead: against a black pixel any difference
/// would be infinitely relative, and the percentile (rather than the
/// brightest pixel) keeps a small sun disc from lifting the floor above the
/// sky. For an all-black reference the floor is 1 (absolute error).
pub fn max_relative_error(reference: &Pixels<f32>, test: &Pixels<f32>) -> f64 {
    let brightest = |p: &[f32]| p[..3].iter().fold(0f64, |m, &c| m.max(f64::from(c)));
    let mut levels: Vec<f64> = reference.data.chunks_exact(4).map(brightest).collect();
    if levels.is_empty() {
        return 0.0;
    }
    let rank = ((levels.len() - 1) as f64 * 0.99).round() as usize;
    let (_, p99, _) = levels.select_nth_unstable_by(rank, f64::total_cmp);
    let floor = match *p99 * 1e-3 {
        f if f > 0.0 => f,
        _ => 1.0,
    };
    reference
        .data
        .chunks_exact(4)
        .zip(test.data.chunks_exact(4))
        .map(|(r, t)| {
            let difference = (0..3).fold(0f64, |m, c| {
                m.max((f64::from(t[c]) - f64::from(r[c])).abs())
            });
            difference / brightest(r).max(floor)
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests;
