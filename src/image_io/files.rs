//! The rendered images: the tone-mapped PNG (with its metadata text) and
//! the linear HDR OpenEXR, written and read back.
//!
//! Every file goes through [`crate::safe_files`]: written under a unique
//! temporary name in the destination folder and renamed into place, so a
//! failed run never leaves a half-written image. The `*_file` functions
//! prepare a file without committing it, for runs that write several files
//! and commit them together.

use super::{ImageError, Pixels};
use crate::safe_files::{self, PendingFile};
use std::io::Write as _;
use std::path::Path;

/// Encodes 8-bit sRGB RGBA pixels as PNG, with `metadata` as text chunks
/// (the device and driver that rendered it, so a comparison can tell
/// whether bit-identity is expected), into a temporary file for `path`.
pub fn png_file(
    path: &Path,
    pixels: &Pixels<u8>,
    metadata: &[(&str, String)],
) -> Result<PendingFile, ImageError> {
    let err = |reason: String| ImageError::Output {
        path: path.to_path_buf(),
        reason,
    };
    safe_files::check_output(path, safe_files::Format::Png)?;
    let file = PendingFile::create(path)?;
    let mut out = std::io::BufWriter::new(file.file());
    let mut encoder = png::Encoder::new(&mut out, pixels.width, pixels.height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    for (key, value) in metadata {
        // tEXt is Latin-1 only; a device or driver name outside it (say
        // with a trademark sign) goes into a UTF-8 iTXt chunk instead.
        let added = if value.chars().all(|c| (c as u32) < 0x80) {
            encoder.add_text_chunk(key.to_string(), value.clone())
        } else {
            encoder.add_itxt_chunk(key.to_string(), value.clone())
        };
        added.map_err(|e| err(e.to_string()))?;
    }
    let mut writer = encoder.write_header().map_err(|e| err(e.to_string()))?;
    writer
        .write_image_data(&pixels.data)
        .map_err(|e| err(e.to_string()))?;
    writer.finish().map_err(|e| err(e.to_string()))?;
    out.flush().map_err(|e| err(e.to_string()))?;
    drop(out);
    Ok(file)
}

/// [`png_file`], committed.
pub fn write_png(
    path: &Path,
    pixels: &Pixels<u8>,
    metadata: &[(&str, String)],
) -> Result<(), ImageError> {
    png_file(path, pixels, metadata)?.commit()?;
    Ok(())
}

/// Reads the text chunks (tEXt, zTXt and iTXt, in that order) of a PNG as
/// `(keyword, text)` pairs, e.g. the metadata [`write_png`] stores. Chunks
/// after the image data count too, so the whole file is read; compressed
/// text is inflated with the `png` crate's default size limit, so a
/// malicious chunk cannot exhaust memory.
pub fn read_png_text(path: &Path) -> Result<Vec<(String, String)>, ImageError> {
    let err = |reason: String| ImageError::Input {
        path: path.to_path_buf(),
        reason,
    };
    let file = std::fs::File::open(path).map_err(|e| err(e.to_string()))?;
    crate::safe_files::note_inputs([path]);
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder
        .read_info()
        .map_err(|e| err(format!("not a readable PNG: {e}")))?;
    reader
        .finish()
        .map_err(|e| err(format!("not a readable PNG: {e}")))?;
    let info = reader.info();
    let mut text: Vec<(String, String)> = info
        .uncompressed_latin1_text
        .iter()
        .map(|c| (c.keyword.clone(), c.text.clone()))
        .collect();
    // zTXt and iTXt chunks are two types with the same two calls (no
    // shared trait), so one macro reads both.
    macro_rules! push_decompressed {
        ($chunks:expr, $kind:literal) => {
            for chunk in $chunks {
                let mut chunk = chunk.clone();
                let value = chunk
                    .decompress_text()
                    .and_then(|()| chunk.get_text())
                    .map_err(|e| {
                        err(format!(concat!($kind, " chunk {:?}: {}"), chunk.keyword, e))
                    })?;
                text.push((chunk.keyword, value));
            }
        };
    }
    push_decompressed!(&info.compressed_latin1_text, "zTXt");
    push_decompressed!(&info.utf8_text, "iTXt");
    Ok(text)
}

/// Encodes linear float RGBA pixels as OpenEXR (32-bit float channels)
/// into a temporary file for `path`.
pub fn exr_file(path: &Path, pixels: &Pixels<f32>) -> Result<PendingFile, ImageError> {
    use exr::prelude::*;
    safe_files::check_output(path, safe_files::Format::Exr)?;
    let file = PendingFile::create(path)?;
    let w = pixels.width as usize;
    let channels = SpecificChannels::rgba(|position: Vec2<usize>| {
        let i = (position.y() * w + position.x()) * 4;
        let p = &pixels.data[i..i + 4];
        (p[0], p[1], p[2], p[3])
    });
    let mut out = std::io::BufWriter::new(file.file());
    // Tiles in increasing order: compressed on every core, but written in
    // one order, so that the same pixels always make the same bytes (in
    // the unspecified order they land as their threads finish, and two
    // renders of one scene differ byte for byte).
    let encoding = Encoding {
        line_order: LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    Image::from_encoded_channels((w, pixels.height as usize), encoding, channels)
        .write()
        .to_buffered(&mut out)
        .map_err(|e| ImageError::Output {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
    out.flush().map_err(|e| file.io_error(e))?;
    drop(out);
    Ok(file)
}

/// [`exr_file`], committed.
pub fn write_exr(path: &Path, pixels: &Pixels<f32>) -> Result<(), ImageError> {
    safe_files::commit_all(vec![exr_file(path, pixels)?])?;
    Ok(())
}

/// The size of the OpenEXR image at `path` (its first layer), from the
/// header alone, checked against the largest image the renderer takes:
/// a small file that claims a huge image is refused before anything is
/// allocated for it.
pub fn exr_size(path: &Path) -> Result<(u32, u32), ImageError> {
    let err = |reason: String| ImageError::Input {
        path: path.to_path_buf(),
        reason,
    };
    crate::safe_files::note_inputs([path]);
    let sizes = super::exr_layer_sizes(path)
        .map_err(|e| err(format!("not a readable OpenEXR file: {e}")))?;
    let max = super::MAX_IMAGE_SIDE as usize;
    let mut size = None;
    for (width, height) in sizes {
        if width == 0 || height == 0 || width > max || height > max {
            return Err(err(format!(
                "the image is {width}x{height}; each side must be in 1..={max}"
            )));
        }
        size.get_or_insert((width as u32, height as u32));
    }
    size.ok_or_else(|| err("the file has no image layer".into()))
}

/// The size of the image at `path` from its header, whatever its format
/// (PNG, JPEG or OpenEXR, told by the content). The error is the reason.
pub fn image_size(path: &Path) -> Result<(u32, u32), String> {
    match super::sniff_file(path).map_err(|e| e.to_string())? {
        super::FileFormat::OpenExr => exr_size(path).map_err(|e| e.to_string()),
        _ => super::open(path)?
            .into_dimensions()
            .map_err(|e| e.to_string()),
    }
}

/// An upper bound of the size of a PNG of `width` x `height` RGBA8 pixels
/// as [`png_file`] writes it: the filtered rows stored
/// uncompressed (what the compressor falls back to for noise), the
/// compressor's and the chunks' framing, and room for the header and the
/// metadata text.
pub fn png_size_bound(width: u32, height: u32) -> u64 {
    let raw = u64::from(height) * (1 + 4 * u64::from(width));
    raw + raw / 64 + (16 << 10)
}

/// An upper bound of the size of an OpenEXR of `width` x `height` RGBA
/// 32-bit float pixels as [`exr_file`] writes it: the
/// pixels uncompressed (the lossless compression falls back to that), the
/// chunk offset table and headers.
pub fn exr_size_bound(width: u32, height: u32) -> u64 {
    let raw = u64::from(width) * u64::from(height) * 16;
    raw + raw / 64 + u64::from(height) * 16 + (16 << 10)
}

/// Peak memory of [`read_exr`] per pixel, an upper bound: the RGBA f32
/// pixels (16 bytes), and the decoder's compressed and decompressed
/// blocks in flight. Measured: 16.5 bytes per pixel at 4096x4096.
pub const READ_EXR_BYTES_PER_PIXEL: u64 = 32;

/// Reads an EXR written by [`write_exr`] (or any RGBA EXR) back as linear
/// float RGBA.
///
/// The header is read first and the size checked against the largest
/// image the renderer takes and the memory budget, so a small file that
/// claims a huge image is refused before anything is allocated for it.
pub fn read_exr(path: &Path) -> Result<Pixels<f32>, ImageError> {
    use exr::prelude::*;
    let (w, h) = exr_size(path)?;
    crate::budget::MemoryBudget::from_env()?.check(
        format!("{} ({w}x{h})", path.display()),
        u64::from(w) * u64::from(h) * READ_EXR_BYTES_PER_PIXEL,
    )?;
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| Pixels {
            width: resolution.width() as u32,
            height: resolution.height() as u32,
            data: vec![0f32; resolution.width() * resolution.height() * 4],
        },
        |pixels: &mut Pixels<f32>, position, (r, g, b, a): (f32, f32, f32, f32)| {
            let i = (position.y() * pixels.width as usize + position.x()) * 4;
            pixels.data[i..i + 4].copy_from_slice(&[r, g, b, a]);
        },
    )
    .map_err(|e| ImageError::Input {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    Ok(image.layer_data.channel_data.pixels)
}

/// Peak memory of tone-mapping an OpenEXR image of `width` x `height`
/// pixels into a PNG (`aerial tonemap`), an upper bound over the whole
/// run: every large buffer alive at its peak (see
/// [`TONEMAP_BUFFER_BYTES_PER_PIXEL`]) and an eighth more for the
/// allocators' rounding. The driver's own fixed memory is not counted
/// (the budget leaves room for it).
pub fn tonemap_memory(width: u32, height: u32) -> u64 {
    let buffers = u64::from(width) * u64::from(height) * TONEMAP_BUFFER_BYTES_PER_PIXEL;
    buffers + buffers / 8
}

/// The large buffers of a tone-mapping run per pixel, all alive at its
/// peak (after the frame is read back): the image read (RGBA f32, 16
/// bytes), its upload buffer (16), the rgba32f attachment (16), the
/// 8-bit output attachment (4), the readback buffers of the output (4)
/// and of the HDR attachment (16, the frame plan reads both back), and
/// the two images read back (16 and 4): 92. Measured, the whole process's
/// peak less that of a 1x1 image: 92.0 to 92.3 bytes per pixel from
/// 1023x517 to 4096x4096 (release build, lavapipe).
pub const TONEMAP_BUFFER_BYTES_PER_PIXEL: u64 = 92;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_text_round_trips_and_bad_files_name_the_path() {
        let dir = std::env::temp_dir().join(format!("aerial-output-text-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("meta.png");
        let pixels = Pixels {
            width: 2,
            height: 1,
            data: vec![255u8; 8],
        };
        let meta = [
            ("aerial:device", "llvmpipe".to_string()),
            ("aerial:driver", "Mesa 24 (Vendor™ GPU)".to_string()),
        ];
        write_png(&path, &pixels, &meta).unwrap();
        let text = read_png_text(&path).unwrap();
        let expected: Vec<(String, String)> = meta
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect();
        assert_eq!(text, expected);

        let junk = dir.join("junk.png");
        std::fs::write(&junk, b"not a png").unwrap();
        let msg = read_png_text(&junk).unwrap_err().to_string();
        assert!(
            msg.contains("junk.png") && msg.contains("cannot read"),
            "{msg}"
        );
        let msg = read_png_text(&dir.join("missing.png"))
            .unwrap_err()
            .to_string();
        assert!(msg.contains("missing.png"), "{msg}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The same pixels make the same bytes: the tiles are written in
    /// increasing order (the header says so), not as their threads finish;
    /// and the pixels read back unchanged.
    #[test]
    fn exr_files_of_the_same_pixels_are_the_same_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let (width, height) = (700u32, 300u32);
        let data: Vec<f32> = (0..width * height * 4)
            .map(|i| (i.wrapping_mul(2_654_435_761) % 1000) as f32 * 0.01)
            .collect();
        let pixels = Pixels {
            width,
            height,
            data,
        };
        let files: Vec<Vec<u8>> = (0..4)
            .map(|k| {
                let path = dir.path().join(format!("{k}.exr"));
                write_exr(&path, &pixels).unwrap();
                std::fs::read(&path).unwrap()
            })
            .collect();
        assert!(files.iter().all(|f| *f == files[0]));
        let path = dir.path().join("0.exr");
        let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
        assert!(meta
            .headers
            .iter()
            .all(|h| h.line_order == exr::meta::attribute::LineOrder::Increasing));
        assert_eq!(read_exr(&path).unwrap().data, pixels.data);
    }

    /// Compressed (zTXt) and international (iTXt) chunks written by another
    /// encoder are inflated and read after the plain ones.
    #[test]
    fn compressed_and_international_text_chunks_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("chunks.png");
        let file = std::fs::File::create(&path).unwrap();
        let mut encoder = png::Encoder::new(file, 1, 1);
        encoder.set_color(png::ColorType::Grayscale);
        encoder
            .add_ztxt_chunk("zipped".into(), "z".repeat(300))
            .unwrap();
        encoder
            .add_itxt_chunk("world".into(), "Világ ✓".into())
            .unwrap();
        encoder.add_text_chunk("plain".into(), "p".into()).unwrap();
        encoder
            .write_header()
            .unwrap()
            .write_image_data(&[7])
            .unwrap();
        let text = read_png_text(&path).unwrap();
        let expected = [
            ("plain", "p".to_string()),
            ("zipped", "z".repeat(300)),
            ("world", "Világ ✓".to_string()),
        ]
        .map(|(k, v)| (k.to_string(), v));
        assert_eq!(text, expected);
    }
}
