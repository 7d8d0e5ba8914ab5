//! Grey image files in and out: what the detector and validation read, what
//! the simulator writes. Readers refuse absurd sizes before decoding and
//! truncated JPEGs; writers replace a file whole or not at all.

use std::path::{Path, PathBuf};

use anyhow::Result;
use image::GrayImage;

/// Largest image side accepted by [`load_gray`].
pub const MAX_SIDE: u32 = 30_000;
/// Largest image area accepted by [`load_gray`], pixels.
pub const MAX_PIXELS: u64 = 400_000_000;

/// Why an image file could not be read. Each message is one line that
/// starts with the file's name; the cause, when there is one, is also the
/// error's `source`.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The file could not be opened or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// The file is not an image the decoders understand, or is damaged.
    #[error("{}: {source}", path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// What the decoder said.
        #[source]
        source: image::ImageError,
    },
    /// The image is larger than [`MAX_SIDE`] or [`MAX_PIXELS`]: refused
    /// before decoding, so a hostile header cannot exhaust memory.
    #[error(
        "{}: image of {width}x{height} pixels is larger than the supported {MAX_SIDE} px a side and {} megapixels",
        path.display(),
        MAX_PIXELS / 1_000_000
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Width in the header, pixels.
        width: u32,
        /// Height in the header, pixels.
        height: u32,
    },
    /// A JPEG file that ends before its image data does.
    #[error(
        "{}: JPEG file is truncated (no end-of-image marker after its image data)",
        path.display()
    )]
    TruncatedJpeg {
        /// The file.
        path: PathBuf,
    },
}

/// Reads an image file (PNG, JPEG, PGM/PPM, BMP; 8 or 16 bit; grey or
/// colour) as 8-bit grey. Refuses absurd dimensions before decoding.
pub fn load_gray(path: &Path) -> std::result::Result<GrayImage, ImageError> {
    let io = |source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    };
    let decode = |source| ImageError::Decode {
        path: path.to_path_buf(),
        source,
    };
    let open = || -> std::result::Result<_, ImageError> {
        image::ImageReader::open(path)
            .map_err(io)?
            .with_guessed_format()
            .map_err(io)
    };
    let (width, height) = open()?.into_dimensions().map_err(decode)?;
    if width > MAX_SIDE || height > MAX_SIDE || u64::from(width) * u64::from(height) > MAX_PIXELS {
        return Err(ImageError::TooLarge {
            path: path.to_path_buf(),
            width,
            height,
        });
    }
    let mut reader = open()?;
    let mut limits = image::Limits::no_limits();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    reader.limits(limits);
    let format = reader.format();
    let decoded = reader.decode().map_err(decode)?;
    if format == Some(image::ImageFormat::Jpeg) {
        check_jpeg_complete(path)?;
    }
    Ok(to_gray(decoded))
}

/// 8-bit grey of decoded pixels: 8-bit grey as it is, colour by the `image`
/// crate's luma weights (alpha ignored), 16-bit data stretched so the
/// brightest value present becomes 255. The loader and the bindings (numpy
/// arrays) both come through here, so a frame gives the same grey levels,
/// and the same detections, whether it was read from a file or handed over.
pub fn to_gray(decoded: image::DynamicImage) -> GrayImage {
    match decoded {
        image::DynamicImage::ImageLuma8(g) => g,
        image::DynamicImage::ImageLuma16(_)
        | image::DynamicImage::ImageLumaA16(_)
        | image::DynamicImage::ImageRgb16(_)
        | image::DynamicImage::ImageRgba16(_) => stretched_to_8_bits(decoded.into_luma16()),
        other => other.into_luma8(),
    }
}

/// Many cameras write 10- or 12-bit data into 16-bit files, which a plain
/// division by 257 squeezes into a handful of grey levels. The brightest
/// value present becomes 255 instead (the detector's thresholds are local,
/// so a linear stretch changes nothing else).
pub fn stretched_to_8_bits(wide: image::ImageBuffer<image::Luma<u16>, Vec<u16>>) -> GrayImage {
    let (width, height) = wide.dimensions();
    GrayImage::from_raw(width, height, stretched_values(wide.as_raw())).expect("same size")
}

