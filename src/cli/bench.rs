//! `aerial bench`: time scenes and the empty pass, print a table, write
//! JSON, and optionally gate against a baseline by median ratio.

use aerial::bench::{
    self, compare, BaselineComparison, BenchReport, BenchScene, BenchSettings, PassReport, Progress,
};
use aerial::scene::Knob;
use anyhow::{bail, Context as _};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scene files (TOML) to benchmark; compared with a baseline by the
    /// path as given here, so give the same paths in CI and baseline runs.
    #[arg(required_unless_present = "from_json")]
    scenes: Vec<PathBuf>,
    /// Measured frames per scene.
    #[arg(long, default_value_t = 30)]
    frames: u32,
    /// Frames rendered and discarded before measuring, per scene.
    #[arg(long, default_value_t = 5)]
    warmup: u32,
    /// Override every scene's output width.
    #[arg(long)]
    width: Option<u32>,
    /// Override every scene's output height.
    #[arg(long)]
    height: Option<u32>,
    /// Set a knob on every scene, NAME=VALUE (repeatable; applied after
    /// --width/--height). An unknown NAME lists the knobs; the README's
    /// knob table says what each does.
    #[arg(long = "knob", value_name = "NAME=VALUE")]
    knobs: Vec<String>,
    /// Write the results as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Compare with a baseline written by --json: print each row's median
    /// ratio (this run / baseline) and fail if one exceeds --max-ratio.
    #[arg(long, value_name = "BASELINE", requires = "max_ratio")]
    compare: Option<PathBuf>,
    /// Largest accepted median ratio for --compare, e.g. 1.25.
    #[arg(long, value_name = "R", requires = "compare")]
    max_ratio: Option<f64>,
    /// Do not measure: print (and --compare) the results stored in FILE.
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with_all = [
            "scenes", "frames", "warmup", "json", "width", "height", "knobs", "validate", "device"
        ]
    )]
    from_json: Option<PathBuf>,
    #[command(flatten)]
    gpu: super::GpuArgs,
}

/// Exit status when the gate measured a slowdown past `--max-ratio`: 1, as
/// `compare` uses for a threshold, so CI can tell it from an error (2).
const EXIT_SLOWER: u8 = 1;

pub fn run(args: BenchArgs) -> anyhow::Result<ExitCode> {
    // Check the gate's argument before spending minutes measuring.
    if let Some(r) = args.max_ratio {
        if !(r.is_finite() && r > 0.0) {
            bail!("--max-ratio: {r} is not a positive number");
        }
    }
    let baseline = match &args.compare {
        Some(path) => Some(BenchReport::load(path)?),
        None => None,
    };
    if let Some(json) = &args.json {
        if let Some(base) = &args.compare {
            if aerial::files::same_file(json, base) {
                bail!(
                    "--json and --compare name the same file ({}): this run would replace \
                     the baseline it is judged against; write it elsewhere and copy it over \
                     the baseline once trusted",
                    json.display()
                );
            }
        }
    }
    // No output may be a file the run reads (`measure` adds the files the
    // scenes name once they are parsed).
    aerial::files::protect_inputs(
        args.scenes
            .iter()
            .chain(&args.compare)
            .chain(&args.from_json),
    );
    if let Some(json) = &args.json {
        // Checked before measuring: a bad path must not cost the run.
        aerial::files::check_destination(json).context("--json")?;
    }
    let report = match &args.from_json {
        Some(path) => BenchReport::load(path)?,
        None => measure(&args)?,
    };
    print_report(&report);
    if let Some(path) = &args.json {
        report.save(path)?;
        eprintln!("wrote {}", path.display());
    }
    if let (Some(baseline), Some(path), Some(max_ratio)) =
        (&baseline, &args.compare, args.max_ratio)
    {
        return gate(&compare(&report, baseline), path, baseline, max_ratio);
    }
    Ok(ExitCode::SUCCESS)
}

