//! `aerial render`: render one scene to PNG (and optionally EXR).

use aerial::bench::{CPU_FRAME, GPU_TOTAL};
use aerial::image_io;
use aerial::render_run::{self, RenderSettings};
use aerial::report::stats::{summarise_passes, Summary};
use aerial::safe_files;
use aerial::vk::validation;
use anyhow::{bail, Context as _};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file (TOML), or a model (OBJ) to render in a scene built
    /// around it; omit for the embedded default scene.
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
    /// Draw one surface attribute instead of the lit image: the HDR output
    /// (--hdr) holds the attribute (world space, signed for vectors,
    /// background 0), the PNG shows 0.5 + 0.5 v.
    #[arg(long, value_enum)]
    debug_view: Option<aerial::scene::DebugView>,
    /// Set a knob on the scene, NAME=VALUE (repeatable; applied after
    /// --width/--height), e.g. depth_prepass=on. An unknown NAME lists the
    /// knobs.
    #[arg(long = "knob", value_name = "NAME=VALUE")]
    knobs: Vec<String>,
    #[command(flatten)]
    model: super::ModelArgs,
    #[command(flatten)]
    strict: super::StrictArgs,
    #[command(flatten)]
    gpu: super::GpuArgs,
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    // Every file the scene reads is an input, found while it loads.
    safe_files::protect_inputs_as_read();
    let mut scene = super::load_scene(
        args.scene.as_deref(),
        &args.model,
        args.width,
        args.height,
        &args.strict,
    )?;
    if args.debug_view.is_some() {
        scene.output.debug_view = args.debug_view;
    }
    for k in &args.knobs {
        let (name, value) = k
            .split_once('=')
            .with_context(|| format!("--knob '{k}': expected NAME=VALUE"))?;
        aerial::scene::Knob::find(name.trim())?.set(&mut scene, value.trim())?;
    }
    if args.frames == 0 {
        bail!("--frames: must be at least 1");
    }
    // Outputs are checked before the render, so a bad path fails at once;
    // none may be a file the scene was read from.
    safe_files::protect_inputs(&scene.files);
    safe_files::check_output(&args.out, safe_files::Format::Png).context("--out")?;
    if let Some(hdr) = &args.hdr {
        if safe_files::same_file(hdr, &args.out) {
            bail!("--hdr and --out name the same file: {}", hdr.display());
        }
        safe_files::check_output(hdr, safe_files::Format::Exr).context("--hdr")?;
    }
    // Room for both on their file systems, before the work.
    let (width, height) = (scene.output.width, scene.output.height);
    let mut sizes = vec![(args.out.as_path(), image_io::png_size_bound(width, height))];
    if let Some(hdr) = &args.hdr {
        sizes.push((hdr.as_path(), image_io::exr_size_bound(width, height)));
    }
    safe_files::check_room(&sizes).map_err(|e| {
        let flag = match &e {
            safe_files::FileError::Refused { path, .. } if Some(path) == args.hdr.as_ref() => {
                "--hdr"
            }
            _ => "--out",
        };
        anyhow::Error::new(e).context(flag)
    })?;
    if let Some(warning) = scene.tessellation_ceiling() {
        eprintln!("warning: {warning}");
    }
    let scene_name = match &args.scene {
        Some(path) => path.display().to_string(),
        None => "the default scene".to_string(),
    };
    let run = render_run::render(
        &scene,
        &RenderSettings {
            validate: args.gpu.validate.unwrap_or_default(),
            device: args.gpu.device.clone(),
            pipeline_cache: args.gpu.pipeline_cache(),
            warmup: 0,
            frames: args.frames,
            keep_hdr: args.hdr.is_some(),
            empty_pass_between_frames: false,
            ..Default::default()
        },
    )
    .with_context(|| format!("rendering {scene_name} failed"))?;
    eprintln!(
        "device: {} ({} {}), Vulkan {}",
        run.device.name, run.device.driver_name, run.device.driver_info, run.device.api_version
    );
    validation::check(&run.validation).context("no output written")?;
    // The grids tessellation = "auto" chose, which nothing else shows;
    // after the render, whose memory check has passed for those meshes
    // (the count builds each distinct mesh again).
    if let Some(summary) = scene.tessellation_summary() {
        eprintln!("{summary}");
    }
    // Both files are encoded before either is renamed into place, so a
    // failure leaves neither.
    let mut outputs = vec![image_io::png_file(
        &args.out,
        &run.output,
        &run.png_metadata(),
    )?];
    if let (Some(path), Some(hdr)) = (&args.hdr, &run.hdr) {
        outputs.push(image_io::exr_file(path, hdr)?);
    }
    for path in safe_files::commit_all(outputs)? {
        eprintln!("wrote {}", path.display());
    }
    if args.frames > 1 {
        print_timings(&run);
    }
    Ok(())
}

/// Per-pass GPU time and CPU frame time over the frames: median and spread.
fn print_timings(run: &render_run::RenderRun) {
    println!(
        "{:<12} {:>10} {:>10} {:>10} {:>10}",
        "pass", "median ms", "min ms", "p95 ms", "max ms"
    );
    let row = |name: &str, s: &Summary| {
        println!(
            "{name:<12} {:>10.3} {:>10.3} {:>10.3} {:>10.3}",
            s.median, s.min, s.p95, s.max
        );
    };
    match summarise_passes(&run.passes, run.frames.iter().map(|f| f.pass_ms.as_slice())) {
        Ok(Some(gpu)) => {
            for (name, s) in &gpu.passes {
                row(name, s);
            }
            row(GPU_TOTAL, &gpu.total);
        }
        Ok(None) => println!("(no GPU timestamps on this device: CPU frame time only)"),
        Err(e) => eprintln!("warning: no GPU times shown: {e}"),
    }
    let cpu: Vec<f64> = run.frames.iter().map(|f| f.cpu_ms).collect();
    if let Some(s) = Summary::of(&cpu) {
        row(CPU_FRAME, &s);
    }
    for (name, value) in &run.setup {
        println!("{name:<12} {value:>10.3}");
    }
    println!("note: {}", aerial::render::subpass_timing_note());
}
