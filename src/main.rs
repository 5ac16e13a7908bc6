//! The `aerial` command line: a thin layer over the library.

mod cli;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "aerial",
    version,
    about = "An explicit, headless Vulkan renderer",
    after_help = "Exit status: 0 on success, 1 when `compare` or the `bench` gate finds a threshold exceeded, 2 on any error, 130 when interrupted."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene, or a model in a scene built around it (the embedded
    /// default scene without SCENE).
    Render(cli::render::RenderArgs),
    /// Tone-map an existing HDR image (OpenEXR) with the GPU tone-map subpass.
    Tonemap(cli::tonemap::ToneMapArgs),
    /// Compare an image with a reference (FLIP, PSNR or RMSE) and fail past
    /// a threshold: for screenshot regression checks in CI.
    Compare(cli::compare::CompareArgs),
    /// Render every combination of knob settings and plot error against
    /// GPU time (sweep.csv, sweep.json, sweep.svg).
    Sweep(cli::sweep::SweepArgs),
    /// Time scenes and the empty pass; write JSON; gate against a baseline.
    Bench(cli::bench::BenchArgs),
    /// Report what the OBJ loader makes of a model: counts, welded
    /// boundaries, degenerate and mirrored triangles, frame errors, timings.
    Mesh(cli::mesh::MeshArgs),
    /// Convert a height map (PNG) into a tangent-space normal map.
    Normalmap(cli::normalmap::NormalMapArgs),
    /// Write the scene `render MODEL` and `view MODEL` build around a model
    /// file (camera, lights, materials) as a scene file to edit.
    Scene(cli::scene::SceneArgs),
    /// Show a scene (or a model) in a window: fly with WASD and the mouse, cycle knobs,
    /// watch per-pass GPU times, take screenshots (F12).
    View(cli::view::ViewArgs),
}

/// Exit status for errors (bad input, failed render). 2 rather than 1 so
/// that `compare` can use 1 for "compared, and the images differ too much",
/// as `cmp` and `diff` do.
const EXIT_ERROR: u8 = 2;

fn main() -> std::process::ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    // SIGINT, SIGTERM and the other stop signals only ask the work to stop
    // at its next safe point; it then unwinds like an error, removing its
    // temporary files (see `aerial::interrupt`). If the handler cannot be
    // installed, the default (exit without cleanup) remains. When it must
    // end the process without unwinding, the temporary output files and
    // folders still open are removed first.
    aerial::interrupt::on_forced_exit(aerial::safe_files::remove_pending);
    #[cfg(target_os = "linux")]
    if let Err(e) = aerial::interrupt::install() {
        eprintln!(
            "warning: cannot handle interrupts ({e}); an interrupt may leave temporary files"
        );
    }
    let result = run(Cli::parse());
    // Whatever the work returned, an interrupt ends the run with 130 (the
    // shell's convention for SIGINT): stopped at a safe point, the error is
    // the interrupt itself, not worth showing.
    if aerial::interrupt::requested() {
        // Outputs completed before the interrupt stay (each is whole); say
        // which, so a script's earlier screenshots are not taken for lost.
        let written: Vec<String> = aerial::safe_files::written()
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        match (result.is_ok(), written.is_empty()) {
            (true, true) => eprintln!("interrupted after the work was done"),
            (false, true) => eprintln!("interrupted; no output written"),
            (_, false) => eprintln!("interrupted; written before it: {}", written.join(", ")),
        }
        return std::process::ExitCode::from(aerial::interrupt::EXIT_INTERRUPTED);
    }
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::from(EXIT_ERROR)
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<std::process::ExitCode> {
    match cli.command {
        Command::Render(args) => cli::render::run(args).map(|()| std::process::ExitCode::SUCCESS),
        Command::Tonemap(args) => cli::tonemap::run(args).map(|()| std::process::ExitCode::SUCCESS),
        Command::Compare(args) => cli::compare::run(args),
        Command::Sweep(args) => cli::sweep::run(args).map(|()| std::process::ExitCode::SUCCESS),
        Command::Bench(args) => cli::bench::run(args),
        Command::Mesh(args) => cli::mesh::run(args).map(|()| std::process::ExitCode::SUCCESS),
        Command::Normalmap(args) => {
            cli::normalmap::run(args).map(|()| std::process::ExitCode::SUCCESS)
        }
        Command::Scene(args) => cli::scene::run(args).map(|()| std::process::ExitCode::SUCCESS),
        Command::View(args) => cli::view::run(args).map(|()| std::process::ExitCode::SUCCESS),
    }
}
