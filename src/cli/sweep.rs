//! `aerial sweep`: render every combination of some knob settings, and
//! write error against GPU time as CSV, JSON and an SVG plot.

use aerial::render::render_on_cpu;
use aerial::render_run::{self, RenderSettings, RunSource};
use aerial::scene::Scene;
use aerial::sweep::{
    self, Axis, Job, ReferenceKind, Rendered, Shard, Sweep, SweepOptions, DEFAULT_MAX_COMBINATIONS,
};
use aerial::vk::validation;
use anyhow::Context as _;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
#[command(
    after_help = "\
Each combination is compared with a reference: the scene with every swept knob at its best \
value. That is a fixed value for some knobs (e.g. hdr_format=rgba32f), the last value listed \
for others (e.g. tessellation: so list values cheapest first), and the combination's own \
value for size. Knobs that are not swept keep the scene's settings.

With --reference cpu, each combination is compared with the exact image of its own scene instead: \
ray-cast in double precision against the analytic surfaces and shaded with the same formula \
(phong spheres, planes and cylinders only; other scenes are refused before rendering).

On many machines: --shard I/N renders only the combinations whose index k (the last knob \
changing fastest) has k % N == I, with I counted from 0. --shard kubernetes/N takes I from \
JOB_COMPLETION_INDEX (a Kubernetes Indexed Job); --shard slurm takes I and N from \
SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN and SLURM_ARRAY_TASK_COUNT (a Slurm job array). \
Each shard writes its own sweep.csv, sweep.json and sweep.svg; `aerial sweep merge DIR... \
--out-dir OUT` joins them into the result of the whole sweep.",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
pub struct SweepArgs {
    #[command(subcommand)]
    command: Option<SweepCommand>,
    /// Scene file (TOML).
    #[arg(required = true)]
    pub scene: Option<PathBuf>,
    /// A knob and the values to try, NAME=V1,V2,... (repeat for more knobs;
    /// cheapest value first). An unknown NAME lists the knobs.
    #[arg(long = "knob", value_name = "NAME=V1,V2,...", required = true)]
    knobs: Vec<String>,
    /// Timed frames per combination.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Frames rendered and discarded before the timed ones.
    #[arg(long, default_value_t = 2)]
    warmup: u32,
    /// Folder for sweep.csv, sweep.json and sweep.svg.
    #[arg(long, default_value = "sweep")]
    out_dir: PathBuf,
    /// Refuse sweeps with more combinations than this.
    #[arg(long, default_value_t = DEFAULT_MAX_COMBINATIONS)]
    max_combinations: usize,
    /// What errors are measured against: the GPU image at the best
    /// settings, or the exact CPU image of each combination's scene.
    #[arg(long, value_enum, default_value = "gpu-best")]
    reference: Reference,
    /// Run only one slice of the combinations: I/N (0 <= I < N),
    /// kubernetes/N (I from JOB_COMPLETION_INDEX) or slurm (I and N from
    /// the SLURM_ARRAY_TASK_* variables).
    #[arg(long, value_name = "I/N|kubernetes/N|slurm")]
    shard: Option<String>,
    #[command(flatten)]
    strict: super::StrictArgs,
    #[command(flatten)]
    gpu: super::GpuArgs,
}

#[derive(clap::Subcommand)]
enum SweepCommand {
    /// Join the outputs of every shard of one sweep (`--shard`) into the
    /// table, sweep.csv, sweep.json and sweep.svg of the whole sweep.
    Merge(MergeArgs),
}

