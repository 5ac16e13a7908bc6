//! The subcommands of the `aerial` binary, one module each.

pub mod bench;
pub mod render;
