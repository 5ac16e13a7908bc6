//! `aerial normalmap`: convert a height map (PNG, 8- or 16-bit grey) into a
//! tangent-space normal map (RGBA8 PNG) with the convention the renderer
//! reads (`src/mesh/height.rs`).

use aerial::budget::MemoryBudget;
use aerial::image_io;
use aerial::mesh::height::{encode_normal_map, GreenAxis, HeightEdge, HeightFilter, HeightMap};
use aerial::render::{preflight, Pixels};
use aerial::safe_files;
use anyhow::{bail, Context as _};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct NormalMapArgs {
    /// Height map: PNG, grey (colour is reduced to luma), 8 or 16 bits.
    input: PathBuf,
    /// The normal map to write (RGBA8 PNG).
    #[arg(long)]
    out: PathBuf,
    /// How many texel widths the full height range 0..1 spans.
    #[arg(long, default_value_t = 1.0)]
    scale: f32,
    /// Derivative estimate.
    #[arg(long, value_enum, default_value = "central")]
    filter: HeightFilter,
    /// What lies beyond the edges: the image repeated, or its edge texel.
    #[arg(long, value_enum, default_value = "wrap")]
    edge: HeightEdge,
    /// Which way the green channel points: up the image (OpenGL style, as
    /// the renderer reads by default) or down (DirectX style).
    #[arg(long, value_enum, default_value = "up")]
    green: GreenAxis,
}

pub fn run(args: NormalMapArgs) -> anyhow::Result<()> {
    if !(args.scale.is_finite() && args.scale > 0.0) {
        bail!("--scale: must be finite and > 0, got {}", args.scale);
    }
    safe_files::protect_inputs_as_read();
    safe_files::protect_inputs([&args.input]);
    safe_files::check_output(&args.out, safe_files::Format::Png).context("--out")?;
    // The size from the header first: refuse what does not fit the memory
    // budget, or the output's file system, before decoding.
    let info = image_io::inspect_texture(&args.input)?;
    safe_files::check_room(&[(&args.out, image_io::png_size_bound(info.width, info.height))])
        .context("--out")?;
    MemoryBudget::from_env()?.check(
        format!(
            "height map {} ({}x{})",
            args.input.display(),
            info.width,
            info.height
        ),
        preflight::height_conversion_bytes(info.width, info.height)
            + u64::from(info.width) * u64::from(info.height) * info.texel_bytes,
    )?;
    let heights = HeightMap::load(&args.input)?;
    let normals = heights.normals(args.scale, args.filter, args.edge)?;
    let pixels = Pixels {
        width: heights.width,
        height: heights.height,
        data: encode_normal_map(&normals, args.green),
    };
    image_io::write_png(&args.out, &pixels, &[])?;
    eprintln!("wrote {}", args.out.display());
    Ok(())
}
