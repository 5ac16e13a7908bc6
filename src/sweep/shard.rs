//! Sweeps on many machines: a sweep split into `N` deterministic slices
//! (shards), each run anywhere, and merged back into one result.
//!
//! Shard `i` of `n` (0-based: `0 <= i < n`) holds the combinations whose
//! index `k` (the last axis changing fastest) has `k % n == i`. Round-robin
//! spreads each axis's expensive values over the shards instead of giving
//! one shard all of them.
//!
//! A shard renders the references its combinations need itself, so its
//! error columns are those of the whole sweep, bit for bit; its time
//! columns are its own machine's, with its own empty-pass floor
//! ([`Row::gpu_x_empty`](super::Row::gpu_x_empty)).
//!
//! [`merge`] joins the shards' results. It refuses results of different
//! sweeps (naming the field: `aerial_version`, `scene_hash`,
//! `axes`, `frames`, `warmup`, `reference`, `combinations` or the shard
//! count), a shard given twice, missing shards (listing them) and a shard
//! whose rows are not its slice.

use super::run::{reference_values, Axis};
use super::{pareto_front, ReferenceKind, Row, SweepResult, TimeAxis};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One slice of a sweep: `index` of `count`, 0-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

/// Where the rows of a merged sweep were measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardSource {
    pub index: usize,
    pub device: String,
}

/// What can go wrong choosing a shard or merging shards. Each message names
/// the argument, variable, file or field involved.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    #[error("--shard '{spec}': {reason} (expected I/N with 0 <= I < N, kubernetes/N or slurm)")]
    Spec { spec: String, reason: String },
    #[error("--shard {spec}: environment variable {var} is {problem}")]
    Env {
        spec: String,
        var: &'static str,
        problem: String,
    },
    #[error("cannot read {}: {error}", path.display())]
    Read {
        path: PathBuf,
        error: std::io::Error,
    },
    /// Not a regular file, or longer than [`MAX_SWEEP_JSON_BYTES`].
    #[error("{}: {reason}", path.display())]
    Input { path: PathBuf, reason: String },
    /// A row that contradicts its sweep or holds a value no measurement
    /// gives.
    #[error("{}: rows[{row}] (combination {index}): {field}: {reason}", path.display())]
    BadRow {
        path: PathBuf,
        row: usize,
        index: usize,
        field: String,
        reason: String,
    },
    /// A field of the whole result that contradicts the rest.
    #[error("{}: {field}: {reason}", path.display())]
    BadField {
        path: PathBuf,
        field: &'static str,
        reason: String,
    },
    #[error("{} is not a sweep's JSON: {error}", path.display())]
    Parse {
        path: PathBuf,
        error: serde_json::Error,
    },
    #[error("{} is not the output of one shard (it has no \"shard\" field): run the sweep with --shard I/N", path.display())]
    NotAShard { path: PathBuf },
    #[error("{}: shard {index} of {count} is no shard (indices run from 0 to N - 1)", path.display())]
    BadShard {
        path: PathBuf,
        index: usize,
        count: usize,
    },
    #[error("nothing to merge: give the shards' folders")]
    Nothing,
    #[error("{} is a shard of a different sweep than {}: {field} differs ({ours} against {theirs})", path.display(), first.display())]
    DifferentSweep {
        path: PathBuf,
        first: PathBuf,
        field: &'static str,
        ours: String,
        theirs: String,
    },
    #[error("shard {index} is given twice: {} and {}", first.display(), second.display())]
    Duplicate {
        index: usize,
        first: PathBuf,
        second: PathBuf,
    },
    #[error("{} of {count} shards missing: {} {}", missing.len(), if missing.len() == 1 { "shard" } else { "shards" }, list(missing))]
    Missing { missing: Vec<usize>, count: usize },
    #[error("{}: shard {index} of {count} should hold combinations {expected} but holds {found}", path.display())]
    WrongRows {
        path: PathBuf,
        index: usize,
        count: usize,
        expected: String,
        found: String,
    },
}

