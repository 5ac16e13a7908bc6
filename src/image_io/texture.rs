//! A texture file's format and size, read from its header without
//! decoding it: what the scene checks a model's maps with, and what the
//! memory estimates are made of.

use super::{FileFormat, ImageError};
use std::path::Path;

/// A texture file's format and size, read from its header only.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureInfo {
    pub width: u32,
    pub height: u32,
    /// Bytes per RGBA texel once decoded: 8 for 16-bit files (normal maps
    /// keep 16 bits), otherwise 4.
    pub texel_bytes: u64,
}

/// Reads a texture's header: the format from the content (not the file
/// name) and the size, without decoding the pixels.
pub fn inspect_texture(path: &Path) -> Result<TextureInfo, ImageError> {
    let err = |reason: String| ImageError::Texture {
        path: path.to_path_buf(),
        reason,
    };
    let format = super::sniff_file(path).map_err(|e| err(e.to_string()))?;
    let kind = match format {
        FileFormat::Png => "PNG",
        FileFormat::Jpeg => "JPEG",
        FileFormat::OpenExr => {
            return Err(err(
                "is an OpenEXR file; textures must be 8- or 16-bit PNG or JPEG".into(),
            ))
        }
        FileFormat::Unknown => {
            return Err(err(
                "is neither a PNG nor a JPEG file (unrecognised content; the file name \
                 is not used to decide the format)"
                    .into(),
            ))
        }
    };
    // The header alone: the size is known before anything is decoded.
    let decoder = super::open(path)
        .map_err(err)?
        .into_decoder()
        .map_err(|e| err(format!("not a readable {kind} file: {e}")))?;
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    let sixteen_bit = image::ImageDecoder::color_type(&decoder).bytes_per_pixel()
        > image::ImageDecoder::color_type(&decoder).channel_count();
    Ok(TextureInfo {
        width,
        height,
        texel_bytes: if sixteen_bit { 8 } else { 4 },
    })
}
