//! `aerial bench`: measure scenes and the empty pass (time; instructions
//! and pipeline statistics when asked), print a table, write JSON, and
//! optionally gate against a baseline or another build on the interval of
//! each median ratio.

use aerial::bench::{
    self, compare, BaselineComparison, BenchReport, BenchScene, BenchSettings, Metric, PassReport,
    Progress, Verdict,
};
use aerial::callgrind::{spawn_counting_run, Callgrind};
use aerial::child_process::{self as child, Limit};
use aerial::scene::Knob;
use anyhow::{bail, Context as _};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::ffi::OsString;
use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::Duration;

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
    /// --width/--height). An unknown NAME lists the knobs; the knob table
    /// in docs/scenes.md says what each does.
    #[arg(long = "knob", value_name = "NAME=VALUE")]
    knobs: Vec<String>,
    /// What to measure and gate on, comma-separated or repeated: time (GPU
    /// timestamps per pass, CPU per frame; always measured), instructions
    /// (CPU instructions per pass under valgrind, CPU drivers only),
    /// work (pipeline statistics per pass).
    #[arg(
        long = "metric",
        value_enum,
        value_delimiter = ',',
        default_value = "time"
    )]
    metrics: Vec<Metric>,
    /// Write the results as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Run another aerial binary on the same scenes in interleaved rounds
    /// (this, other, other, this, ...) and print each row's ratio this /
    /// other with its 95 % interval, per metric.
    #[arg(long, value_name = "OTHER_AERIAL", conflicts_with_all = ["compare", "from_json"])]
    against: Option<PathBuf>,
    /// Rounds of --against: each runs both builds once, alternating which
    /// goes first.
    #[arg(long, default_value_t = 4, requires = "against")]
    rounds: u32,
    /// Time limit of each run of either build in --against, in seconds
    /// (the other build must also answer --version within it, or within
    /// 30 s if that is shorter): a build that takes longer is stopped and
    /// the comparison fails.
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_ROUND_TIMEOUT_S, requires = "against")]
    round_timeout: f64,
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
            "scenes", "frames", "warmup", "json", "width", "height", "knobs", "validate", "device",
            "against", "strict"
        ]
    )]
    from_json: Option<PathBuf>,
    #[command(flatten)]
    strict: super::StrictArgs,
    #[command(flatten)]
    gpu: super::GpuArgs,
}

/// The default `--round-timeout`: half an hour per run of a build, far
/// above a counted run of the example scenes at 640x360 (about 3 minutes).
const DEFAULT_ROUND_TIMEOUT_S: f64 = 1800.0;

/// The longest the other build of `--against` may take to answer
/// `--version`.
const PROBE_TIMEOUT: Duration = Duration::from_secs(30);

