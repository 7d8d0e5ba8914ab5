//! Grey image files in and out: what the detector and validation read, what
//! the simulator writes. Readers refuse absurd sizes before decoding and
//! truncated JPEGs; writers replace a file whole or not at all.

use std::path::{Path, PathBuf};

use crate::error::{FileKind, LoadError, LoadProblem, WriteError};
use image::GrayImage;

/// Largest image side accepted by [`load_gray`].
pub const MAX_SIDE: u32 = 30_000;
/// Largest image area accepted by [`load_gray`], pixels.
pub const MAX_PIXELS: u64 = 400_000_000;

/// The largest image a reader accepts, checked against the file's header
/// before anything is decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizeLimit {
    /// Longest side, pixels.
    pub max_side: u32,
    /// Largest area, pixels.
    pub max_pixels: u64,
}

impl SizeLimit {
    /// What [`load_gray`] accepts: [`MAX_SIDE`] and [`MAX_PIXELS`].
    pub const FILES: SizeLimit = SizeLimit {
        max_side: MAX_SIDE,
        max_pixels: MAX_PIXELS,
    };

    fn admits(&self, width: u32, height: u32) -> bool {
        width <= self.max_side
            && height <= self.max_side
            && u64::from(width) * u64::from(height) <= self.max_pixels
    }
}

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ImageWriteError {
    /// The output's extension names no format this crate writes.
    #[error("{}: unknown image type (use .png, .jpg, .pgm or .bmp)", path.display())]
    UnknownType {
        /// The output.
        path: PathBuf,
    },
    /// The encoder refused the pixels.
    #[error("cannot encode {}: {source}", path.display())]
    Encode {
        /// The output.
        path: PathBuf,
        /// What the encoder said.
        #[source]
        source: image::ImageError,
    },
    /// The encoded bytes could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

fn image_error(path: &Path, problem: LoadProblem) -> LoadError {
    LoadError::new(path, FileKind::Image, problem)
}

/// Reads an image file (PNG, JPEG, PGM/PPM, BMP; 8 or 16 bit; grey or
/// colour) as 8-bit grey. Refuses sizes beyond [`SizeLimit::FILES`] before
/// decoding.
pub fn load_gray(path: &Path) -> Result<GrayImage, LoadError> {
    let open = || std::fs::File::open(path).map(std::io::BufReader::new);
    let (decoded, format) = decode(path, open, SizeLimit::FILES)?;
    if format == image::ImageFormat::Jpeg {
        // Only now the whole file: the decoder has already read it once.
        let bytes = std::fs::read(path).map_err(|e| image_error(path, LoadProblem::Read(e)))?;
        check_jpeg_complete(path, &bytes)?;
    }
    Ok(to_gray(decoded))
}

/// [`load_gray`] for a file's contents already in memory (an upload in the
/// browser page, bytes from a socket): same formats, same conversion, same
/// errors, with `name` standing for the file in them and `limit` for what
/// the caller can hold.
pub fn decode_gray(name: &Path, bytes: &[u8], limit: SizeLimit) -> Result<GrayImage, LoadError> {
    let open = || Ok(std::io::Cursor::new(bytes));
    let (decoded, format) = decode(name, open, limit)?;
    if format == image::ImageFormat::Jpeg {
        check_jpeg_complete(name, bytes)?;
    }
    Ok(to_gray(decoded))
}

/// Decodes what `open` reads (opened twice: once for the header, once for
/// the pixels), after checking the header's size against `limit`.
fn decode<R: std::io::BufRead + std::io::Seek>(
    path: &Path,
    open: impl Fn() -> std::io::Result<R>,
    limit: SizeLimit,
) -> Result<(image::DynamicImage, image::ImageFormat), LoadError> {
    let io = |e| image_error(path, LoadProblem::Read(e));
    let decode = |e| image_error(path, LoadProblem::Decode(e));
    let reader = || -> Result<_, LoadError> {
        image::ImageReader::new(open().map_err(io)?)
            .with_guessed_format()
            .map_err(io)
    };
    let probe = reader()?;
    let Some(format) = probe.format() else {
        return Err(image_error(
            path,
            LoadProblem::Invalid("not an image (no PNG, JPEG, PGM/PPM or BMP signature)".into()),
        ));
    };
    let (width, height) = probe.into_dimensions().map_err(decode)?;
    if width == 0 || height == 0 {
        return Err(image_error(
            path,
            LoadProblem::Invalid(format!("image of {width}x{height} pixels holds nothing")),
        ));
    }
    if !limit.admits(width, height) {
        return Err(image_error(
            path,
            LoadProblem::TooLarge {
                width,
                height,
                limit,
            },
        ));
    }
    let mut reader = reader()?;
    let mut limits = image::Limits::no_limits();
    limits.max_image_width = Some(limit.max_side);
    limits.max_image_height = Some(limit.max_side);
    // 16-bit RGBA, the widest pixels any of the decoders produces.
    limits.max_alloc = Some(limit.max_pixels.saturating_mul(8));
    reader.limits(limits);
    Ok((reader.decode().map_err(decode)?, format))
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
fn check_jpeg_complete(path: &Path, bytes: &[u8]) -> Result<(), LoadError> {
    let last_scan = bytes.windows(2).rposition(|w| w == [0xFF, 0xDA]);
    let ends = last_scan.is_some_and(|k| bytes[k..].windows(2).any(|w| w == [0xFF, 0xD9]));
    if !ends {
        return Err(image_error(
            path,
            LoadProblem::Invalid(
                "JPEG file is truncated (no end-of-image marker after its image data)".into(),
            ),
        ));
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
    pub fn from_path(path: &Path) -> Result<ImageFormat, ImageWriteError> {
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
            _ => {
                return Err(ImageWriteError::UnknownType {
                    path: path.to_path_buf(),
                })
            }
        })
    }
}

/// A colour picture (an annotated photo) as PNG bytes.
pub fn encode_rgb_png(picture: &image::RgbImage) -> Result<Vec<u8>, image::ImageError> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes).write_image(
        picture.as_raw(),
        picture.width(),
        picture.height(),
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(bytes)
}

