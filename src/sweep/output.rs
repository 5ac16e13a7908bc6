//! Writing a finished sweep: the terminal table, `sweep.csv`, `sweep.json`
//! and the `sweep.svg` plot (drawn by [`crate::report::plot`]).

use super::{ReferenceKind, SweepError, SweepResult, TimeAxis};
use crate::report::plot::{self, PlotPoint};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The sweep as CSV: one row per combination, knob columns first, then the
/// reference's settings, per-pass and total times in ms, the empty pass's
/// median and the GPU median as a multiple of it (`gpu_x_empty`), the
/// error metrics, the setup measures and the Pareto flag. Times are rounded to 0.1 µs (far below the noise
/// between frames); errors keep every digit. Fields are quoted only where
/// RFC 4180 needs it (a comma, quote or line break), lines end in `\n`.
pub fn to_csv(result: &SweepResult) -> Result<String, SweepError> {
    let mut header: Vec<String> = result.knobs.clone();
    header.push("reference".into());
    header.push("is_reference".into());
    header.extend(result.passes.iter().map(|p| format!("{p}_median_ms")));
    header.extend(
        [
            "gpu_median_ms",
            "gpu_p95_ms",
            "cpu_median_ms",
            "empty_median_ms",
            "gpu_x_empty",
            "rmse",
            "max_rel_error",
            "flip_mean",
            "flip_p99",
        ]
        .map(String::from),
    );
    header.extend(result.setup.iter().cloned());
    header.push("pareto".into());
    let mut out = csv::Writer::from_writer(Vec::new());
    out.write_record(&header)?;
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
            row.empty_median_ms
                .map(|ms| format!("{ms:.4}"))
                .unwrap_or_default(),
            row.gpu_x_empty
                .map(|x| format!("{x:.3}"))
                .unwrap_or_default(),
            row.rmse.to_string(),
            row.max_rel_error.to_string(),
            row.flip_mean.to_string(),
            row.flip_p99.to_string(),
        ]);
        // A measure this combination does not report is an empty cell.
        fields.extend(result.setup.iter().map(|name| {
            setup_value(row, name)
                .map(|v| v.to_string())
                .unwrap_or_default()
        }));
        fields.push(row.pareto.to_string());
        out.write_record(&fields)?;
    }
    let bytes = out
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    // Every field was a `String`, so the bytes are UTF-8 and nothing is lost.
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// The row's setup measure `name`, if it reported one.
fn setup_value(row: &super::Row, name: &str) -> Option<f64> {
    row.setup.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
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
    if result.time_axis == TimeAxis::GpuXEmpty {
        let _ = writeln!(
            out,
            "merged from {} shards; times are each shard's own, and the Pareto front is by x empty (GPU median over the shard's empty pass)",
            result.shards.len()
        );
    }
    for (k, w) in result.knobs.iter().zip(&widths) {
        let _ = write!(out, "{k:<w$}  ");
    }
    let _ = write!(
        out,
        "{:>10} {:>10} {:>8} {:>11} {:>9} {:>9} {:>9}",
        "gpu ms", "p95 ms", "x empty", "rmse", "max rel", "flip", "flip p99"
    );
    for name in &result.setup {
        let _ = write!(out, " {name:>w$}", w = name.len().max(9));
    }
    out.push_str("  pareto\n");
    for (row, label) in result.rows.iter().zip(&labels) {
        for (v, w) in label.iter().zip(&widths) {
            let _ = write!(out, "{v:<w$}  ");
        }
        let _ = write!(
            out,
            "{:>10.3} {:>10.3} {:>8} {:>11.4e} {:>9.2e} {:>9.5} {:>9.5}",
            row.gpu_ms.median,
            row.gpu_ms.p95,
            row.gpu_x_empty
                .map_or_else(|| "-".to_string(), |x| format!("{x:.2}")),
            row.rmse,
            row.max_rel_error,
            row.flip_mean,
            row.flip_p99,
        );
        for name in &result.setup {
            let w = name.len().max(9);
            match setup_value(row, name) {
                Some(v) => {
                    let _ = write!(out, " {v:>w$.1}");
                }
                None => {
                    let _ = write!(out, " {:>w$}", "-");
                }
            }
        }
        let _ = writeln!(
            out,
            "  {}{}",
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
                x: result.time_axis.of(r),
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
    if !result.shards.is_empty() {
        let _ = write!(subtitle, "; {} shards", result.shards.len());
    }
    if !fixed.is_empty() {
        let _ = write!(subtitle, "; {}", fixed.join(", "));
    }
    if result.reference == ReferenceKind::Cpu {
        subtitle.push_str("; reference: exact CPU image");
    }
    Ok(plot::error_vs_time_svg(&plot::Plot {
        title: &format!("{}: error against GPU time", result.scene),
        subtitle: &subtitle,
        x_label: match result.time_axis {
            TimeAxis::GpuMedianMs => "GPU time per frame, median (ms)",
            TimeAxis::GpuXEmpty => "GPU time per frame, median, as a multiple of the empty pass",
        },
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
        ("sweep.csv", to_csv(result)?),
        ("sweep.json", json),
        ("sweep.svg", to_svg(result)?),
    ];
    // The folders this creates, deepest first, removed again if the files
    // cannot be written: a failed sweep leaves no empty folder behind.
    let mut created: Vec<&Path> = dir
        .ancestors()
        .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
        .collect();
    let result = std::fs::create_dir_all(dir)
        .map_err(|error| SweepError::CreateDir {
            path: dir.to_path_buf(),
            error,
        })
        .and_then(|()| {
            // All three are written before any is renamed into place, so a
            // failure leaves none of them.
            let mut pending = Vec::new();
            for (name, text) in files {
                let path = dir.join(name);
                let file =
                    crate::safe_files::PendingFile::create(&path).map_err(SweepError::File)?;
                std::io::Write::write_all(&mut file.file(), text.as_bytes())
                    .map_err(|e| SweepError::File(file.io_error(e)))?;
                pending.push(file);
            }
            crate::safe_files::commit_all(pending).map_err(SweepError::File)
        });
    if result.is_err() {
        // remove_dir only removes empty folders: nothing else is touched.
        created.drain(..).for_each(|d| drop(std::fs::remove_dir(d)));
    }
    result
}