/// Exit status when the gate measured a slowdown past `--max-ratio`: 1, as
/// `compare` uses for a threshold, so CI can tell it from an error (2).
const EXIT_SLOWER: u8 = 1;
/// Exit status when some row's interval straddles `--max-ratio`: the run
/// cannot tell (more frames narrow the interval).
const EXIT_INCONCLUSIVE: u8 = 3;

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
            if aerial::safe_files::same_file(json, base) {
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
    aerial::safe_files::protect_inputs(
        args.scenes
            .iter()
            .chain(&args.compare)
            .chain(&args.from_json),
    );
    if let Some(json) = &args.json {
        // Checked before measuring: a bad path must not cost the run.
        check_json_output(json)?;
    }
    if let Some(other) = &args.against {
        return against(&args, other);
    }
    let report = match &args.from_json {
        Some(path) => BenchReport::load(path)?,
        None => measure(&args)?,
    };
    // The copy counting instructions under valgrind only hands its report
    // to the run that started it.
    let counting_copy = Callgrind::from_env()?.is_some();
    if !counting_copy {
        print_report(&report);
    }
    if let Some(path) = &args.json {
        report.save(path)?;
        if !counting_copy {
            eprintln!("wrote {}", path.display());
        }
    }
    if let (Some(baseline), Some(path), Some(max_ratio)) =
        (&baseline, &args.compare, args.max_ratio)
    {
        let gated = gated_metrics(&args.metrics);
        return gate(
            &compare(&report, baseline, &gated),
            &gated,
            path,
            baseline,
            max_ratio,
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The metrics a gate judges: those asked for that have ratios (work
/// counts explain a change; they are not a slowdown).
fn gated_metrics(metrics: &[Metric]) -> Vec<Metric> {
    let gated: Vec<Metric> = metrics
        .iter()
        .copied()
        .filter(|m| *m != Metric::Work)
        .collect();
    if gated.is_empty() {
        vec![Metric::Time]
    } else {
        gated
    }
}

/// The command line of a `bench` run of the same scenes and settings that
/// writes its report to `json`: for the counting copy under valgrind and
/// for the runs of `--against`.
fn run_args(args: &BenchArgs, metrics: &[Metric], json: &std::path::Path) -> Vec<OsString> {
    let mut out: Vec<OsString> = vec!["bench".into()];
    out.extend(args.scenes.iter().map(|p| p.clone().into_os_string()));
    out.push(format!("--frames={}", args.frames).into());
    out.push(format!("--warmup={}", args.warmup).into());
    if let Some(w) = args.width {
        out.push(format!("--width={w}").into());
    }
    if let Some(h) = args.height {
        out.push(format!("--height={h}").into());
    }
    for k in &args.knobs {
        out.push(format!("--knob={k}").into());
    }
    let names: Vec<String> = metrics.iter().map(value_name).collect();
    out.push(format!("--metric={}", names.join(",")).into());
    if let Some(v) = &args.gpu.validate {
        out.push(format!("--validate={}", value_name(v)).into());
    }
    if let Some(d) = &args.gpu.device {
        out.push(format!("--device={d}").into());
    }
    if args.gpu.no_pipeline_cache {
        out.push("--no-pipeline-cache".into());
    }
    if args.strict.strict {
        out.push("--strict".into());
    }
    let mut json_arg = OsString::from("--json=");
    json_arg.push(json);
    out.push(json_arg);
    out
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
    // A knob set twice would silently keep the last value, and the report
    // would not say which was meant.
    for (i, (knob, _)) in knobs.iter().enumerate() {
        if knobs[..i].iter().any(|(k, _)| k.name == knob.name) {
            bail!("--knob: knob {} is given twice; give it once", knob.name);
        }
    }
    let mut scenes = Vec::new();
    for path in &args.scenes {
        let mut s = BenchScene::load(path)?;
        args.strict
            .apply(&s.scene)
            .with_context(|| path.display().to_string())?;
        s.scene.set_output_size(args.width, args.height)?;
        for (knob, value) in &knobs {
            knob.set(&mut s.scene, value)
                .with_context(|| path.display().to_string())?;
        }
        scenes.push(s);
    }
    aerial::safe_files::protect_inputs(scenes.iter().flat_map(|s| &s.scene.files));
    if let Some(json) = &args.json {
        check_json_output(json)?;
    }
    if cfg!(debug_assertions) {
        eprintln!("note: this is a debug build; users run release builds (cargo build --release)");
    }
    if args.gpu.validate.is_some() {
        eprintln!("note: validation is on; the timings include its overhead");
    }
    let counting = Callgrind::from_env()?.is_some();
    let settings = BenchSettings {
        warmup: args.warmup,
        frames: args.frames,
        validate: args.gpu.validate.unwrap_or_default(),
        device: args.gpu.device.clone(),
        pipeline_cache: args.gpu.pipeline_cache(),
        metrics: args.metrics.clone(),
        counting,
    };
    if counting {
        return Ok(bench::run(&scenes, &settings, &mut ())?);
    }
    let mut progress = Bar::new();
    let report = bench::run(&scenes, &settings, &mut progress);
    progress.bar.finish_and_clear();
    let mut report = report?;
    if args.metrics.contains(&Metric::Instructions) {
        // An interrupt waits for valgrind to be stopped and the folder
        // to be removed (see `child`), also between the steps.
        let _busy = aerial::interrupt::Busy::start();
        aerial::interrupt::check()?;
        eprintln!("counting instructions under valgrind (a few seconds per frame and pass)...");
        let dir = aerial::safe_files::TempFolder::new().context("a folder for valgrind's files")?;
        let json = dir.path().join("instructions.json");
        spawn_counting_run(&run_args(args, &[Metric::Instructions], &json), dir.path())?;
        let counted = BenchReport::load_named(&json, "the counting run's report")?;
        bench::merge_counts(&mut report, &counted);
    }
    Ok(report)
}

/// Checks `--json` before any work: a file it can write, named as a file
/// (`o.json/` names a folder, which the report cannot be written as).
fn check_json_output(json: &Path) -> anyhow::Result<()> {
    if names_a_folder(json) {
        bail!(
            "--json {}: the path ends in '/', '.' or '..', so it names a folder; the \
             report is written as a file: name it like bench.json",
            json.display()
        );
    }
    aerial::safe_files::check_destination(json).context("--json")?;
    Ok(())
}

/// Whether `path` as written can only name a folder: it ends in `/`, `/.`
/// or `/..` (which `Path` itself would drop from the file name).
fn names_a_folder(path: &Path) -> bool {
    use std::os::unix::ffi::OsStrExt as _;
    let last = path
        .as_os_str()
        .as_bytes()
        .rsplit(|&b| b == b'/')
        .next()
        .unwrap_or_default();
    matches!(last, b"" | b"." | b"..")
}

/// The name a value is given by on the command line.
fn value_name(v: &impl clap::ValueEnum) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// `--against`: both builds on the same scenes in `rounds` interleaved
/// rounds, then each row's ratio this / other with its interval.
///
/// The other build is run from exactly the file named (made absolute:
/// never looked up in `PATH`), after it answers `--version` as an aerial
/// build. Every run is a child that dies with this one (see `child`),
/// stopped after `--round-timeout`; its temporary files and messages stay
/// in a temporary folder, shown only when it fails.
fn against(args: &BenchArgs, other: &Path) -> anyhow::Result<ExitCode> {
    if args.rounds == 0 {
        bail!("--rounds: must be at least 1");
    }
    let timeout = args.round_timeout;
    if !(timeout.is_finite() && timeout > 0.0 && timeout <= 1e9) {
        bail!("--round-timeout: {timeout} is not a number of seconds between 0 and 1e9");
    }
    let other = resolve_build(other)?;
    let this = std::env::current_exe().context("this binary's path")?;
    // Held throughout, so an interrupt between the runs also waits for the
    // temporary folder to be removed.
    let _busy = aerial::interrupt::Busy::start();
    let dir = aerial::safe_files::TempFolder::new().context("a folder for the rounds' reports")?;
    let limit = Limit {
        after: Duration::from_secs_f64(timeout),
        hint: " (--round-timeout)".to_string(),
    };
    probe_build(&other, dir.path(), &limit)?;
    let names = [
        format!("this build ({})", this.display()),
        format!("the other build ({})", other.display()),
    ];
    let mut reports: [Vec<BenchReport>; 2] = [Vec::new(), Vec::new()];
    for round in 0..args.rounds {
        // ABBA: the build that went second goes first in the next round, so
        // a drift of the machine's speed over the sitting cancels.
        let order = if round % 2 == 0 { [0, 1] } else { [1, 0] };
        for which in order {
            aerial::interrupt::check()?;
            let binary = if which == 0 { &this } else { &other };
            let name = &names[which];
            let json = dir.path().join(format!("round{round}-{which}.json"));
            let log = dir.path().join(format!("round{round}-{which}.log"));
            eprintln!(
                "round {}/{}: {}",
                round + 1,
                args.rounds,
                if which == 0 {
                    "this build"
                } else {
                    "other build"
                }
            );
            let mut command = Command::new(binary);
            command
                .args(run_args(args, &args.metrics, &json))
                .env("TMPDIR", dir.path())
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(std::fs::File::create(&log).context("a file for a round's messages")?);
            let what = format!("{name}, round {}", round + 1);
            let status = child::run(&mut command, &what, Some(limit.clone()))?;
            if !status.success() {
                bail!(
                    "{what}: bench failed ({status}){}",
                    shown_log(&log, dir.path())
                );
            }
            reports[which].push(BenchReport::load_named(
                &json,
                &format!("the report of {what}"),
            )?);
        }
    }
    let [mine, theirs] = reports;
    let this_pooled = bench::pool(&mine)?;
    let other_pooled = bench::pool(&theirs)?;
    print_report(&this_pooled);
    if let Some(path) = &args.json {
        this_pooled.save(path)?;
        eprintln!("wrote {}", path.display());
    }
    let c = compare(&this_pooled, &other_pooled, &gated_metrics(&args.metrics));
    println!();
    println!(
        "this build ({}) / other build ({} at {}), {} interleaved rounds",
        this_pooled.commit,
        other_pooled.commit,
        other.display(),
        args.rounds
    );
    print_ratios(&c, None);
    Ok(ExitCode::SUCCESS)
}

/// The `--against` build as an absolute path to an executable file: the
/// file checked is the file run (a bare `NAME` is `./NAME`, not a program
/// from `PATH`).
fn resolve_build(given: &Path) -> anyhow::Result<PathBuf> {
    use std::os::unix::fs::PermissionsExt as _;
    let path = std::fs::canonicalize(given).map_err(|e| {
        anyhow::anyhow!(
            "--against {}: {} (give the path of another aerial binary, e.g. \
             ../before/target/release/aerial; it is not looked up in PATH)",
            given.display(),
            match aerial::safe_files::input_file_problem(given) {
                Some(problem) => problem,
                None => e.to_string(),
            }
        )
    })?;
    let meta =
        std::fs::metadata(&path).with_context(|| format!("--against {}", given.display()))?;
    if !meta.is_file() {
        bail!("--against {}: not a file", given.display());
    }
    if meta.permissions().mode() & 0o111 == 0 {
        bail!("--against {}: not executable", given.display());
    }
    Ok(path)
}

/// Asks the other build for `--version` (within `limit`, at most
/// [`PROBE_TIMEOUT`]) and refuses a program that is not aerial.
fn probe_build(other: &Path, dir: &Path, limit: &Limit) -> anyhow::Result<()> {
    let out = dir.join("version.txt");
    let limit = Limit {
        after: limit.after.min(PROBE_TIMEOUT),
        hint: limit.hint.clone(),
    };
    let mut command = Command::new(other);
    command
        .arg("--version")
        .env("TMPDIR", dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).context("a file for the other build's version")?)
        .stderr(Stdio::null());
    let what = format!("the other build ({}) answering --version", other.display());
    let status = child::run(&mut command, &what, Some(limit))?;
    let text = child::tail_of(&out, 4096);
    let version = text.trim();
    match version.strip_prefix("aerial ") {
        Some(_) if status.success() => Ok(()),
        _ => bail!(
            "--against {}: not an aerial build (`--version` {}: '{}')",
            other.display(),
            status,
            version.chars().take(200).collect::<String>()
        ),
    }
}

/// The end of a failed run's messages, for its error, with the temporary
/// folder's name (gone once the command ends) left out.
fn shown_log(log: &Path, dir: &Path) -> String {
    let text =
        child::tail_of(log, 16 << 10).replace(&dir.display().to_string(), "(temporary folder)");
    let text = text.trim();
    if text.is_empty() {
        String::new()
    } else {
        format!(":\n{text}")
    }
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
    println!("note: {}", aerial::render::subpass_timing_note());
    for e in &report.empty_passes {
        println!();
        println!("empty pass {}", e.resolution);
        print_rows(e.rows());
    }
    for s in &report.scenes {
        println!();
        println!(
            "{}  {}  {} triangles drawn  sha256 {}",
            s.file,
            s.resolution,
            s.triangles,
            s.sha256.chars().take(12).collect::<String>()
        );
        let knobs: Vec<String> = s.knobs.iter().map(|(k, v)| format!("{k}={v}")).collect();
        // The tessellation knob's value counts two triangles per cell of
        // every parametric grid, cells that collapse at a sphere's poles
        // included; the count above is what the frame draws.
        println!("knobs: {}", knobs.join(", "));
        if s.passes.is_empty() {
            println!("(no GPU timestamps on this device: CPU frame time only)");
        }
        // The floor first: the empty pass timed between this scene's frames.
        print_rows(s.empty_pass_between_frames.iter().chain(s.rows()));
    }
}

fn print_rows<'a>(rows: impl Iterator<Item = &'a PassReport>) {
    let rows: Vec<&PassReport> = rows.collect();
    println!(
        "{:<12} {:>9} {:>19} {:>9} {:>9} {:>9} {:>9} {:>8}",
        "pass", "median", "median 95% CI", "min", "p95", "max", "std dev", "x empty"
    );
    for r in &rows {
        let s = &r.ms;
        let multiple = r
            .empty_pass_multiple
            .map_or_else(|| "-".to_string(), |m| format!("{m:.2}"));
        let ci = s.median_ci.map_or_else(
            || "-".to_string(),
            |i| format!("{:.3}..{:.3}", i.low, i.high),
        );
        println!(
            "{:<12} {:>9.3} {:>19} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>8}",
            r.name, s.median, ci, s.min, s.p95, s.max, s.std_dev, multiple
        );
    }
    if rows.iter().any(|r| r.instructions.is_some()) {
        println!(
            "{:<12} {:>15} {:>15} {:>15} {:>10} {:>8}",
            "pass", "instructions", "min", "max", "max/min-1", "x empty"
        );
        for r in &rows {
            let Some(c) = &r.instructions else { continue };
            let multiple = c
                .empty_pass_multiple
                .map_or_else(|| "-".to_string(), |m| format!("{m:.2}"));
            println!(
                "{:<12} {:>15.0} {:>15.0} {:>15.0} {:>10.2e} {:>8}",
                r.name, c.summary.median, c.summary.min, c.summary.max, c.spread, multiple
            );
        }
    }
    if rows.iter().any(|r| r.work.is_some()) {
        println!(
            "{:<12} {:>12} {:>12} {:>12} {:>14} {:>14} {:>12}",
            "pass", "primitives", "vertices", "clipped", "fragments", "depth passed", "compute"
        );
        for r in &rows {
            let Some(w) = &r.work else { continue };
            println!(
                "{:<12} {:>12} {:>12} {:>12} {:>14} {:>14} {:>12}",
                r.name,
                w.input_primitives,
                w.vertex_invocations,
                w.clipped_primitives,
                w.fragment_invocations,
                w.depth_passed,
                w.compute_invocations
            );
        }
    }
}

/// The comparison's rows: both medians, the ratio, its interval and, with
/// a limit, each row's verdict.
fn print_ratios(c: &BaselineComparison, max_ratio: Option<f64>) {
    let width = c
        .rows
        .iter()
        .map(|r| r.key.scene.len())
        .max()
        .unwrap_or(5)
        .max(5);
    println!(
        "{:<width$}  {:<12} {:<12} {:>14} {:>14} {:>7} {:>17}",
        "scene", "pass", "metric", "other/base", "current", "ratio", "95% interval"
    );
    for r in &c.rows {
        let ratio = r
            .ratio
            .map_or_else(|| "n/a".to_string(), |x| format!("{x:.4}"));
        let interval = r.interval.map_or_else(
            || "-".to_string(),
            |i| format!("{:.4}..{:.4}", i.low, i.high),
        );
        let flag = match max_ratio.map(|m| (m, r.verdict(m))) {
            _ if r.not_judged.is_some() => {
                format!("  (not judged: {})", r.not_judged.expect("checked"))
            }
            Some((m, Verdict::Fail)) => format!("  > {m}"),
            Some((m, Verdict::Inconclusive)) => format!("  straddles {m}"),
            _ => String::new(),
        };
        let metric = match r.metric {
            Metric::Time => "time ms",
            Metric::Instructions => "instructions",
            Metric::Work => "work",
        };
        // Instruction counts are whole numbers (a median of an even
        // number of frames may end in .5, shown rounded).
        let digits = if r.metric == Metric::Instructions {
            0
        } else {
            4
        };
        println!(
            "{:<width$}  {:<12} {:<12} {:>14.digits$} {:>14.digits$} {:>7} {:>17}{flag}",
            r.key.scene, r.key.pass, metric, r.baseline, r.current, ratio, interval
        );
    }
}

/// Prints the comparison and decides on each row's interval: fails (1) if
/// any lies wholly above `max_ratio`, is inconclusive (3) if any straddles
/// it, and errs (2) if the rows cannot back a verdict on the `gated`
/// metrics (see `BaselineComparison::judgeable`: a gate that checked
/// nothing, or less than it claims, must not pass). When one metric's rows
/// are all too small to judge, a failure of another's is still reported as
/// one.
fn gate(
    c: &BaselineComparison,
    gated: &[Metric],
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
    print_ratios(c, Some(max_ratio));
    for k in &c.missing {
        eprintln!("warning: in the baseline but not in this run: {k}");
    }
    for k in &c.new {
        eprintln!("warning: not in the baseline: {k}");
    }
    match c.judgeable(gated) {
        Ok(()) => {}
        // A metric had no row large enough to judge (instructions under
        // 3.5e6), but a row of another is slower beyond doubt: that
        // slowdown stands. Anything else is no verdict.
        Err(bench::baseline::Unjudgeable::NothingJudged { .. })
            if c.verdict(max_ratio) == Verdict::Fail => {}
        Err(e) => bail!("{}: {e}", path.display()),
    }
    let list = |v: Verdict| -> Vec<String> {
        c.rows
            .iter()
            .filter(|r| r.verdict(max_ratio) == v)
            .map(|r| format!("{} ({:.4})", r.key, r.ratio.unwrap_or(f64::NAN)))
            .collect()
    };
    match c.verdict(max_ratio) {
        Verdict::Fail => {
            let slow = list(Verdict::Fail);
            eprintln!(
                "error: {} row(s) slower than --max-ratio {max_ratio} (whole 95 % interval above it): {}",
                slow.len(),
                slow.join(", ")
            );
            Ok(ExitCode::from(EXIT_SLOWER))
        }
        Verdict::Inconclusive => {
            let unsure = list(Verdict::Inconclusive);
            eprintln!(
                "inconclusive: {} row(s) have a 95 % interval that straddles --max-ratio {max_ratio} \
                 (measure more frames to decide): {}",
                unsure.len(),
                unsure.join(", ")
            );
            Ok(ExitCode::from(EXIT_INCONCLUSIVE))
        }
        Verdict::Pass => {
            println!("ok: every ratio's 95 % interval is at most {max_ratio}");
            Ok(ExitCode::SUCCESS)
        }
    }
}
