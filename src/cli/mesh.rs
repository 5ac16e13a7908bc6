//! `aerial mesh`: print what the OBJ loader makes of a model file (the
//! same loading, smoothing and tangent frames a scene's `obj` shape gets),
//! optionally as JSON.

use aerial::mesh::inspect::inspect;
use aerial::mesh::obj::{
    ModelOptions, TangentMethod, DEFAULT_CREASE_DEGREES, DEFAULT_WELD_TOLERANCE,
};
use aerial::mesh::smoothing::Smoothing;
use anyhow::{bail, Context as _};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct MeshArgs {
    /// The OBJ file.
    model: PathBuf,
    /// Smoothing mode (default: file when every corner has a normal,
    /// otherwise model).
    #[arg(long, value_enum)]
    smoothing: Option<Smoothing>,
    /// Crease angle in degrees: faces meeting at a sharper angle do not
    /// share a normal.
    #[arg(long, default_value_t = DEFAULT_CREASE_DEGREES)]
    crease: f32,
    /// Weld tolerance relative to the bounding-box diagonal.
    #[arg(long, default_value_t = DEFAULT_WELD_TOLERANCE)]
    weld: f32,
    /// Tangent frames: aerial's own, or MikkTSpace.
    #[arg(long, value_enum, default_value = "aerial")]
    tangents: TangentMethod,
    /// Also write the report as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    strict: super::StrictArgs,
}

pub fn run(args: MeshArgs) -> anyhow::Result<()> {
    if !(args.crease.is_finite() && (0.0..=180.0).contains(&args.crease)) {
        bail!(
            "--crease: must be between 0 and 180 degrees, got {}",
            args.crease
        );
    }
    // The same bound the scene file applies to weld_tolerance.
    if !(args.weld.is_finite() && (0.0..=1e-3).contains(&args.weld)) {
        bail!("--weld: must be between 0 and 1e-3, got {}", args.weld);
    }
    // The model, its MTL libraries and the textures they name are inputs.
    aerial::safe_files::protect_inputs_as_read();
    aerial::safe_files::protect_inputs([&args.model]);
    if let Some(json) = &args.json {
        aerial::safe_files::check_destination(json).context("--json")?;
    }
    let report = inspect(
        &args.model,
        &ModelOptions {
            smoothing: args.smoothing,
            crease_degrees: args.crease,
            weld_tolerance: args.weld,
            tangents: args.tangents,
        },
    )?;
    if let Some(w) = report.asset_warnings.first().filter(|_| args.strict.strict) {
        return Err(super::strict_error(&w.problem, &w.fallback));
    }
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    // Its MTL libraries and textures are known once it is read.
    aerial::safe_files::protect_inputs(&report.files);
    if let Some(json) = &args.json {
        aerial::safe_files::check_destination(json).context("--json")?;
    }
    println!("model                      {}", report.file);
    println!("smoothing                  {}", report.smoothing);
    println!("objects                    {}", report.objects);
    println!("triangles                  {}", report.triangles);
    println!("corners (3 per triangle)   {}", report.corners);
    println!("vertices after splitting   {}", report.vertices);
    println!(
        "welded boundary points     {}",
        report.welded_boundary_points
    );
    println!(
        "zero-area triangles        {} (collapsed to a line or a point; left out)",
        report.collapsed_triangles
    );
    println!(
        "zero-UV-area triangles     {} (their UVs give no tangent; frames from the normal)",
        report.zero_uv_area_triangles
    );
    println!(
        "triangles without UVs      {} (frames from the normal; nothing to fix)",
        report.triangles_without_uvs
    );
    println!("mirrored triangles         {}", report.mirrored_triangles);
    println!(
        "non-finite attributes      {}",
        report.non_finite_attributes
    );
    println!(
        "max orthonormality error   {:.3e}",
        report.max_orthonormality_error
    );
    println!(
        "seconds: load {:.4}, smoothing {:.4}, tangents {:.4}",
        report.seconds.load, report.seconds.smoothing, report.seconds.tangents
    );
    println!(
        "cpu seconds: load {:.4}, smoothing {:.4}, tangents {:.4}",
        report.cpu_seconds.load, report.cpu_seconds.smoothing, report.cpu_seconds.tangents
    );
    if let Some(json) = &args.json {
        let text = serde_json::to_string_pretty(&report).context("encoding the report")?;
        aerial::safe_files::write_bytes(json, text.as_bytes())?;
        eprintln!("wrote {}", json.display());
    }
    Ok(())
}
