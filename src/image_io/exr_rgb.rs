//! OpenEXR images as linear RGB, for comparing images: the size of each
//! layer from the header alone, so a caller can refuse a huge claim before
//! anything is decoded, and the R, G and B channels of the first valid
//! layer. Any flat RGB(A) file reads, not only the renderer's own.

use std::io::Cursor;
use std::path::Path;

/// The OpenEXR decoder's error, as the callers of this module see it.
pub use exr::error::Error as ExrError;

/// An OpenEXR image's R, G and B channels: linear, row-major from the top,
/// interleaved (three values per pixel).
#[derive(Clone, Debug)]
pub struct ExrRgb {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

/// The size (width, height) of each layer of an OpenEXR file, from its
/// header alone: `bytes` is the whole file.
pub fn exr_layer_sizes_in(bytes: &[u8]) -> Result<Vec<(usize, usize)>, ExrError> {
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)?;
    Ok(layer_sizes(&meta))
}

/// [`exr_layer_sizes_in`] of the file at `path`, reading only its header.
pub fn exr_layer_sizes(path: &Path) -> Result<Vec<(usize, usize)>, ExrError> {
    let meta = exr::meta::MetaData::read_from_file(path, false)?;
    Ok(layer_sizes(&meta))
}

fn layer_sizes(meta: &exr::meta::MetaData) -> Vec<(usize, usize)> {
    meta.headers
        .iter()
        .map(|h| (h.layer_size.0, h.layer_size.1))
        .collect()
}

/// Decodes the R, G and B channels of the first valid flat layer (at its
/// largest resolution) of the OpenEXR file whose bytes are `bytes`. The
/// decoder allocates whatever the header asks for: check
/// [`exr_layer_sizes_in`] first.
pub fn read_exr_rgb(bytes: &[u8]) -> Result<ExrRgb, ExrError> {
    // Builder steps of the exr reader are trait methods.
    use exr::prelude::{ReadChannels, ReadLayers};

    struct Rgb {
        width: usize,
        data: Vec<f32>,
    }
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| Rgb {
                width: size.0,
                data: vec![0.0; size.0 * size.1 * 3],
            },
            |px: &mut Rgb, pos, (r, g, b): (f32, f32, f32)| {
                let i = (pos.1 * px.width + pos.0) * 3;
                if let Some(dst) = px.data.get_mut(i..i + 3) {
                    dst.copy_from_slice(&[r, g, b]);
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))?;
    let size = image.layer_data.size;
    Ok(ExrRgb {
        width: size.0,
        height: size.1,
        data: image.layer_data.channel_data.pixels.data,
    })
}
