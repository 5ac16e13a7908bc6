//! `aerial scene`: write the scene `render` and `view` build around a
//! model file, as a scene file to start from and edit.

use aerial::safe_files;
use aerial::scene::model_scene_toml;
use anyhow::Context as _;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct SceneArgs {
    /// The model (OBJ).
    model: PathBuf,
    /// The scene file to write (TOML).
    #[arg(long)]
    out: PathBuf,
    /// Output width of the scene.
    #[arg(long)]
    width: Option<u32>,
    /// Output height of the scene.
    #[arg(long)]
    height: Option<u32>,
    #[command(flatten)]
    model_args: super::ModelArgs,
    #[command(flatten)]
    strict: super::StrictArgs,
}

pub fn run(args: SceneArgs) -> anyhow::Result<()> {
    // The model, and every file read while loading it (its MTL libraries
    // and the textures they name), may not be the scene file written.
    safe_files::protect_inputs_as_read();
    safe_files::protect_inputs([&args.model]);
    safe_files::check_destination(&args.out).context("--out")?;
    let options = args.model_args.options(args.width, args.height);
    let text = model_scene_toml(&args.model, &options)?;
    // Parsed before it is written: the file is a scene that loads, and its
    // warnings are shown (or refused under --strict) now.
    let scene = aerial::scene::Scene::from_toml(
        &text,
        &args.out.display().to_string(),
        args.out
            .parent()
            .unwrap_or_else(|| std::path::Path::new("")),
    )?;
    args.strict.apply(&scene)?;
    // Now every file the scene reads is known: none may be the output.
    safe_files::protect_inputs(&scene.files);
    safe_files::check_destination(&args.out).context("--out")?;
    safe_files::write_bytes(&args.out, text.as_bytes()).context("--out")?;
    eprintln!("wrote {}", args.out.display());
    Ok(())
}