fn list(indices: &[usize]) -> String {
    indices
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

impl Shard {
    /// Parses `--shard`: `I/N` (0-based), `kubernetes/N` (`I` from
    /// `JOB_COMPLETION_INDEX`, which an Indexed Job sets 0-based) or `slurm`
    /// (`I` = `SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN`, `N` =
    /// `SLURM_ARRAY_TASK_COUNT`, so arrays numbered from 0 or from 1 both
    /// work). `env` looks a variable up (`std::env::var` in the CLI).
    pub fn parse(spec: &str, env: impl Fn(&str) -> Option<String>) -> Result<Shard, ShardError> {
        let bad = |reason: &str| ShardError::Spec {
            spec: spec.to_string(),
            reason: reason.to_string(),
        };
        let var = |name: &'static str| -> Result<usize, ShardError> {
            let problem = |problem: String| ShardError::Env {
                spec: spec.to_string(),
                var: name,
                problem,
            };
            let value = env(name).ok_or_else(|| problem("not set".into()))?;
            value
                .trim()
                .parse()
                .map_err(|_| problem(format!("'{value}', not a whole number >= 0")))
        };
        let count = |n: &str| -> Result<usize, ShardError> {
            n.trim().parse().map_err(|_| bad("N is not a whole number"))
        };
        // Where each number came from, for the messages: a scheduler's
        // variable is named, so a job's wrong setting is found at once.
        let (index, count, index_from, count_from) = if spec.trim() == "slurm" {
            let id = var("SLURM_ARRAY_TASK_ID")?;
            let min = var("SLURM_ARRAY_TASK_MIN")?;
            let count = var("SLURM_ARRAY_TASK_COUNT")?;
            let index = id.checked_sub(min).ok_or_else(|| ShardError::Env {
                spec: spec.to_string(),
                var: "SLURM_ARRAY_TASK_ID",
                problem: format!("{id}, below SLURM_ARRAY_TASK_MIN ({min})"),
            })?;
            (
                index,
                count,
                format!(" (SLURM_ARRAY_TASK_ID {id} - SLURM_ARRAY_TASK_MIN {min})"),
                format!(" (SLURM_ARRAY_TASK_COUNT {count})"),
            )
        } else {
            let (i, n) = spec.split_once('/').ok_or_else(|| bad("no '/'"))?;
            let n = count(n)?;
            let (i, from) = match i.trim() {
                "kubernetes" => {
                    let i = var("JOB_COMPLETION_INDEX")?;
                    (i, format!(" (JOB_COMPLETION_INDEX {i})"))
                }
                i => (
                    i.parse()
                        .map_err(|_| bad("I is not a whole number, 'kubernetes' or 'slurm'"))?,
                    String::new(),
                ),
            };
            (i, n, from, String::new())
        };
        if count == 0 {
            return Err(bad(&format!("there must be at least 1 shard{count_from}")));
        }
        if index >= count {
            return Err(bad(&format!(
                "shard index {index}{index_from} is out of range for {count} shards{count_from} \
                 (indices are 0-based: 0 to {})",
                count - 1
            )));
        }
        Ok(Shard { index, count })
    }

    /// Where `spec` takes its numbers from, for messages about them: the
    /// scheduler's variables of `kubernetes/N` and `slurm`, nothing for
    /// `I/N`.
    pub fn source(spec: &str) -> &'static str {
        match spec.trim() {
            "slurm" => {
                " (I from SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN, N from \
                 SLURM_ARRAY_TASK_COUNT)"
            }
            s if s.starts_with("kubernetes/") => " (I from JOB_COMPLETION_INDEX)",
            _ => "",
        }
    }

    /// Whether combination `k` belongs to this shard.
    pub fn holds(self, k: usize) -> bool {
        k % self.count == self.index
    }

    /// The combinations of a sweep of `total` this shard holds, in order.
    pub fn combinations(self, total: usize) -> Vec<usize> {
        (self.index..total).step_by(self.count).collect()
    }
}