#[derive(clap::Args)]
#[command(after_help = "\
Refuses shards of different sweeps (naming the field that differs), a shard given twice and \
missing shards (naming them); then nothing is written. Error columns are those of the sweep \
run at once; times stay each shard's own, and the Pareto front and plot rank them as \
multiples of each shard's empty pass (gpu_x_empty), which compare between machines.")]
struct MergeArgs {
    /// The shards' output folders (each with its sweep.json).
    #[arg(required = true, value_name = "DIR")]
    dirs: Vec<PathBuf>,
    /// Folder for the merged sweep.csv, sweep.json and sweep.svg.
    #[arg(long)]
    out_dir: PathBuf,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Reference {
    GpuBest,
    Cpu,
}

/// Refuses an output folder the sweep's files cannot be written to, before
/// any work: besides what `check_output_dir` refuses, a path on the way
/// that is a symbolic link to a missing target (creating the folder would
/// fail after the work) or a file (`o.png/` naming an existing file).
fn check_out_dir(dir: &Path) -> anyhow::Result<()> {
    // The path as components: `o.png/` is checked as `o.png`, which the
    // folder would have to be.
    let clean: PathBuf = dir.components().collect();
    for probe in clean.ancestors().filter(|p| !p.as_os_str().is_empty()) {
        let Ok(link) = std::fs::symlink_metadata(probe) else {
            continue;
        };
        let refuse = |reason: String| {
            anyhow::anyhow!("--out-dir {}: {reason}; nothing was run", dir.display())
        };
        match std::fs::metadata(probe) {
            Ok(meta) if meta.is_dir() => break,
            Ok(_) if probe == clean => {
                return Err(refuse("it exists and is not a folder".to_string()))
            }
            Ok(_) => {
                return Err(refuse(format!(
                    "{} is not a folder, so the folder cannot be created",
                    probe.display()
                )))
            }
            Err(_) if link.file_type().is_symlink() => {
                let target = std::fs::read_link(probe)
                    .map(|t| t.display().to_string())
                    .unwrap_or_default();
                return Err(refuse(format!(
                    "{} is a symbolic link to a missing target ({target}), so the folder \
                     cannot be created there",
                    probe.display()
                )));
            }
            Err(e) => return Err(refuse(format!("{}: {e}", probe.display()))),
        }
    }
    aerial::safe_files::check_output_dir(dir)?;
    for name in ["sweep.csv", "sweep.json", "sweep.svg"] {
        let path = dir.join(name);
        if path.exists() {
            aerial::safe_files::check_destination(&path)?;
        }
    }
    Ok(())
}

pub fn run(args: SweepArgs) -> anyhow::Result<()> {
    let Some(scene_path) = args.scene.clone() else {
        return match args.command {
            Some(SweepCommand::Merge(merge)) => run_merge(merge),
            // clap requires SCENE without a subcommand.
            None => anyhow::bail!("give a scene file, or `merge`"),
        };
    };
    let shard = args
        .shard
        .as_deref()
        .map(|spec| Shard::parse(spec, |var| std::env::var(var).ok()))
        .transpose()?;
    let (scene, scene_bytes) = read_scene(&args, &scene_path)?;
    // Before the work: a sweep takes minutes, a bad folder must not.
    check_out_dir(&args.out_dir)?;
    let axes = args
        .knobs
        .iter()
        .map(|k| Axis::parse(k))
        .collect::<Result<Vec<_>, _>>()?;
    let mut sweep = Sweep::new(
        scene_path.display().to_string(),
        scene,
        axes,
        SweepOptions {
            frames: args.frames,
            warmup: args.warmup,
            max_combinations: args.max_combinations,
            reference: match args.reference {
                Reference::GpuBest => ReferenceKind::GpuBest,
                Reference::Cpu => ReferenceKind::Cpu,
            },
        },
    )?;
    sweep.set_scene_hash(sweep::scene_hash(&scene_bytes));
    let total = announce_combinations(shard, args.shard.as_deref(), sweep.combinations().len())?;
    let mut done = 0;
    let result = sweep
        .run_shard(
            shard,
            |scene: &Scene, job: Job| render_job(&args, scene, job),
            |_, row| {
                done += 1;
                let settings: Vec<String> = row
                    .settings
                    .iter()
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect();
                eprintln!(
                    "[{done}/{total}] {}: {:.3} ms, rmse {:.3e}",
                    settings.join(" "),
                    row.gpu_ms.median,
                    row.rmse
                );
            },
        )
        .context("sweep failed; no output written")?;

    print!("{}", sweep::to_table(&result));
    for path in sweep::write_outputs(&result, &args.out_dir)? {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// The scene to sweep, loaded and checked (`--strict`), and its file's
/// bytes for the result's scene hash.
fn read_scene(args: &SweepArgs, scene_path: &Path) -> anyhow::Result<(Scene, Vec<u8>)> {
    // A FIFO or device would block or never end: refused before opening.
    if let Some(problem) = aerial::safe_files::input_file_problem(scene_path) {
        if std::fs::metadata(scene_path).is_ok() {
            anyhow::bail!(
                "{problem}; a scene is read from a regular file of at most {}",
                aerial::budget::Bytes(aerial::scene::MAX_SCENE_FILE_BYTES)
            );
        }
        anyhow::bail!("{problem}");
    }
    let scene = Scene::load(scene_path)?;
    args.strict.apply(&scene)?;
    aerial::safe_files::protect_inputs(&scene.files);
    let scene_bytes =
        aerial::safe_files::read_limited(scene_path, aerial::scene::MAX_SCENE_FILE_BYTES).map_err(
            |e| match e {
                Some(e) => anyhow::anyhow!("cannot read {}: {e}", scene_path.display()),
                None => anyhow::anyhow!(
                    "{}: longer than {} (reading stopped there)",
                    scene_path.display(),
                    aerial::budget::Bytes(aerial::scene::MAX_SCENE_FILE_BYTES)
                ),
            },
        )?;
    Ok((scene, scene_bytes))
}

/// Refuses a shard count above the sweep's `all` combinations, says how
/// many combinations this run renders, and returns that number.
fn announce_combinations(
    shard: Option<Shard>,
    spec: Option<&str>,
    all: usize,
) -> anyhow::Result<usize> {
    if let (Some(s), Some(spec)) = (shard, spec) {
        if s.count > all {
            anyhow::bail!(
                "--shard {spec}: {} shards{}, but the sweep has only {all} combinations, so \
                 some shards would have none (use at most {all} shards)",
                s.count,
                Shard::source(spec)
            );
        }
    }
    Ok(match shard {
        Some(s) => {
            let mine = s.combinations(all).len();
            eprintln!(
                "shard {} of {} (0-based): {mine} of {all} combinations",
                s.index, s.count
            );
            mine
        }
        None => {
            eprintln!("{all} combinations");
            all
        }
    })
}

/// The render settings of one run of the sweep, on the GPU `args` choose.
fn render_settings(
    args: &SweepArgs,
    warmup: u32,
    frames: u32,
    keep_hdr: bool,
    empty_pass: bool,
) -> RenderSettings {
    RenderSettings {
        validate: args.gpu.validate.unwrap_or_default(),
        device: args.gpu.device.clone(),
        pipeline_cache: args.gpu.pipeline_cache(),
        warmup,
        frames,
        keep_hdr,
        empty_pass_between_frames: empty_pass,
        ..Default::default()
    }
}

/// Does the GPU (or CPU reference) work of `job` for `scene`.
fn render_job(args: &SweepArgs, scene: &Scene, job: Job) -> anyhow::Result<Rendered> {
    let (warmup, frames, keep_hdr) = match job {
        Job::Timing { warmup, frames } => (warmup, frames, false),
        Job::Images => (0, 1, true),
        Job::Reference => {
            let hdr = render_on_cpu(scene)?;
            // The sRGB output through the renderer's own tone-map
            // pass, as the GPU images get theirs.
            let run = render_run::run(
                RunSource::HdrImage(&hdr, scene.tone_map),
                &render_settings(args, 0, 1, false, false),
                &mut || {},
            )?;
            validation::check(&run.validation)?;
            return Ok(Rendered {
                device: run.device.name.clone(),
                passes: Vec::new(),
                frames: Vec::new(),
                output: run.output,
                hdr: Some(hdr),
                setup: Vec::new(),
                empty_pass_ms: Vec::new(),
            });
        }
    };
    // The timed run also times the empty pass between its frames: the
    // floor its time is a multiple of.
    let timing = matches!(job, Job::Timing { .. });
    let run = render_run::render(
        scene,
        &render_settings(args, warmup, frames, keep_hdr, timing),
    )?;
    validation::check(&run.validation)?;
    Ok(Rendered {
        device: run.device.name.clone(),
        passes: run.passes.iter().map(|p| p.to_string()).collect(),
        frames: run.frames,
        output: run.output,
        hdr: run.hdr,
        setup: run
            .setup
            .iter()
            .map(|(name, value)| (name.to_string(), *value))
            .collect(),
        empty_pass_ms: run
            .empty_pass_frames
            .iter()
            .map(|f| f.pass_ms.iter().sum())
            .collect(),
    })
}

/// `aerial sweep merge`: reads every shard, merges, and only then writes.
fn run_merge(args: MergeArgs) -> anyhow::Result<()> {
    check_out_dir(&args.out_dir)?;
    // Writing over a shard's own files would lose it.
    let out = std::fs::canonicalize(&args.out_dir).ok();
    for dir in &args.dirs {
        if out.is_some() && std::fs::canonicalize(dir).ok() == out {
            anyhow::bail!(
                "--out-dir {} is one of the shards' folders; merge into another folder",
                args.out_dir.display()
            );
        }
    }
    let shards = args
        .dirs
        .iter()
        .map(|dir| sweep::read_shard(dir))
        .collect::<Result<Vec<_>, _>>()?;
    let result = sweep::merge(shards).context("merge failed; nothing written")?;
    eprintln!(
        "merged {} shards: {} combinations",
        result.shards.len(),
        result.rows.len()
    );
    print!("{}", sweep::to_table(&result));
    for path in sweep::write_outputs(&result, &args.out_dir)? {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
