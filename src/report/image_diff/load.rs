//! Images for comparison: PNG (sRGB) and OpenEXR (linear) files, the
//! format from the content (`crate::image_io::sniff`), sizes checked
//! before decoding and decoder panics turned into errors; in-memory images
//! with the same checks.

use super::*;

pub(super) fn load(path: &Path) -> Result<Loaded, CompareError> {
    let bytes = fs::read(path).map_err(|source| CompareError::Read {
        path: path.to_owned(),
        source,
    })?;
    match crate::image_io::sniff(&bytes) {
        FileFormat::Png => load_png(path, &bytes),
        FileFormat::OpenExr => load_exr(path, &bytes),
        FileFormat::Jpeg | FileFormat::Unknown => Err(CompareError::UnknownFormat {
            path: path.to_owned(),
        }),
    }
}

/// Runs a third-party decoder, turning a panic on malformed input into an
/// error so that one corrupt screenshot fails its check instead of the tool.
fn guard<T>(
    path: &Path,
    format: &'static str,
    f: impl FnOnce() -> Result<T, CompareError>,
) -> Result<T, CompareError> {
    panic::catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|_| {
        Err(CompareError::DecoderPanic {
            path: path.to_owned(),
            format,
        })
    })
}

fn check_size(path: &Path, width: usize, height: usize) -> Result<(u32, u32), CompareError> {
    let bad = || CompareError::BadSize {
        path: path.to_owned(),
        width,
        height,
        max: MAX_PIXELS,
    };
    let pixels = width.checked_mul(height).ok_or_else(bad)?;
    if pixels == 0 || pixels > MAX_PIXELS {
        return Err(bad());
    }
    // MAX_PIXELS keeps both sides (and width * height * 3, which the FLIP
    // binding computes in u32) far below u32::MAX.
    Ok((
        u32::try_from(width).map_err(|_| bad())?,
        u32::try_from(height).map_err(|_| bad())?,
    ))
}

fn load_png(path: &Path, bytes: &[u8]) -> Result<Loaded, CompareError> {
    // The image crate's default limits bound memory use for huge PNGs.
    let img = guard(path, "PNG", || {
        image::load_from_memory_with_format(bytes, ImageFormat::Png).map_err(|source| {
            CompareError::Png {
                path: path.to_owned(),
                source,
            }
        })
    })?;
    let (width, height) = check_size(path, img.width() as usize, img.height() as usize)?;
    Ok(Loaded {
        width,
        height,
        pixels: Samples::Srgb(img),
    })
}

fn load_exr(path: &Path, bytes: &[u8]) -> Result<Loaded, CompareError> {
    let exr_err = |source| CompareError::Exr {
        path: path.to_owned(),
        source,
    };
    // Check the claimed sizes before decoding, because the decoder allocates
    // whatever the header asks for.
    let sizes = guard(path, "OpenEXR", || {
        crate::image_io::exr_layer_sizes_in(bytes).map_err(exr_err)
    })?;
    for (width, height) in sizes {
        check_size(path, width, height)?;
    }
    let image = guard(path, "OpenEXR", || {
        crate::image_io::read_exr_rgb(bytes).map_err(exr_err)
    })?;
    let (width, height) = check_size(path, image.width, image.height)?;
    check_finite(path, &image.data, image.width)?;
    Ok(Loaded {
        width,
        height,
        pixels: Samples::Linear(image.data),
    })
}

/// Rejects NaN and infinite values in interleaved RGB `data` of an image
/// `width` pixels wide, naming the first one.
fn check_finite(path: &Path, data: &[f32], width: usize) -> Result<(), CompareError> {
    let mut bad = data.iter().enumerate().filter(|(_, v)| !v.is_finite());
    if let Some((first, _)) = bad.next() {
        let pixel = first / 3;
        return Err(CompareError::NonFinite {
            path: path.to_owned(),
            count: 1 + bad.count(),
            x: pixel % width.max(1),
            y: pixel / width.max(1),
        });
    }
    Ok(())
}

/// Copies an in-memory RGBA image into the form [`load`] produces, with the
/// same size and value checks as a file gets.
pub(super) fn from_memory(path: &Path, image: ImageRef<'_>) -> Result<Loaded, CompareError> {
    let (width, height, len) = match image {
        ImageRef::Srgb8 {
            width,
            height,
            rgba,
        } => (width, height, rgba.len()),
        ImageRef::Linear {
            width,
            height,
            rgba,
        } => (width, height, rgba.len()),
    };
    let (width, height) = check_size(path, width as usize, height as usize)?;
    // check_size bounds the pixel count, so this cannot overflow.
    let expected = width as usize * height as usize * 4;
    if len != expected {
        return Err(CompareError::BadBuffer {
            path: path.to_owned(),
            len,
            width,
            height,
        });
    }
    let pixels = match image {
        ImageRef::Srgb8 { rgba, .. } => {
            // The length was checked above; the error is only a fallback.
            let img =
                image::RgbaImage::from_raw(width, height, rgba.to_vec()).ok_or_else(|| {
                    CompareError::BadBuffer {
                        path: path.to_owned(),
                        len,
                        width,
                        height,
                    }
                })?;
            Samples::Srgb(DynamicImage::ImageRgba8(img))
        }
        ImageRef::Linear { rgba, .. } => {
            let rgb: Vec<f32> = rgba
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            check_finite(path, &rgb, width as usize)?;
            Samples::Linear(rgb)
        }
    };
    Ok(Loaded {
        width,
        height,
        pixels,
    })
}

/// An image file's width and height from its header alone (PNG or
/// OpenEXR, by content), for sizing memory before decoding.
pub(super) fn header_size(path: &Path) -> Result<(usize, usize), CompareError> {
    let format = crate::image_io::sniff_file(path).map_err(|source| CompareError::Read {
        path: path.to_owned(),
        source,
    })?;
    match format {
        FileFormat::Png => {
            let reader = guard(path, "PNG", || {
                image::ImageReader::open(path)
                    .and_then(|r| r.with_guessed_format())
                    .map_err(|source| CompareError::Read {
                        path: path.to_owned(),
                        source,
                    })?
                    .into_dimensions()
                    .map_err(|source| CompareError::Png {
                        path: path.to_owned(),
                        source,
                    })
            })?;
            Ok((reader.0 as usize, reader.1 as usize))
        }
        FileFormat::OpenExr => {
            let sizes = guard(path, "OpenEXR", || {
                crate::image_io::exr_layer_sizes(path).map_err(|source| CompareError::Exr {
                    path: path.to_owned(),
                    source,
                })
            })?;
            Ok(sizes
                .into_iter()
                .max_by_key(|&(w, h)| w.saturating_mul(h))
                .unwrap_or((0, 0)))
        }
        FileFormat::Jpeg | FileFormat::Unknown => Err(CompareError::UnknownFormat {
            path: path.to_owned(),
        }),
    }
}