/// What identifies a scene file across machines: FNV-1a (64 bit) of its
/// bytes, in hex. Two shards of one sweep must read the same file.
pub fn scene_hash(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    format!("{hash:016x}")
}

/// The largest `sweep.json` [`read_shard`] reads: a row takes about a
/// kilobyte, and a sweep has at most a few thousand.
pub const MAX_SWEEP_JSON_BYTES: u64 = 64 << 20;

/// Reads `dir/sweep.json`, the output of one shard. The file must be a
/// regular file of at most [`MAX_SWEEP_JSON_BYTES`]: a device (a link to
/// `/dev/zero`), FIFO or folder is refused before it is opened, and
/// reading stops at the bound.
pub fn read_shard(dir: &Path) -> Result<(PathBuf, SweepResult), ShardError> {
    use crate::safe_files::TextReadError;
    let path = dir.join("sweep.json");
    let bound = crate::budget::Bytes(MAX_SWEEP_JSON_BYTES);
    let input = |reason: String| ShardError::Input {
        path: path.clone(),
        reason,
    };
    if let Some(problem) = crate::safe_files::input_file_problem(&path) {
        let shown = path.display().to_string();
        let problem = problem
            .strip_suffix(&shown)
            .map_or(problem.as_str(), |p| p.trim_end_matches([':', ' ']))
            .to_string();
        return Err(input(if std::fs::metadata(&path).is_ok() {
            format!(
                "{problem}; a shard's sweep.json is read from a regular file of at most {bound}"
            )
        } else {
            problem
        }));
    }
    let text = crate::safe_files::read_text(&path, MAX_SWEEP_JSON_BYTES).map_err(|e| match e {
        TextReadError::Io(error) => ShardError::Read {
            path: path.clone(),
            error,
        },
        TextReadError::TooLong(_) => input(format!(
            "longer than {bound}, the most read of a sweep.json (reading stopped there)"
        )),
        e @ TextReadError::NotUtf8 { .. } => input(format!("{e}; a sweep.json is UTF-8 text")),
    })?;
    // A shard's file has a "shard" object; say so plainly rather than
    // through a missing-field error when given a whole sweep or an older
    // file.
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|error| ShardError::Parse {
            path: path.clone(),
            error,
        })?;
    if value.get("shard").is_none_or(serde_json::Value::is_null) {
        return Err(ShardError::NotAShard { path });
    }
    // Parsed again from the text: a `Value`'s objects sort their keys, and
    // the order of knobs and passes is part of the result.
    let result: SweepResult = serde_json::from_str(&text).map_err(|error| ShardError::Parse {
        path: path.clone(),
        error,
    })?;
    Ok((path, result))
}

