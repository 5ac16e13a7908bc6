//! `aerial sweep`: render every combination of some knob settings, and
//! write error against GPU time as CSV, JSON and an SVG plot.

use aerial::app::{self, FrameSource, RenderSettings};
use aerial::render::render_reference;
use aerial::scene::Scene;
use aerial::sweep::{
    self, Axis, Job, ReferenceKind, Rendered, Sweep, SweepOptions, DEFAULT_MAX_COMBINATIONS,
};
use aerial::vk::validation;
use anyhow::Context as _;
use std::path::PathBuf;

#[derive(clap::Args)]
#[command(after_help = "\
Each combination is compared with a reference: the scene with every swept knob at its best \
value. That is a fixed value for some knobs (e.g. hdr_format=rgba32f), the last value listed \
for others (e.g. tessellation: so list values cheapest first), and the combination's own \
value for size. Knobs that are not swept keep the scene's settings.

With --reference cpu, each combination is compared with the exact image of its own scene instead: \
ray-cast in double precision against the analytic surfaces and shaded with the same formula \
(phong spheres, planes and cylinders only; other scenes are refused before rendering).")]
pub struct SweepArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
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
    #[command(flatten)]
    strict: super::StrictArgs,
    #[command(flatten)]
    gpu: super::GpuArgs,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Reference {
    GpuBest,
    Cpu,
}

pub fn run(args: SweepArgs) -> anyhow::Result<()> {
    let scene = Scene::load(&args.scene)?;
    args.strict.apply(&scene)?;
    aerial::files::protect_inputs(&scene.files);
    // Before the work: a sweep takes minutes, a bad folder must not.
    aerial::files::check_output_dir(&args.out_dir)?;
    for name in ["sweep.csv", "sweep.json", "sweep.svg"] {
        let path = args.out_dir.join(name);
        if path.exists() {
            aerial::files::check_destination(&path)?;
        }
    }
    let axes = args
        .knobs
        .iter()
        .map(|k| Axis::parse(k))
        .collect::<Result<Vec<_>, _>>()?;
    let sweep = Sweep::new(
        args.scene.display().to_string(),
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
    let total = sweep.combinations().len();
    eprintln!("{total} combinations");

    let settings = |warmup, frames, keep_hdr| RenderSettings {
        validate: args.gpu.validate.unwrap_or_default(),
        device: args.gpu.device.clone(),
        warmup,
        frames,
        keep_hdr,
        empty_pass_between_frames: false,
        ..Default::default()
    };
    let render = |scene: &Scene, job: Job| -> anyhow::Result<Rendered> {
        let (warmup, frames, keep_hdr) = match job {
            Job::Timing { warmup, frames } => (warmup, frames, false),
            Job::Images => (0, 1, true),
            Job::Reference => {
                let hdr = render_reference(scene)?;
                // The sRGB output through the renderer's own tone-map
                // pass, as the GPU images get theirs.
                let run = app::run(
                    FrameSource::HdrImage(&hdr, scene.tone_map),
                    &settings(0, 1, false),
                )?;
                validation::check(&run.validation)?;
                return Ok(Rendered {
                    device: run.device.name.clone(),
                    passes: Vec::new(),
                    frames: Vec::new(),
                    output: run.output,
                    hdr: Some(hdr),
                    setup: Vec::new(),
                });
            }
        };
        let run = app::render(scene, &settings(warmup, frames, keep_hdr))?;
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
        })
    };
    let result = sweep
        .run(render, |i, row| {
            let settings: Vec<String> = row
                .settings
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            eprintln!(
                "[{}/{total}] {}: {:.3} ms, rmse {:.3e}",
                i + 1,
                settings.join(" "),
                row.gpu_ms.median,
                row.rmse
            );
        })
        .context("sweep failed; no output written")?;

    print!("{}", sweep::to_table(&result));
    for path in sweep::write_outputs(&result, &args.out_dir)? {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
