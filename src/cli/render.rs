//! `aerial render`: render one scene to PNG (and optionally EXR).

use aerial::app::{self, RenderSettings};
use aerial::render::output;
use aerial::report::stats::Summary;
use aerial::scene::Scene;
use aerial::vk::validation::{self, Validation};
use anyhow::{bail, Context as _};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file (TOML); omit for the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Tone-mapped 8-bit sRGB output.
    #[arg(long, default_value = "out.png")]
    out: PathBuf,
    /// Linear HDR image before tone mapping (OpenEXR).
    #[arg(long)]
    hdr: Option<PathBuf>,
    /// Override the scene's output width.
    #[arg(long)]
    width: Option<u32>,
    /// Override the scene's output height.
    #[arg(long)]
    height: Option<u32>,
    /// Frames to render; with more than one, per-pass GPU times are reported.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    /// Enable the Khronos validation layer: --validate=core, sync,
    /// best-practices or all (plain --validate is all).
    /// Any message fails the run.
    #[arg(
        long,
        value_enum,
        value_name = "MODE",
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = "all"
    )]
    validate: Option<Validation>,
    /// Physical device by index or name substring.
    #[arg(long)]
    device: Option<String>,
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let mut scene = match &args.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::default_scene(),
    };
    scene.set_output_size(args.width, args.height)?;
    if args.frames == 0 {
        bail!("--frames: must be at least 1");
    }
    let run = app::render(
        &scene,
        &RenderSettings {
            validate: args.validate.unwrap_or_default(),
            device: args.device.clone(),
            warmup: 0,
            frames: args.frames,
            keep_hdr: args.hdr.is_some(),
        },
    )
    .context("render failed")?;
    eprintln!(
        "device: {} ({} {}), Vulkan {}",
        run.device.name, run.device.driver_name, run.device.driver_info, run.device.api_version
    );
    validation::check(&run.validation).context("no output written")?;
    output::write_png(&args.out, &run.output, &run.png_metadata())?;
    eprintln!("wrote {}", args.out.display());
    if let (Some(path), Some(hdr)) = (&args.hdr, &run.hdr) {
        output::write_exr(path, hdr)?;
        eprintln!("wrote {}", path.display());
    }
    if args.frames > 1 {
        print_timings(&run);
    }
    Ok(())
}

/// Per-pass GPU time and CPU frame time over the frames: median and spread.
fn print_timings(run: &app::RenderRun) {
    println!(
        "{:<12} {:>10} {:>10} {:>10} {:>10}",
        "pass", "median ms", "min ms", "p95 ms", "max ms"
    );
    let row = |name: &str, samples: Vec<f64>| {
        if let Some(s) = Summary::of(&samples) {
            println!(
                "{name:<12} {:>10.3} {:>10.3} {:>10.3} {:>10.3}",
                s.median, s.min, s.p95, s.max
            );
        }
    };
    for (i, name) in run.passes.iter().enumerate() {
        row(
            name,
            run.frames
                .iter()
                .filter_map(|f| f.pass_ms.get(i).copied())
                .collect(),
        );
    }
    row(
        "gpu total",
        run.frames.iter().map(|f| f.pass_ms.iter().sum()).collect(),
    );
    row("cpu frame", run.frames.iter().map(|f| f.cpu_ms).collect());
    println!("note: {}", aerial::render::SUBPASS_TIMING_NOTE);
}