/// The fields two shards of one sweep share, by name, as text.
/// The scene's path is not one of them: machines may keep the same file
/// in different places.
fn identity(r: &SweepResult, shard: Shard) -> [(&'static str, String); 8] {
    [
        ("aerial_version", r.aerial_version.clone()),
        ("scene_hash", r.scene_hash.clone()),
        ("axes", r.axes.join(" ")),
        ("frames", r.frames.to_string()),
        ("warmup", r.warmup.to_string()),
        ("reference", r.reference.name().to_string()),
        ("combinations", r.combinations.to_string()),
        ("shard count", shard.count.to_string()),
    ]
}

/// Joins the results of every shard of one sweep (as [`read_shard`] gives
/// them: path and result) into the result of the whole sweep: rows in
/// combination order, pass and setup columns as a run at once lists them,
/// and the Pareto front over [`TimeAxis::GpuXEmpty`] (see the module docs
/// for what is refused).
pub fn merge(shards: Vec<(PathBuf, SweepResult)>) -> Result<SweepResult, ShardError> {
    let first_path = shards.first().ok_or(ShardError::Nothing)?.0.clone();
    let shard_of = |(path, r): &(PathBuf, SweepResult)| match r.shard {
        None => Err(ShardError::NotAShard { path: path.clone() }),
        Some(s) if s.index >= s.count => Err(ShardError::BadShard {
            path: path.clone(),
            index: s.index,
            count: s.count,
        }),
        Some(s) => Ok(s),
    };
    let first_shard = shard_of(&shards[0])?;
    let first_id = identity(&shards[0].1, first_shard);
    let count = first_shard.count;
    let mut by_index: Vec<Option<usize>> = vec![None; count];
    for (n, entry) in shards.iter().enumerate() {
        let shard = shard_of(entry)?;
        let (path, result) = entry;
        for ((field, ours), (_, theirs)) in identity(result, shard).into_iter().zip(&first_id) {
            if ours != *theirs {
                return Err(ShardError::DifferentSweep {
                    path: path.clone(),
                    first: first_path.clone(),
                    field,
                    ours,
                    theirs: theirs.clone(),
                });
            }
        }
        let slot = &mut by_index[shard.index];
        if let Some(earlier) = *slot {
            return Err(ShardError::Duplicate {
                index: shard.index,
                first: shards[earlier].0.clone(),
                second: path.clone(),
            });
        }
        *slot = Some(n);
        let expected = shard.combinations(result.combinations);
        let found: Vec<usize> = result.rows.iter().map(|r| r.index).collect();
        if found != expected {
            return Err(ShardError::WrongRows {
                path: path.clone(),
                index: shard.index,
                count,
                expected: list(&expected),
                found: list(&found),
            });
        }
    }
    let missing: Vec<usize> = (0..count).filter(|&i| by_index[i].is_none()).collect();
    if !missing.is_empty() {
        return Err(ShardError::Missing { missing, count });
    }
    for (path, result) in &shards {
        check_rows(path, result)?;
    }

    let first = &shards[0].1;
    let mut sources = Vec::with_capacity(count);
    let mut devices: Vec<&str> = Vec::new();
    let mut rows: Vec<Row> = Vec::with_capacity(first.combinations);
    for (index, n) in by_index.iter().enumerate() {
        // Every slot was filled: `missing` is empty.
        let Some(result) = n.map(|n| &shards[n].1) else {
            continue;
        };
        sources.push(ShardSource {
            index,
            device: result.device.clone(),
        });
        if !devices.contains(&result.device.as_str()) {
            devices.push(&result.device);
        }
        rows.extend(result.rows.iter().cloned());
    }
    rows.sort_by_key(|r| r.index);
    // Columns in the order a run at once finds them: by combination.
    let mut passes: Vec<String> = Vec::new();
    let mut setup: Vec<String> = Vec::new();
    for row in &rows {
        super::run::add_new_names(&mut passes, row.pass_median_ms.iter().map(|(p, _)| p));
        super::run::add_new_names(&mut setup, row.setup.iter().map(|(s, _)| s));
    }
    let time_axis = TimeAxis::GpuXEmpty;
    let points: Vec<(f64, f64)> = rows.iter().map(|r| (time_axis.of(r), r.rmse)).collect();
    for (row, on_front) in rows.iter_mut().zip(pareto_front(&points)) {
        row.pareto = on_front;
    }
    let device = devices.join("; ");
    Ok(SweepResult {
        aerial_version: first.aerial_version.clone(),
        scene: first.scene.clone(),
        scene_hash: first.scene_hash.clone(),
        device,
        frames: first.frames,
        warmup: first.warmup,
        reference: first.reference,
        knobs: first.knobs.clone(),
        axes: first.axes.clone(),
        combinations: first.combinations,
        shard: None,
        shards: sources,
        time_axis,
        passes,
        setup,
        asset_warnings: first.asset_warnings,
        rows,
    })
}

/// Checks every row of a shard's result against the sweep it claims to
/// belong to: its settings must be the combination its index names (the
/// axes listed in the file, the last changing fastest), its reference the
/// one that combination is compared with, and every measured value a
/// finite number of its range (times and errors at least 0, FLIP at most
/// 1, the floor above 0, `gpu_x_empty` the GPU median over the floor). A
/// row that contradicts its index would be merged under another label.
fn check_rows(path: &Path, result: &SweepResult) -> Result<(), ShardError> {
    let axes = sweep_axes(path, result)?;
    for (n, row) in result.rows.iter().enumerate() {
        let check = RowCheck { path, n, row };
        let own = check.labels(result, &axes)?;
        check.numbers(own)?;
    }
    Ok(())
}

/// The axes of a shard's result, which its knobs and number of
/// combinations must agree with.
fn sweep_axes(path: &Path, result: &SweepResult) -> Result<Vec<Axis>, ShardError> {
    let field_error = |field: &'static str, reason: String| ShardError::BadField {
        path: path.to_path_buf(),
        field,
        reason,
    };
    let axes = result
        .axes
        .iter()
        .map(|a| Axis::parse(a))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| field_error("axes", e.to_string()))?;
    let names: Vec<&str> = axes.iter().map(|a| a.knob.name).collect();
    if result.knobs != names {
        return Err(field_error(
            "knobs",
            format!(
                "{} do not match the axes' knobs {}",
                result.knobs.join(", "),
                names.join(", ")
            ),
        ));
    }
    let total = axes
        .iter()
        .try_fold(1usize, |n, a| n.checked_mul(a.values.len()));
    if total != Some(result.combinations) {
        return Err(field_error(
            "combinations",
            format!(
                "{}, but the axes make {}",
                result.combinations,
                total.map_or_else(|| "too many".to_string(), |t| t.to_string())
            ),
        ));
    }
    Ok(axes)
}

