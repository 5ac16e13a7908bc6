//! Checks made before a run allocates anything large, so that every input
//! the renderer cannot handle is refused with a message naming it, instead
//! of crashing, aborting on a failed allocation, tripping the validation
//! layer or silently drawing a wrong image:
//!
//! - [`scene_memory`] / [`image_memory`]: the estimated peak memory of the
//!   run (geometry, attachments, readback, textures) against the
//!   [`MemoryBudget`];
//! - [`scene_on_device`]: textures (format detected from the content, size
//!   within the device's limits). Meshes are checked where they are built,
//!   once (`SceneGeometry::new`), and the lights each object's uniform
//!   block must hold where the blocks are laid out (`scene_resources`).

use super::passes::aerial_volume;
use super::plan::{attachment, FrameGraph, PassIo};
use super::RenderError;
use crate::budget::{Bytes, MemoryBudget};
use crate::image_io::{inspect_texture, TextureInfo};
use crate::scene::Scene;
use crate::vk::{bytes_per_texel, Context};
use std::path::Path;

/// The largest decoded texture (RGBA, 8 bits per channel) the PNG decoder
/// accepts: the `image` crate's default allocation limit.
pub const MAX_TEXTURE_BYTES: u64 = 512 << 20;

/// Bytes per vertex and per index as uploaded (see `crate::mesh::Vertex`).
const VERTEX_BYTES: u64 = std::mem::size_of::<crate::mesh::Vertex>() as u64;
const INDEX_BYTES: u64 = 4;
/// The f64 copy of each position kept while tessellating one object.
const EXACT_POSITION_BYTES: u64 = 24;

/// Working memory of turning a `w`×`h` height map into a normal map
/// (`crate::mesh::height`): 16-bit grey, f32 heights, f32 normals and the
/// RGBA8 result.
pub fn height_conversion_bytes(w: u32, h: u32) -> u64 {
    u64::from(w) * u64::from(h) * (2 + 4 + 12 + 4)
}

/// Decoded RGBA bytes of a texture, plus its mip chain (a third more).
fn texture_bytes(info: TextureInfo) -> (u64, u64) {
    let base = info.width as u64 * info.height as u64 * info.texel_bytes;
    (base, base + base / 3)
}

/// [`scene_memory`] against the budget this process runs under
/// (`AERIAL_MEMORY_BUDGET`, or half the machine's limit): called before
/// the device exists, so nothing is allocated for a scene that does not fit.
pub fn scene_fits(scene: &Scene, keep_hdr: bool) -> Result<(), RenderError> {
    let budget = crate::budget::MemoryBudget::from_env().map_err(RenderError::from)?;
    scene_memory(scene, keep_hdr, &budget)
}

/// Bytes per output pixel of the empty pass `bench` and `sweep` time
/// between a scene's frames, built on the same device: its RGBA8
/// attachment and its read-back buffer (without them `bench`'s estimate
/// fell 13 % short of its measured peak at 2048x2048).
pub const EMPTY_PASS_BYTES_PER_PIXEL: u64 = 8;

/// Estimated peak memory of rendering `scene`, with the largest item named
/// when over `budget`.
pub fn scene_memory(
    scene: &Scene,
    keep_hdr: bool,
    budget: &MemoryBudget,
) -> Result<(), RenderError> {
    scene_bytes(scene, keep_hdr, 0, budget).map(|_| ())
}

/// [`scene_memory`]'s estimate in bytes, with `extra_per_pixel` bytes more
/// for each output pixel (e.g. [`EMPTY_PASS_BYTES_PER_PIXEL`]); an error,
/// naming the largest item, when it is over `budget`.
pub fn scene_bytes(
    scene: &Scene,
    keep_hdr: bool,
    extra_per_pixel: u64,
    budget: &MemoryBudget,
) -> Result<u64, RenderError> {
    let (geometry, largest) = geometry_bytes(scene, budget)?;
    let (w, h) = (scene.output.width as u64, scene.output.height as u64);
    // Every attachment the renderer will create (the G-buffer and the
    // atmosphere's surface copy included), from the same graph.
    let graph = FrameGraph::new(scene, keep_hdr);
    let attachments =
        attachment_bytes(w, h, &graph).saturating_add((w * h).saturating_mul(extra_per_pixel));
    let size_what = format!("output size {w}x{h}");
    budget.check(&size_what, attachments)?;
    let total = geometry
        .saturating_add(attachments)
        .saturating_add(map_bytes(scene, budget)?)
        .saturating_add(sky_bytes(scene, &graph, budget)?);
    if total > budget.bytes {
        // Each part fits but the sum does not: name the biggest parts.
        let what = match largest {
            Some((object, n)) if n > attachments => {
                format!("the scene (largest part: {object})")
            }
            _ => format!("the scene (largest part: {size_what})"),
        };
        budget.check(what, total)?;
    }
    Ok(total)
}

