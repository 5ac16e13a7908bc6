//! The subcommands of the `aerial` binary, one module each.

pub mod bench;
pub mod compare;
pub mod mesh;
pub mod normalmap;
pub mod render;
pub mod scene;
pub mod sweep;
pub mod tonemap;
pub mod view;

use aerial::mesh::smoothing::Smoothing;
use aerial::scene::{is_model_file, ModelSceneOptions, Scene};
use aerial::vk::validation::Validation;
use aerial::vk::PipelineCacheStore;
use std::path::Path;

/// The options of every command that renders: validation, device and
/// pipeline cache.
#[derive(clap::Args)]
pub struct GpuArgs {
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
    pub validate: Option<Validation>,
    /// Physical device by index or name substring.
    #[arg(long)]
    pub device: Option<String>,
    /// Neither read nor write the pipeline cache on disk (kept in
    /// $XDG_CACHE_HOME/aerial or ~/.cache/aerial, or where
    /// AERIAL_PIPELINE_CACHE says; AERIAL_PIPELINE_CACHE=off does the same).
    #[arg(long)]
    pub no_pipeline_cache: bool,
}

impl GpuArgs {
    /// Where the device's pipeline cache is kept between runs.
    pub fn pipeline_cache(&self) -> PipelineCacheStore {
        PipelineCacheStore::for_command_line(self.no_pipeline_cache)
    }
}

/// `--strict`: every asset warning is an error.
#[derive(clap::Args)]
pub struct StrictArgs {
    /// Refuse a model whose MTL library or textures are missing or broken
    /// (exit 2) instead of drawing it with default materials and
    /// placeholder textures and warning.
    #[arg(long)]
    pub strict: bool,
}

impl StrictArgs {
    /// Under `--strict` the first warning of `scene` as an error (saying
    /// that `--strict` made it one); otherwise its warnings printed to
    /// stderr (once each).
    pub fn apply(&self, scene: &Scene) -> anyhow::Result<()> {
        if self.strict {
            if let Some(w) = scene.warnings.first() {
                return Err(strict_error(w.to_error(), &w.warning.fallback));
            }
        } else {
            scene.print_warnings();
        }
        Ok(())
    }
}

/// An asset warning turned into an error by `--strict`: the warning's
/// problem, then that `--strict` made it an error and what the run would
/// have done without it.
pub fn strict_error(problem: impl std::fmt::Display, fallback: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "{problem} (an error because of --strict; without --strict this is a warning and {fallback})"
    )
}

/// The materials of a scene made from a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelMaterial {
    /// The model's MTL materials.
    Mtl,
    /// One plain grey material (the MTL's textures are never opened).
    Grey,
}

/// Options for a scene built around a model file.
#[derive(clap::Args)]
pub struct ModelArgs {
    /// With a model: how shading normals are made (default: the file's
    /// normals when every corner has one, otherwise smoothed over the
    /// model).
    #[arg(long, value_enum)]
    pub smoothing: Option<Smoothing>,
    /// With a model: its MTL materials, or plain grey.
    #[arg(long, value_enum)]
    pub material: Option<ModelMaterial>,
    /// With a model: a ground plane under it.
    #[arg(long)]
    pub ground: bool,
}

impl ModelArgs {
    fn given(&self) -> Option<&'static str> {
        if self.smoothing.is_some() {
            Some("--smoothing")
        } else if self.material.is_some() {
            Some("--material")
        } else if self.ground {
            Some("--ground")
        } else {
            None
        }
    }

    /// The options for a scene around a model, `width` x `height` unless
    /// overridden.
    pub fn options(&self, width: Option<u32>, height: Option<u32>) -> ModelSceneOptions {
        let default = ModelSceneOptions::default();
        ModelSceneOptions {
            width: width.unwrap_or(default.width),
            height: height.unwrap_or(default.height),
            smoothing: self.smoothing,
            grey: self.material == Some(ModelMaterial::Grey),
            ground: self.ground,
        }
    }
}

/// The scene a `render` or `view` argument names: a scene file, a scene
/// built around a model file (by extension or content), or without one
/// the embedded default scene; the output size overridden, asset warnings
/// printed (or, under `--strict`, the first one as the error).
pub fn load_scene(
    path: Option<&Path>,
    model: &ModelArgs,
    width: Option<u32>,
    height: Option<u32>,
    strict: &StrictArgs,
) -> anyhow::Result<Scene> {
    let is_model = path.is_some_and(is_model_file);
    if !is_model {
        if let Some(flag) = model.given() {
            anyhow::bail!("{flag}: only for a model file (OBJ), not a scene file");
        }
    }
    let mut scene = match path {
        Some(path) if is_model => {
            // Validated like the scene file's output size before use.
            let mut check = Scene::default_scene();
            check.set_output_size(width, height)?;
            let scene = Scene::from_model(path, &model.options(width, height))?;
            if scene.objects.iter().any(|o| o.two_sided) {
                eprintln!(
                    "note: {} has open boundary edges: drawing both sides of its faces \
                     (two_sided)",
                    path.display()
                );
            }
            scene
        }
        Some(path) => Scene::load(path)?,
        None => Scene::default_scene(),
    };
    scene.set_output_size(width, height)?;
    strict.apply(&scene)?;
    Ok(scene)
}