/// [`stretched_to_8_bits`] on bare values.
pub fn stretched_values(wide: &[u16]) -> Vec<u8> {
    let brightest = wide.iter().copied().max().unwrap_or(0).max(1);
    let scale = 255.0 / f64::from(brightest);
    wide.iter()
        .map(|&v| (f64::from(v) * scale).round() as u8)
        .collect()
}

/// The JPEG decoder fills a truncated file's missing part with grey and
/// reports no error, which would read as "no markers here". A complete
/// file has an end-of-image marker after its last scan (a thumbnail's EOI
/// comes before the main image's scans; entropy-coded data never holds FF D9).
fn check_jpeg_complete(path: &Path) -> std::result::Result<(), ImageError> {
    let bytes = std::fs::read(path).map_err(|source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let last_scan = bytes.windows(2).rposition(|w| w == [0xFF, 0xDA]);
    let ends = last_scan.is_some_and(|k| bytes[k..].windows(2).any(|w| w == [0xFF, 0xD9]));
    if !ends {
        return Err(ImageError::TruncatedJpeg {
            path: path.to_path_buf(),
        });
    }
    Ok(())
}

/// Image file formats written, chosen by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// PNG, lossless.
    Png,
    /// JPEG, lossy: what cameras deliver.
    Jpeg,
    /// Binary PGM, for tools that read nothing else.
    Pgm,
    /// BMP, uncompressed.
    Bmp,
}

impl ImageFormat {
    /// The format named by the file's extension, or an error naming the file.
    pub fn from_path(path: &Path) -> Result<ImageFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or_default()
            .to_ascii_lowercase();
        Ok(match ext.as_str() {
            "png" => ImageFormat::Png,
            "jpg" | "jpeg" => ImageFormat::Jpeg,
            "pgm" | "pnm" => ImageFormat::Pgm,
            "bmp" => ImageFormat::Bmp,
            _ => anyhow::bail!(
                "{}: unknown image type (use .png, .jpg, .pgm or .bmp)",
                path.display()
            ),
        })
    }
}

/// Writes a grey image whole or not at all, in the format of the path's
/// extension (JPEG at `jpeg_quality`).
#[cfg(feature = "files")]
pub fn save_image(path: &Path, image: &GrayImage, jpeg_quality: u8) -> Result<()> {
    use image::ImageEncoder;
    let format = ImageFormat::from_path(path)?;
    let (w, h) = image.dimensions();
    let mut bytes = Vec::new();
    let colour = image::ExtendedColorType::L8;
    let result = match format {
        ImageFormat::Png => image::codecs::png::PngEncoder::new(&mut bytes).write_image(
            image.as_raw(),
            w,
            h,
            colour,
        ),
        ImageFormat::Jpeg => image::codecs::jpeg::JpegEncoder::new_with_quality(
            &mut bytes,
            jpeg_quality.clamp(1, 100),
        )
        .write_image(image.as_raw(), w, h, colour),
        ImageFormat::Pgm => image::codecs::pnm::PnmEncoder::new(&mut bytes)
            .with_subtype(image::codecs::pnm::PnmSubtype::Graymap(
                image::codecs::pnm::SampleEncoding::Binary,
            ))
            .write_image(image.as_raw(), w, h, colour),
        ImageFormat::Bmp => image::codecs::bmp::BmpEncoder::new(&mut bytes).write_image(
            image.as_raw(),
            w,
            h,
            colour,
        ),
    };
    result.map_err(|e| anyhow::anyhow!("cannot encode {}: {e}", path.display()))?;
    crate::io::write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_bit_data_is_stretched_to_the_brightest_value() {
        let wide = image::ImageBuffer::from_raw(4, 1, vec![0u16, 1, 511, 1023]).unwrap();
        assert_eq!(stretched_to_8_bits(wide).into_raw(), [0, 0, 127, 255]);
    }
}