/// The objects' geometry, and the largest object (named) with its bytes.
/// Every mesh is held on the CPU, copied into one upload array (which may
/// briefly exist twice while it grows) and into the geometry buffer, so
/// about three copies; plus the f64 positions of the object being
/// tessellated.
fn geometry_bytes(
    scene: &Scene,
    budget: &MemoryBudget,
) -> Result<(u64, Option<(String, u64)>), RenderError> {
    let mut total = 0u64;
    let mut largest_transient = 0u64;
    let mut largest: Option<(String, u64)> = None;
    // The grids as built: an auto object's is chosen from the camera.
    let grids = scene.tessellations();
    for (i, (object, source)) in scene.objects.iter().zip(scene.mesh_sources()).enumerate() {
        // An object drawn from another's mesh (the same shape) adds none.
        if source < i {
            continue;
        }
        let (u, v) = (grids[i].0 as u64, grids[i].1 as u64);
        let mut vertices = (u + 1) * (v + 1);
        let mut geometry = vertices * VERTEX_BYTES + u * v * 6 * INDEX_BYTES;
        // A loaded model's size is known exactly; its tessellation is unused.
        if let crate::scene::Shape::Mesh { mesh } = &object.shape {
            vertices = 0;
            geometry =
                mesh.vertices.len() as u64 * VERTEX_BYTES + mesh.indices.len() as u64 * INDEX_BYTES;
        }
        let need = geometry.saturating_mul(3);
        largest_transient = largest_transient.max(vertices * EXACT_POSITION_BYTES);
        let what = format!(
            "objects[{i}] \"{}\" (tessellation {u}x{v}, {} triangles)",
            object.name,
            2 * u * v
        );
        budget.check(&what, need)?;
        if largest.as_ref().is_none_or(|(_, n)| need > *n) {
            largest = Some((what, need));
        }
        total = total.saturating_add(need);
    }
    Ok((total.saturating_add(largest_transient), largest))
}

/// The materials' maps, each file once: every kind costs the same (see
/// `MapKindInfo::keeps_sixteen_bit`), plus, for a height map, the
/// conversion's working arrays.
fn map_bytes(scene: &Scene, budget: &MemoryBudget) -> Result<u64, RenderError> {
    let mut total = 0u64;
    let mut seen: Vec<&Path> = Vec::new();
    let maps = scene.materials.iter().flat_map(|m| m.maps.iter());
    for (_, source) in maps {
        let Some(path) = source.path() else { continue };
        if seen.contains(&path) {
            continue;
        }
        seen.push(path);
        let info = inspect_texture(path)?;
        let (base, with_mips) = texture_bytes(info);
        if base > MAX_TEXTURE_BYTES {
            return Err(RenderError::Texture {
                path: path.to_path_buf(),
                reason: format!(
                    "{}x{} decodes to {}; textures may decode to at most {} \
                     (e.g. 8192x8192)",
                    info.width,
                    info.height,
                    Bytes(base),
                    Bytes(MAX_TEXTURE_BYTES)
                ),
            });
        }
        // Decoded pixels (twice during conversion to RGBA), staging buffer
        // and the mipmapped image.
        let mut need = 3 * base + with_mips;
        if source.height_scale.is_some() {
            need += height_conversion_bytes(info.width, info.height);
        }
        budget.check(
            format!(
                "texture {} ({}x{})",
                path.display(),
                info.width,
                info.height
            ),
            need,
        )?;
        total = total.saturating_add(need);
    }
    Ok(total)
}

/// The atmosphere's tables and, in frames of `graph` that have it, its
/// aerial-perspective volume.
fn sky_bytes(scene: &Scene, graph: &FrameGraph, budget: &MemoryBudget) -> Result<u64, RenderError> {
    let Some(sky) = &scene.sky else {
        return Ok(0);
    };
    // The optical-depth table: its texels on the CPU, in the staging
    // buffer and in the image.
    let (w, h) = sky.table_size;
    let need = u64::from(w) * u64::from(h) * 16 * 3;
    budget.check(format!("optical-depth table {w}x{h}"), need)?;
    let mut total = need;
    // The sky-view table: RGBA32F panels of w x h.
    if let Some((w, h)) = sky.sky_view {
        let need = u64::from(w) * u64::from(h) * 16 * u64::from(sky.sky_view_panels());
        budget.check(format!("sky-view table {w}x{h}"), need)?;
        total = total.saturating_add(need);
    }
    // The aerial-perspective volume: two RGBA32F panels, in frames
    // that have it.
    if graph.has(aerial_volume::PASS) {
        let (w, h, d) = sky.aerial_volume;
        let need = crate::render::sky_resources::AerialVolume::bytes(sky.aerial_volume);
        budget.check(format!("aerial-perspective volume {w}x{h}x{d}"), need)?;
        total = total.saturating_add(need);
    }
    // The multiple-scattering and sky-irradiance tables, RGBA32F
    // images written on the device.
    if sky.multiple_scattering {
        for (what, (w, h)) in [
            ("multiple-scattering table", sky.ms_table_size),
            ("sky-irradiance table", sky.irradiance_table_size),
        ] {
            let need = u64::from(w) * u64::from(h) * 16;
            budget.check(format!("{what} {w}x{h}"), need)?;
            total = total.saturating_add(need);
        }
    }
    Ok(total)
}

