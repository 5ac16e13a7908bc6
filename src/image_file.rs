//! Reading texture-like image files (base colour, normal and height maps):
//! the format is recognised from the content, never from the file name, so
//! a PNG named `.jpg` or a file without an extension reads as what it is.

use image::{DynamicImage, ImageReader};
use std::io::BufReader;
use std::path::Path;

/// Opens `path` with its format guessed from its first bytes. The error is
/// the reason alone; callers name the file in their own error type.
pub fn open(path: &Path) -> Result<ImageReader<BufReader<std::fs::File>>, String> {
    ImageReader::open(path)
        .map_err(|e| e.to_string())?
        .with_guessed_format()
        .map_err(|e| e.to_string())
}

/// Decodes `path` whole (format from its content).
pub fn decode(path: &Path) -> Result<DynamicImage, String> {
    open(path)?.decode().map_err(|e| e.to_string())
}
