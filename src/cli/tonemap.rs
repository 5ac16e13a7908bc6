//! `aerial tonemap`: tone-map an existing linear HDR image (OpenEXR) with
//! the renderer's own tone-map subpass, e.g. to try another operator or
//! exposure on a `render --hdr` output without rendering again.

use aerial::budget::MemoryBudget;
use aerial::image_io;
use aerial::render_run::{self, RenderSettings, RunSource};
use aerial::safe_files;
use aerial::scene::{Exposure, ToneMap, ToneMapOperator};
use aerial::vk::validation;
use anyhow::{bail, Context as _};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct ToneMapArgs {
    /// Linear HDR input (OpenEXR, RGBA or RGB).
    input: PathBuf,
    /// Tone-mapped 8-bit sRGB output.
    #[arg(long, default_value = "out.png")]
    out: PathBuf,
    /// Tone-map operator.
    #[arg(long, value_enum, default_value = "reinhard")]
    operator: Operator,
    /// Linear scale applied before the operator.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    #[command(flatten)]
    gpu: super::GpuArgs,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Operator {
    Reinhard,
    Aces,
}

pub fn run(args: ToneMapArgs) -> anyhow::Result<()> {
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("--exposure: must be finite and > 0, got {}", args.exposure);
    }
    safe_files::protect_inputs_as_read();
    safe_files::protect_inputs([&args.input]);
    safe_files::check_output(&args.out, safe_files::Format::Png).context("--out")?;
    // From the header alone: the output's room on its file system, and the
    // whole run's memory (reading, the GPU's copies, the PNG) against the
    // budget, before anything is decoded.
    let (width, height) = image_io::exr_size(&args.input)?;
    safe_files::check_room(&[(&args.out, image_io::png_size_bound(width, height))])
        .context("--out")?;
    MemoryBudget::from_env()?.check(
        format!("tone-mapping {} ({width}x{height})", args.input.display()),
        image_io::tonemap_memory(width, height),
    )?;
    let image = image_io::read_exr(&args.input)?;
    let tone_map = ToneMap {
        operator: match args.operator {
            Operator::Reinhard => ToneMapOperator::Reinhard,
            Operator::Aces => ToneMapOperator::Aces,
        },
        exposure: Exposure::Fixed(args.exposure),
        bloom: None,
    };
    let run = render_run::run(
        RunSource::HdrImage(&image, tone_map),
        &RenderSettings {
            validate: args.gpu.validate.unwrap_or_default(),
            pipeline_cache: args.gpu.pipeline_cache(),
            device: args.gpu.device,
            warmup: 0,
            frames: 1,
            keep_hdr: false,
            empty_pass_between_frames: false,
            ..Default::default()
        },
        &mut || {},
    )
    .context("tone mapping failed")?;
    validation::check(&run.validation).context("no output written")?;
    image_io::write_png(&args.out, &run.output, &run.png_metadata())?;
    eprintln!("wrote {}", args.out.display());
    Ok(())
}