/// The frame's attachments (sized from the graph the renderer builds),
/// the read-back buffers and the CPU copies of the read-back images for a
/// `w` x `h` frame.
fn attachment_bytes(w: u64, h: u64, graph: &FrameGraph) -> u64 {
    let pixels = w * h;
    let texel = |name: &str| {
        graph
            .attachments
            .iter()
            .find(|a| a.name == name)
            .map_or(0, |a| bytes_per_texel(a.format))
    };
    let mut bytes: u64 = graph
        .attachments
        .iter()
        .map(|a| {
            let (aw, ah) = a.size.extent(w as u32, h as u32);
            u64::from(aw) * u64::from(ah) * bytes_per_texel(a.format)
        })
        .sum();
    // The bloom chain beside them: RGBA16F, level 0 a quarter of the
    // frame each way, the levels below it a third more at most.
    if graph.has(super::passes::bloom::PASS) {
        let (lw, lh) = super::passes::bloom::level_size(w as u32, h as u32, 0);
        bytes += u64::from(lw) * u64::from(lh) * 8 * 4 / 3;
    }
    for pass in &graph.passes {
        if let PassIo::Transfer { reads, .. } = &pass.io {
            for name in reads {
                // The read-back buffer, its copy on the CPU (as f32 for
                // HDR), and the encoder's buffer: the PNG's, at most the
                // 8-bit image's size (without it the estimate fell 2 %
                // below the measured peak of a 4096x4096 render), or for
                // HDR the OpenEXR encoder's.
                bytes += if *name == attachment::OUTPUT {
                    pixels * texel(name) * 3
                } else {
                    pixels * (texel(name) + 16 + 16)
                };
            }
        }
    }
    bytes
}

/// Estimated peak memory of tone-mapping a `w` x `h` HDR image that is
/// already in memory (upload buffer, rgba32f attachment, output, readback).
pub fn image_memory(w: u32, h: u32, budget: &MemoryBudget) -> Result<(), RenderError> {
    let (w, h) = (w as u64, h as u64);
    let need = w * h * 16 + attachment_bytes(w, h, &FrameGraph::for_hdr_image(false));
    budget.check(format!("image size {w}x{h}"), need)?;
    Ok(())
}

/// Estimated peak memory of running the empty pass alone at `w` x `h`:
/// its attachment and read-back buffer and the image read back, 12 bytes
/// per pixel, and a third more (measured: 11.6 bytes per pixel above the
/// driver's own memory at 4096x4096).
pub fn empty_pass_memory(w: u32, h: u32, budget: &MemoryBudget) -> Result<(), RenderError> {
    let need = u64::from(w) * u64::from(h) * 16;
    budget.check(format!("output size {w}x{h}"), need)?;
    Ok(())
}

/// Checks `scene` against `ctx`'s limits; see the module documentation.
pub fn scene_on_device(scene: &Scene, ctx: &Context) -> Result<(), RenderError> {
    let max_side = ctx.limits.max_image_dimension2_d;
    // Maps of every kind (decoded by content): only the device's size
    // limit applies here.
    let textures = scene.materials.iter().flat_map(|m| m.maps.files());
    for path in textures {
        let info = inspect_texture(path)?;
        if info.width == 0 || info.height == 0 || info.width.max(info.height) > max_side {
            return Err(RenderError::Texture {
                path: path.to_path_buf(),
                reason: format!(
                    "{}x{} is outside this device's image size limit of 1..={max_side} \
                     pixels per side (maxImageDimension2D)",
                    info.width, info.height
                ),
            });
        }
    }
    // Attachments of their own size (the shadow map's tiles) too.
    let graph = FrameGraph::new(scene, false);
    for a in &graph.attachments {
        let (w, h) = a.size.extent(scene.output.width, scene.output.height);
        if w.max(h) > max_side {
            return Err(RenderError::Frame(format!(
                "the {} attachment would be {w}x{h}, beyond this device's image size limit of \
                 {max_side} pixels per side (maxImageDimension2D); lower output.shadow_map",
                a.name
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preflight_refuses_oversized_scenes_naming_the_object_or_size() {
        let budget = MemoryBudget {
            bytes: 64 << 20,
            from_env: true,
        };
        let mut scene = Scene::default_scene();
        scene.set_output_size(Some(64), Some(64)).unwrap();
        assert!(scene_memory(&scene, true, &budget).is_ok());
        scene.objects[0].tessellation = (4096, 4096);
        let msg = scene_memory(&scene, false, &budget)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("objects[0]") && msg.contains("4096x4096"),
            "{msg}"
        );
        scene.objects[0].tessellation = (8, 8);
        scene.set_output_size(Some(16384), Some(16384)).unwrap();
        let msg = scene_memory(&scene, false, &budget)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("output size 16384x16384"), "{msg}");
        let msg = image_memory(16384, 16384, &budget).unwrap_err().to_string();
        assert!(msg.contains("16384x16384"), "{msg}");
    }
}
