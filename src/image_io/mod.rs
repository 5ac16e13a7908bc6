//! Image files in one place: recognising a file's format from its content
//! (never from its name, so a PNG named `.jpg` or a file without an
//! extension reads as what it is), inspecting and decoding textures, and
//! reading and writing the rendered PNG and OpenEXR images (written through
//! [`crate::safe_files`]: a temporary name, then a rename). No other module
//! reads or writes OpenEXR: `compare` takes its linear images from
//! [`read_exr_rgb`].

mod exr_rgb;
mod files;
mod texture;

pub use exr_rgb::{exr_layer_sizes, exr_layer_sizes_in, read_exr_rgb, ExrError, ExrRgb};
pub use files::{
    exr_file, exr_size, exr_size_bound, image_size, png_file, png_size_bound, read_exr,
    read_png_text, tonemap_memory, write_exr, write_png, READ_EXR_BYTES_PER_PIXEL,
    TONEMAP_BUFFER_BYTES_PER_PIXEL,
};
pub use texture::{inspect_texture, TextureInfo};

use image::{DynamicImage, ImageReader};
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// The longest side of an image this crate renders or reads back (the
/// scene's `[output]` size is checked against it too): a header claiming
/// more is refused before anything is allocated for it.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// An image in memory, row-major, top row first, RGBA: what the renderer
/// reads back and what the image files hold.
#[derive(Clone, Debug)]
pub struct Pixels<T> {
    pub width: u32,
    pub height: u32,
    pub data: Vec<T>,
}

/// Why an image file could not be read or written; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error(transparent)]
    File(#[from] crate::safe_files::FileError),
    #[error(transparent)]
    Budget(#[from] crate::budget::BudgetError),
    #[error("cannot write {path}: {reason}")]
    Output { path: PathBuf, reason: String },
    #[error("cannot read {path}: {reason}")]
    Input { path: PathBuf, reason: String },
    #[error("texture {path}: {reason}")]
    Texture { path: PathBuf, reason: String },
}

/// Opens `path` with its format guessed from its first bytes. The error is
/// the reason alone; callers name the file in their own error type. The
/// file is an input from then on (see [`crate::safe_files::note_inputs`]).
pub fn open(path: &Path) -> Result<ImageReader<BufReader<std::fs::File>>, String> {
    crate::safe_files::note_inputs([path]);
    ImageReader::open(path)
        .map_err(|e| e.to_string())?
        .with_guessed_format()
        .map_err(|e| e.to_string())
}

/// Decodes `path` whole (format from its content).
pub fn decode(path: &Path) -> Result<DynamicImage, String> {
    open(path)?.decode().map_err(|e| e.to_string())
}

/// What an image file is, from its first bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileFormat {
    Png,
    Jpeg,
    OpenExr,
    Unknown,
}

/// The format of the file at `path`, from its first bytes (an input from
/// then on, as for [`open`]).
pub fn sniff_file(path: &Path) -> std::io::Result<FileFormat> {
    use std::io::Read as _;
    crate::safe_files::note_inputs([path]);
    let mut head = [0u8; 8];
    let n = std::fs::File::open(path)?.read(&mut head)?;
    Ok(sniff(&head[..n]))
}

/// The format of `bytes`, a file's start, from its signature.
pub fn sniff(bytes: &[u8]) -> FileFormat {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        FileFormat::Png
    } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        FileFormat::Jpeg
    } else if bytes.starts_with(&[0x76, 0x2F, 0x31, 0x01]) {
        FileFormat::OpenExr
    } else {
        FileFormat::Unknown
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_are_sniffed_from_content() {
        assert_eq!(sniff(b"\x89PNG\r\n\x1a\n...."), FileFormat::Png);
        assert_eq!(sniff(&[0xFF, 0xD8, 0xFF, 0xE0]), FileFormat::Jpeg);
        assert_eq!(sniff(&[0x76, 0x2F, 0x31, 0x01]), FileFormat::OpenExr);
        assert_eq!(sniff(b"GIF89a"), FileFormat::Unknown);
        assert_eq!(sniff(b""), FileFormat::Unknown);
    }
}
