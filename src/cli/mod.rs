//! The subcommands of the `aerial` binary, one module each.

pub mod bench;
pub mod compare;
pub mod mesh;
pub mod normalmap;
pub mod render;
pub mod sweep;
pub mod tonemap;
