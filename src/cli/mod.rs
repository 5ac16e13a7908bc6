//! The subcommands of the `aerial` binary, one module each.

pub mod render;
pub mod sweep;
