//! `aerial view`: the scene in a window, with keyboard and mouse
//! navigation, live knobs and per-pass GPU times (see `aerial::viewer`).

use aerial::viewer::{self, Script, ScriptAction, ViewOptions};
use aerial::vk::{validation, PresentMode};
use anyhow::Context as _;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct ViewArgs {
    /// Scene file (TOML), or a model (OBJ) to look at in a scene built
    /// around it; omit for the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Initial window width (default: the scene's output width).
    #[arg(long)]
    width: Option<u32>,
    /// Initial window height (default: the scene's output height).
    #[arg(long)]
    height: Option<u32>,
    /// How frames are queued for the display.
    #[arg(long, value_enum, default_value = "fifo")]
    present_mode: PresentMode,
    /// Replay input from a file: lines `FRAME ACTION [ARG]` with actions
    /// press KEY, release KEY, mouse DX DY, resize W H, screenshot PATH,
    /// quit; frames advance time by a fixed 1/60 s while it runs.
    #[arg(long)]
    script: Option<PathBuf>,
    #[command(flatten)]
    model: super::ModelArgs,
    #[command(flatten)]
    strict: super::StrictArgs,
    #[command(flatten)]
    gpu: super::GpuArgs,
}

pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    // Every file the scene and the script read is an input.
    aerial::safe_files::protect_inputs_as_read();
    let scene = super::load_scene(
        args.scene.as_deref(),
        &args.model,
        args.width,
        args.height,
        &args.strict,
    )?;
    let script = args.script.as_deref().map(Script::load).transpose()?;
    // No screenshot may be a file the run reads.
    aerial::safe_files::protect_inputs(scene.files.iter().chain(&args.script));
    if let Some(script) = &script {
        for (frame, action) in &script.steps {
            if let ScriptAction::Screenshot(path) = action {
                let check = || -> Result<(), aerial::safe_files::FileError> {
                    aerial::safe_files::check_output(path, aerial::safe_files::Format::Png)?;
                    aerial::safe_files::check_destination(&path.with_extension("exr"))?;
                    Ok(())
                };
                check().with_context(|| format!("the script's screenshot at frame {frame}"))?;
            }
        }
    }
    let scene_name = match &args.scene {
        Some(path) => path.display().to_string(),
        None => "the default scene".to_string(),
    };
    let outcome = viewer::run(ViewOptions {
        scene,
        scene_name: scene_name.clone(),
        validate: args.gpu.validate.unwrap_or_default(),
        device: args.gpu.device.clone(),
        pipeline_cache: args.gpu.pipeline_cache(),
        present_mode: args.present_mode,
        script,
    });
    if outcome.frames > 0 {
        println!("{} frames; {}", outcome.frames, outcome.timings);
    }
    // A layer message fails the run even when the viewer itself stopped
    // cleanly; both are shown when both happened.
    let context = format!("viewing {scene_name} failed");
    match (outcome.error, validation::check(&outcome.validation)) {
        (None, Ok(())) => Ok(()),
        (None, Err(v)) => Err(anyhow::Error::new(v)),
        (Some(e), Ok(())) => Err(anyhow::Error::new(e).context(context)),
        (Some(e), Err(v)) => Err(anyhow::Error::new(e).context(format!("{context}; {v}"))),
    }
}
