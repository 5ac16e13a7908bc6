//! The integration tests, one binary with a module per area: rendering
//! features, the commands, the scene and model formats, robustness, the
//! benchmarks and the regression references. Each test lives in the module
//! of the subject it checks (texture filters in `texture_filters`, exposure
//! in `tonemap`, toon in `shading`, light culling in `frame_graph`, ...);
//! a new area is a new module with `use crate::common;` and a `mod` line
//! below. Shared helpers live only in `common`.
//!
//! One binary links once, where one per file linked forty times; only
//! `tests/obj_memory.rs` stays a binary of its own, because it installs a
//! counting global allocator that would count every other test's memory.
//!
//! Run one area with `cargo test --test suite AREA::`, e.g.
//! `cargo test --test suite regression:: -- --nocapture`.

mod common;

mod aerial_volume;
mod atmosphere;
mod atmosphere_objects;
mod auto_exposure;
mod bench;
mod bench_metrics;
mod bloom;
mod bounds;
mod claims_validation;
mod cli;
mod cli_compare;
mod cpu_renderer;
mod debug_view;
mod depth_prepass;
mod docs_links;
mod examples;
mod frame_graph;
mod function_length;
mod fuzz;
mod gbuffer_range;
mod height_maps;
mod hostile;
mod hostile_bench;
mod hostile_io;
mod instancing;
mod interrupt;
mod limits;
mod local_defects;
mod memory_peaks;
mod mesh_command;
mod mikktspace;
mod missing_assets;
mod model_corpus;
mod module_layers;
mod multiple_scattering;
mod normal_maps;
mod obj_models;
mod object_sunlight;
mod outputs;
mod pipeline_cache;
mod pixel_oracle;
mod real_models;
mod regression;
mod scene_errors;
mod screen_tessellation;
mod shading;
mod shadows;
mod sweep;
mod sweep_shards;
mod tall_atmosphere;
mod texture_filters;
mod tonemap;
mod two_sided;
mod validation;
mod viewer;
mod world_precision;
