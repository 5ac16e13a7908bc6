//! The `aerial` command line: a thin layer over the library.

use aerial::app::{self, RenderSettings};
use aerial::render::output;
use aerial::scene::Scene;
use anyhow::{bail, Context as _};
use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "aerial",
    version,
    about = "An explicit, headless Vulkan renderer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (the embedded default scene without SCENE).
    Render(RenderArgs),
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file (TOML); omit for the embedded default scene.
    scene: Option<PathBuf>,
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
    /// Enable the Khronos validation layer; any message fails the run.
    #[arg(long)]
    validate: bool,
    /// Physical device by index or name substring.
    #[arg(long)]
    device: Option<String>,
}

fn main() -> std::process::ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Render(args) => render(args),
    }
}

fn render(args: RenderArgs) -> anyhow::Result<()> {
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
            validate: args.validate,
            device: args.device.clone(),
            frames: args.frames,
            keep_hdr: args.hdr.is_some(),
        },
    )
    .context("render failed")?;
    eprintln!(
        "device: {} ({} {}), Vulkan {}",
        run.device.name, run.device.driver_name, run.device.driver_info, run.device.api_version
    );
    if !run.validation.is_empty() {
        for m in &run.validation {
            eprintln!("{m}");
        }
        bail!(
            "{} validation message(s); no output written",
            run.validation.len()
        );
    }
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

fn print_timings(run: &app::RenderRun) {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let med = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        (med, v[0], v[n - 1])
    };
    println!(
        "{:<12} {:>10} {:>10} {:>10}",
        "pass", "median ms", "min ms", "max ms"
    );
    for (i, name) in run.passes.iter().enumerate() {
        let samples: Vec<f64> = run
            .frames
            .iter()
            .filter_map(|f| f.pass_ms.get(i).copied())
            .collect();
        if samples.is_empty() {
            continue;
        }
        let (med, lo, hi) = median(samples);
        println!("{name:<12} {med:>10.3} {lo:>10.3} {hi:>10.3}");
    }
    let (med, lo, hi) = median(run.frames.iter().map(|f| f.cpu_ms).collect());
    println!("{:<12} {med:>10.3} {lo:>10.3} {hi:>10.3}", "cpu frame");
}