/// Writes a grey image whole or not at all, in the format of the path's
/// extension (JPEG at `jpeg_quality`).
#[cfg(feature = "files")]
pub fn save_image(path: &Path, image: &GrayImage, jpeg_quality: u8) -> Result<(), ImageWriteError> {
    Ok(crate::io::write_atomic(
        path,
        &encode_image(path, image, jpeg_quality)?,
    )?)
}

/// The bytes [`save_image`] writes: `image` in the format `path`'s
/// extension names, for writing together with other files.
pub fn encode_image(
    path: &Path,
    image: &GrayImage,
    jpeg_quality: u8,
) -> Result<Vec<u8>, ImageWriteError> {
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
    result.map_err(|source| ImageWriteError::Encode {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_bit_data_is_stretched_to_the_brightest_value() {
        let wide = image::ImageBuffer::from_raw(4, 1, vec![0u16, 1, 511, 1023]).unwrap();
        assert_eq!(stretched_to_8_bits(wide).into_raw(), [0, 0, 127, 255]);
    }

    fn png_bytes(image: &GrayImage) -> Vec<u8> {
        use image::ImageEncoder;
        let mut bytes = Vec::new();
        image::codecs::png::PngEncoder::new(&mut bytes)
            .write_image(
                image.as_raw(),
                image.width(),
                image.height(),
                image::ExtendedColorType::L8,
            )
            .unwrap();
        bytes
    }

    #[test]
    fn bytes_and_files_read_the_same() {
        let image = GrayImage::from_fn(30, 20, |x, y| image::Luma([(x * 7 + y * 3) as u8]));
        let bytes = png_bytes(&image);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ramp.png");
        std::fs::write(&path, &bytes).unwrap();
        let from_file = load_gray(&path).unwrap();
        let from_bytes = decode_gray(Path::new("ramp.png"), &bytes, SizeLimit::FILES).unwrap();
        assert_eq!(from_file, image);
        assert_eq!(from_bytes, image);
    }

    #[test]
    fn errors_name_the_input_and_the_problem() {
        let name = Path::new("notes.png");
        let err = decode_gray(name, b"these are notes", SizeLimit::FILES).unwrap_err();
        assert_eq!(
            err.to_string(),
            "notes.png: not an image (no PNG, JPEG, PGM/PPM or BMP signature)"
        );
        let small = SizeLimit {
            max_side: 25,
            max_pixels: 1_000_000,
        };
        let bytes = png_bytes(&GrayImage::new(30, 20));
        let err = decode_gray(Path::new("wide.png"), &bytes, small).unwrap_err();
        assert!(matches!(
            err.problem,
            LoadProblem::TooLarge {
                width: 30,
                height: 20,
                ..
            }
        ));
        assert_eq!(
            err.to_string(),
            "wide.png: image of 30x20 pixels is larger than the supported 25 px a side and 1 megapixels"
        );
        let mut jpeg = Vec::new();
        image::codecs::jpeg::JpegEncoder::new(&mut jpeg)
            .encode_image(&GrayImage::new(64, 64))
            .unwrap();
        let err =
            decode_gray(Path::new("empty.pgm"), b"P5\n0 0\n255\n", SizeLimit::FILES).unwrap_err();
        assert_eq!(
            err.to_string(),
            "empty.pgm: image of 0x0 pixels holds nothing"
        );
        jpeg.truncate(jpeg.len() - 2);
        let err = decode_gray(Path::new("cut.jpg"), &jpeg, SizeLimit::FILES).unwrap_err();
        assert_eq!(
            err.to_string(),
            "cut.jpg: JPEG file is truncated (no end-of-image marker after its image data)"
        );
    }
}
