//! The subcommands of the `aerial` binary, one module each.

pub mod bench;
pub mod compare;
pub mod mesh;
pub mod normalmap;
pub mod render;
pub mod sweep;
pub mod tonemap;
pub mod view;

use aerial::vk::validation::Validation;

/// The options of every command that renders: validation and device.
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
}
