//! `aerial`: an explicit, headless Vulkan renderer.
//!
//! Data flows one way: a [`scene::Scene`] (TOML) is planned into the passes
//! and resources it needs ([`render::FramePlan`]), built on the GPU through
//! the thin RAII layer in [`vk`], recorded once into a command buffer,
//! submitted per frame, and read back as images and per-pass timings.

pub mod app;
pub mod bench;
pub mod budget;
pub mod files;
pub mod mesh;
pub mod render;
pub mod report;
pub mod scene;
pub mod vk;

/// SPIR-V of every shader in `glsl/`, compiled by `build.rs`.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