fn measure(args: &BenchArgs) -> anyhow::Result<BenchReport> {
    if args.frames == 0 {
        bail!("--frames: must be at least 1");
    }
    let knobs = args
        .knobs
        .iter()
        .map(|k| {
            let (name, value) = k
                .split_once('=')
                .with_context(|| format!("--knob '{k}': expected NAME=VALUE"))?;
            Ok((Knob::find(name.trim())?, value.trim()))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut scenes = Vec::new();
    for path in &args.scenes {
        let mut s = BenchScene::load(path)?;
        s.scene.set_output_size(args.width, args.height)?;
        for (knob, value) in &knobs {
            knob.set(&mut s.scene, value)
                .with_context(|| path.display().to_string())?;
        }
        scenes.push(s);
    }
    aerial::files::protect_inputs(scenes.iter().flat_map(|s| &s.scene.files));
    if let Some(json) = &args.json {
        aerial::files::check_destination(json).context("--json")?;
    }
    if cfg!(debug_assertions) {
        eprintln!("note: this is a debug build; users run release builds (cargo build --release)");
    }
    if args.gpu.validate.is_some() {
        eprintln!("note: validation is on; the timings include its overhead");
    }
    let settings = BenchSettings {
        warmup: args.warmup,
        frames: args.frames,
        validate: args.gpu.validate.unwrap_or_default(),
        device: args.gpu.device.clone(),
    };
    let mut progress = Bar::new();
    let report = bench::run(&scenes, &settings, &mut progress);
    progress.bar.finish_and_clear();
    Ok(report?)
}

/// A progress bar on stderr over all frames of the benchmark, hidden when
/// stderr is not a terminal (CI logs, redirected output).
struct Bar {
    bar: ProgressBar,
}

impl Bar {
    fn new() -> Bar {
        let target = if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let bar = ProgressBar::with_draw_target(Some(0), target);
        bar.set_style(
            ProgressStyle::with_template(
                "{wide_msg} [{bar:30}] {pos}/{len} frames, {elapsed} (eta {eta})",
            )
            // The template is a constant; it only fails if edited wrongly.
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        Bar { bar }
    }
}

impl Progress for Bar {
    fn start(&mut self, total_frames: u64) {
        self.bar.set_length(total_frames);
    }
    fn run(&mut self, label: &str) {
        self.bar.set_message(label.to_string());
    }
    fn frame(&mut self) {
        self.bar.inc(1);
    }
}

fn print_report(report: &BenchReport) {
    println!("device: {}", report.device);
    println!(
        "aerial {} (commit {}, {} build); {} warm-up + {} measured frames per run{}",
        report.aerial_version,
        report.commit,
        report.build,
        report.warmup,
        report.frames,
        if report.validate {
            "; validation on"
        } else {
            ""
        }
    );
    println!(
        "times in ms; x empty = median / median of the empty pass timed between the scene's frames (its row 'empty')"
    );
    println!("note: {}", aerial::render::SUBPASS_TIMING_NOTE);
    for e in &report.empty_passes {
        println!();
        println!("empty pass {}", e.resolution);
        print_rows(e.rows());
    }
    for s in &report.scenes {
        println!();
        println!(
            "{}  {}  {} triangles  sha256 {}",
            s.file,
            s.resolution,
            s.triangles,
            s.sha256.chars().take(12).collect::<String>()
        );
        let knobs: Vec<String> = s.knobs.iter().map(|(k, v)| format!("{k}={v}")).collect();
        println!("knobs: {}", knobs.join(", "));
        if s.passes.is_empty() {
            println!("(no GPU timestamps on this device: CPU frame time only)");
        }
        // The floor first: the empty pass timed between this scene's frames.
        print_rows(s.empty_pass_between_frames.iter().chain(s.rows()));
    }
}

fn print_rows<'a>(rows: impl Iterator<Item = &'a PassReport>) {
    println!(
        "{:<12} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8}",
        "pass", "median", "min", "p95", "max", "mean", "std dev", "x empty"
    );
    for r in rows {
        let s = &r.ms;
        let multiple = r
            .empty_pass_multiple
            .map_or_else(|| "-".to_string(), |m| format!("{m:.2}"));
        println!(
            "{:<12} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>8}",
            r.name, s.median, s.min, s.p95, s.max, s.mean, s.std_dev, multiple
        );
    }
}

/// Prints the comparison and fails if any ratio is above `max_ratio`, or if
/// nothing matched (a gate that checked nothing must not pass silently).
fn gate(
    c: &BaselineComparison,
    path: &std::path::Path,
    baseline: &BenchReport,
    max_ratio: f64,
) -> anyhow::Result<ExitCode> {
    println!();
    println!(
        "compared with {} (commit {}, {} build)",
        path.display(),
        baseline.commit,
        baseline.build
    );
    for w in &c.warnings {
        eprintln!("warning: {w}");
    }
    let width = c
        .rows
        .iter()
        .map(|r| r.key.scene.len())
        .max()
        .unwrap_or(5)
        .max(5);
    println!(
        "{:<width$}  {:<12} {:>11} {:>11} {:>7}",
        "scene", "pass", "baseline ms", "current ms", "ratio"
    );
    for r in &c.rows {
        let ratio = r
            .ratio
            .map_or_else(|| "n/a".to_string(), |x| format!("{x:.2}"));
        let flag = if r.exceeds(max_ratio) {
            format!("  > {max_ratio}")
        } else {
            String::new()
        };
        println!(
            "{:<width$}  {:<12} {:>11.3} {:>11.3} {:>7}{flag}",
            r.key.scene, r.key.pass, r.baseline_ms, r.current_ms, ratio
        );
    }
    for k in &c.missing {
        eprintln!("warning: in the baseline but not in this run: {k}");
    }
    for k in &c.new {
        eprintln!("warning: not in the baseline: {k}");
    }
    if c.rows.is_empty() {
        bail!(
            "nothing to compare: no scene and pass of this run is in {}",
            path.display()
        );
    }
    // A row without a ratio (a baseline median that is zero, negative or
    // not a number) was not compared; a gate that compared less than it
    // claims must not pass.
    let unjudged: Vec<String> = c
        .rows
        .iter()
        .filter(|r| r.ratio.is_none())
        .map(|r| format!("{} (baseline {} ms)", r.key, r.baseline_ms))
        .collect();
    if !unjudged.is_empty() {
        bail!(
            "{} row(s) of {} have no usable baseline median (must be a positive number), \
             so they cannot be compared: {}",
            unjudged.len(),
            path.display(),
            unjudged.join(", ")
        );
    }
    let slow = c.exceeding(max_ratio);
    if !slow.is_empty() {
        let list: Vec<String> = slow
            .iter()
            .map(|r| format!("{} ({:.2})", r.key, r.ratio.unwrap_or(f64::NAN)))
            .collect();
        eprintln!(
            "error: {} row(s) above --max-ratio {max_ratio}: {}",
            slow.len(),
            list.join(", ")
        );
        return Ok(ExitCode::from(EXIT_SLOWER));
    }
    println!("ok: every median ratio is at most {max_ratio}");
    Ok(ExitCode::SUCCESS)
}
