//! The `aerial` command line: a thin layer over the library.

mod cli;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "aerial",
    version,
    about = "An explicit, headless Vulkan renderer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (the embedded default scene without SCENE).
    Render(cli::render::RenderArgs),
    /// Time scenes and the empty pass; write JSON; gate against a baseline.
    Bench(cli::bench::BenchArgs),
}

fn main() -> std::process::ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Render(args) => cli::render::run(args),
        Command::Bench(args) => cli::bench::run(args),
    }
}