/// The checks of one row (the `n`th) of a shard's result.
struct RowCheck<'a> {
    path: &'a Path,
    n: usize,
    row: &'a Row,
}

impl RowCheck<'_> {
    fn bad(&self, field: &str, reason: String) -> ShardError {
        ShardError::BadRow {
            path: self.path.to_path_buf(),
            row: self.n,
            index: self.row.index,
            field: field.to_string(),
            reason,
        }
    }

    /// Checks the row's settings, reference and `is_reference` against
    /// the combination its index names; returns whether the combination
    /// is its own reference.
    fn labels(&self, result: &SweepResult, axes: &[Axis]) -> Result<bool, ShardError> {
        let row = self.row;
        if row.index >= result.combinations {
            return Err(self.bad(
                "index",
                format!("beyond the sweep's {} combinations", result.combinations),
            ));
        }
        // The combination's values: the index in mixed radix, the last
        // axis the fastest digit.
        let mut values = vec![String::new(); axes.len()];
        let mut rest = row.index;
        for (slot, axis) in values.iter_mut().zip(axes).rev() {
            *slot = axis.values[rest % axis.values.len()].clone();
            rest /= axis.values.len();
        }
        let show = |pairs: &[(String, String)]| {
            pairs
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let pairs = |values: &[String]| -> Vec<(String, String)> {
            axes.iter()
                .zip(values)
                .map(|(a, v)| (a.knob.name.to_string(), v.clone()))
                .collect()
        };
        let expected = pairs(&values);
        if row.settings != expected {
            return Err(self.bad(
                "settings",
                format!(
                    "'{}' contradicts the row's index, which is '{}' in this sweep",
                    show(&row.settings),
                    show(&expected)
                ),
            ));
        }
        let reference_of = match result.reference {
            ReferenceKind::GpuBest => reference_values(axes, &values),
            ReferenceKind::Cpu => values.clone(),
        };
        let reference = pairs(&reference_of);
        if row.reference != reference {
            return Err(self.bad(
                "reference",
                format!(
                    "'{}', but this combination's reference is '{}'",
                    show(&row.reference),
                    show(&reference)
                ),
            ));
        }
        let own = result.reference == ReferenceKind::GpuBest && values == reference_of;
        if row.is_reference != own {
            return Err(self.bad(
                "is_reference",
                format!(
                    "{}, but this combination {} its own reference",
                    row.is_reference,
                    if own { "is" } else { "is not" }
                ),
            ));
        }
        Ok(own)
    }

    /// Refuses `v` unless it is finite, at least 0 and at most `max`.
    fn number(&self, field: &str, v: f64, max: f64) -> Result<(), ShardError> {
        if !v.is_finite() || v < 0.0 || v > max {
            let range = if max.is_finite() {
                format!("a number from 0 to {max}")
            } else {
                "a finite number, at least 0".to_string()
            };
            return Err(self.bad(field, format!("{v} is not {range}")));
        }
        Ok(())
    }

    /// Checks every measured value of the row: errors (all 0 where the
    /// combination is `own` reference), times and the floor.
    fn numbers(&self, own: bool) -> Result<(), ShardError> {
        let row = self.row;
        let any = f64::INFINITY;
        self.number("rmse", row.rmse, any)?;
        self.number("max_rel_error", row.max_rel_error, any)?;
        self.number("flip_mean", row.flip_mean, 1.0)?;
        self.number("flip_p99", row.flip_p99, 1.0)?;
        if own && (row.rmse, row.max_rel_error, row.flip_mean, row.flip_p99) != (0.0, 0.0, 0.0, 0.0)
        {
            return Err(self.bad(
                "rmse",
                "a combination compared with itself has every error 0".to_string(),
            ));
        }
        for (name, s) in [("gpu_ms", &row.gpu_ms), ("cpu_ms", &row.cpu_ms)] {
            for (stat, v) in s.named() {
                self.number(&format!("{name}.{stat}"), v, any)?;
            }
            if s.count == 0 {
                return Err(self.bad(&format!("{name}.count"), "0 frames".to_string()));
            }
            if !(s.min <= s.median && s.median <= s.p95 && s.p95 <= s.max) {
                return Err(self.bad(
                    name,
                    format!(
                        "min {} <= median {} <= p95 {} <= max {} does not hold",
                        s.min, s.median, s.p95, s.max
                    ),
                ));
            }
        }
        for (pass, ms) in &row.pass_median_ms {
            self.number(&format!("pass_median_ms.{pass}"), *ms, any)?;
        }
        for (name, v) in &row.setup {
            self.number(&format!("setup.{name}"), *v, any)?;
        }
        self.floor()
    }

    /// The empty pass's median and `gpu_x_empty`: both or neither, the
    /// floor above 0, and `gpu_x_empty` the GPU median over it.
    fn floor(&self) -> Result<(), ShardError> {
        let row = self.row;
        let any = f64::INFINITY;
        match (row.empty_median_ms, row.gpu_x_empty) {
            (None, None) => {}
            (Some(floor), Some(x)) => {
                self.number("empty_median_ms", floor, any)?;
                if floor == 0.0 {
                    return Err(self.bad(
                        "empty_median_ms",
                        "0; the empty pass always takes time".to_string(),
                    ));
                }
                self.number("gpu_x_empty", x, any)?;
                let expected = row.gpu_ms.median / floor;
                if (x - expected).abs() > 1e-9 * expected.abs().max(x.abs()) {
                    return Err(self.bad(
                        "gpu_x_empty",
                        format!("{x} is not gpu_ms.median / empty_median_ms ({expected})"),
                    ));
                }
            }
            (floor, x) => {
                return Err(self.bad(
                    "gpu_x_empty",
                    format!("{x:?} with empty_median_ms {floor:?}: one is given without the other"),
                ))
            }
        }
        Ok(())
    }
}
