//! Grey image files in and out: what the detector and validation read, what
//! the simulator writes. Readers refuse absurd sizes before decoding and
//! truncated JPEGs; writers replace a file whole or not at all.

use std::path::{Path, PathBuf};

use crate::error::{FileKind, LoadError, LoadProblem, WriteError};
use image::{GrayImage, ImageBuffer};

pub use crate::limits::{SizeLimit, MAX_PIXELS, MAX_SIDE};

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
    load_gray_reading_whole(path, READ_WHOLE_BYTES)
}

/// Image files up to this size are read into memory whole before decoding
/// (a 25-megapixel JPEG is about 10 MB).
const READ_WHOLE_BYTES: u64 = 64 << 20;

/// [`load_gray`], reading a file of up to `whole` bytes into memory once
/// and decoding it from there: the decoder looks at the header, then at the
/// pixels, which from disk is a second and third opening of the file. A
/// larger file is opened again for each look, so that a huge file whose
/// header is refused is never read whole.
fn load_gray_reading_whole(path: &Path, whole: u64) -> Result<GrayImage, LoadError> {
    // Refuses a FIFO or device before the decoder waits on it or reads
    // without end.
    {
        let (mut file, length) = crate::input::open(path, FileKind::Image)?;
        if length <= whole {
            let mut bytes = Vec::with_capacity(length as usize);
            std::io::Read::read_to_end(&mut file, &mut bytes)
                .map_err(|e| image_error(path, LoadProblem::Read(e)))?;
            let open = || Ok(std::io::Cursor::new(&bytes[..]));
            return Ok(decode(path, open, SizeLimit::FILES)?.0);
        }
    }
    let open = || std::fs::File::open(path).map(std::io::BufReader::new);
    Ok(decode(path, open, SizeLimit::FILES)?.0)
}

/// [`load_gray`] for a file's contents already in memory (an upload in the
/// browser page, bytes from a socket): same formats, same conversion, same
/// errors, with `name` standing for the file in them and `limit` for what
/// the caller can hold.
pub fn decode_gray(name: &Path, bytes: &[u8], limit: SizeLimit) -> Result<GrayImage, LoadError> {
    let open = || Ok(std::io::Cursor::new(bytes));
    Ok(decode(name, open, limit)?.0)
}

/// PNGs of more pixels than this are turned grey a row at a time: whole, a
/// 20000 x 20000 RGBA16 file (3 MB on disk) took 3.9 GB to decode.
const ROW_BY_ROW_PNG_PIXELS: u64 = 16_000_000;

/// Decodes what `open` reads (opened twice: once for the header, once for
/// the pixels) to grey, after checking the header's size against `limit`.
fn decode<R: std::io::BufRead + std::io::Seek>(
    path: &Path,
    open: impl Fn() -> std::io::Result<R>,
    limit: SizeLimit,
) -> Result<(GrayImage, image::ImageFormat), LoadError> {
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
    if format == image::ImageFormat::Jpeg {
        let mut bytes = Vec::new();
        open()
            .and_then(|mut source| source.read_to_end(&mut bytes))
            .map_err(io)?;
        check_jpeg_complete(path, &bytes)?;
        let decoded =
            decode_jpeg_strictly(&bytes).map_err(|damage| image_error(path, damage.into()))?;
        let gray = to_gray(decoded);
        if zeroed_scan(&bytes) && same_in_every_block(&gray) {
            return Err(image_error(
                path,
                LoadProblem::Invalid(
                    "damaged JPEG: its image data is zeros (every 8x8 block decodes the same)"
                        .into(),
                ),
            ));
        }
        return Ok((gray, format));
    }
    if format == image::ImageFormat::Png {
        check_palette_indices(open().map_err(io)?)
            .map_err(|damage| image_error(path, damage.into()))?;
    }
    if format == image::ImageFormat::Png
        && u64::from(width) * u64::from(height) > ROW_BY_ROW_PNG_PIXELS
    {
        let source = open().map_err(io)?;
        let rows = png_rows_to_gray(source).map_err(|damage| image_error(path, damage.into()))?;
        if let Some(gray) = rows {
            return Ok((gray, format));
        }
    }
    let mut reader = reader()?;
    let mut limits = image::Limits::no_limits();
    limits.max_image_width = Some(limit.max_side);
    limits.max_image_height = Some(limit.max_side);
    // 16-bit RGBA, the widest pixels any of the decoders produces.
    limits.max_alloc = Some(limit.max_pixels.saturating_mul(8));
    reader.limits(limits);
    let decoded = reader.decode().map_err(|e| match &e {
        image::ImageError::IoError(cause) if cause.kind() == std::io::ErrorKind::UnexpectedEof => {
            truncated(path, format)
        }
        _ => decode(e),
    })?;
    Ok((to_gray(decoded), format))
}

/// A file that ends before the pixels its header gives, in words: the
/// decoders say only that a read came up short. (JPEGs are checked for
/// completeness before they get here.)
fn truncated(path: &Path, format: image::ImageFormat) -> LoadError {
    let name = match format {
        image::ImageFormat::Png => "PNG",
        image::ImageFormat::Pnm => "PGM/PPM",
        image::ImageFormat::Bmp => "BMP",
        _ => "image",
    };
    image_error(
        path,
        LoadProblem::Invalid(format!(
            "{name} file is truncated (it ends before the pixels its header gives)"
        )),
    )
}

/// Damage the strict decoders below find in a file the `image` crate would
/// decode without a word. A decoder's own error is quoted in the message,
/// not chained as a source, so that the message is the whole line.
#[derive(Debug, thiserror::Error)]
enum Damage {
    /// The JPEG decoder's refusal.
    #[error("damaged JPEG: {0}")]
    Jpeg(zune_jpeg::errors::DecodeErrors),
    /// A JPEG without a frame header.
    #[error("damaged JPEG: no frame header")]
    NoFrameHeader,
    /// A JPEG whose pixels stop short of its header's size.
    #[error("damaged JPEG: fewer pixels than its header gives")]
    ShortJpeg,
    /// The PNG decoder's refusal.
    #[error("damaged PNG: {0}")]
    Png(png::DecodingError),
    /// A palette index past the palette's end.
    #[error(
        "damaged PNG: pixel index {highest} runs past its palette of {colours} colour{}",
        if *colours == 1 { "" } else { "s" }
    )]
    PastPalette {
        /// The highest index in the pixels.
        highest: u16,
        /// How many colours the palette has.
        colours: usize,
    },
    /// A PNG row of another length than its header gives.
    #[error("a PNG row of another length than its header gives")]
    RowLength,
}

impl From<Damage> for LoadProblem {
    fn from(damage: Damage) -> LoadProblem {
        LoadProblem::Invalid(damage.to_string())
    }
}

/// A JPEG decoded as the `image` crate decodes it (the same decoder,
/// asked for the same colours), but in the decoder's strict mode: leniently,
/// a scan of zeros or a corrupt Huffman stream decodes "without error" to
/// grey or garbage, which would read as a photo with no markers in it.
fn decode_jpeg_strictly(bytes: &[u8]) -> Result<image::DynamicImage, Damage> {
    use zune_core::colorspace::ColorSpace;
    let options = zune_core::options::DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(usize::MAX)
        .set_max_height(usize::MAX);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(
        zune_core::bytestream::ZCursor::new(bytes),
        options,
    );
    decoder.decode_headers().map_err(Damage::Jpeg)?;
    let (width, height) = decoder.dimensions().ok_or(Damage::NoFrameHeader)?;
    let colours = match decoder.input_colorspace() {
        Some(c @ (ColorSpace::RGB | ColorSpace::RGBA | ColorSpace::Luma | ColorSpace::LumaA)) => c,
        _ => ColorSpace::RGB,
    };
    decoder.set_options(decoder.options().jpeg_set_out_colorspace(colours));
    let pixels = decoder.decode().map_err(Damage::Jpeg)?;
    let (w, h) = (width as u32, height as u32);
    use image::DynamicImage as Dyn;
    Ok(match colours {
        ColorSpace::Luma => {
            Dyn::ImageLuma8(ImageBuffer::from_raw(w, h, pixels).ok_or(Damage::ShortJpeg)?)
        }
        ColorSpace::LumaA => {
            Dyn::ImageLumaA8(ImageBuffer::from_raw(w, h, pixels).ok_or(Damage::ShortJpeg)?)
        }
        ColorSpace::RGBA => {
            Dyn::ImageRgba8(ImageBuffer::from_raw(w, h, pixels).ok_or(Damage::ShortJpeg)?)
        }
        _ => Dyn::ImageRgb8(ImageBuffer::from_raw(w, h, pixels).ok_or(Damage::ShortJpeg)?),
    })
}

/// Whether the last scan's entropy-coded data is nearly all zero bytes,
/// as a file whose data was wiped (or never written) is. The decoder reads
/// zeros as valid codes and makes a grey picture of them without a word.
fn zeroed_scan(bytes: &[u8]) -> bool {
    let Some(sos) = bytes.windows(2).rposition(|w| w == [0xFF, 0xDA]) else {
        return false;
    };
    let Some(header) = bytes.get(sos + 2..sos + 4) else {
        return false;
    };
    let start = sos + 2 + usize::from(u16::from_be_bytes([header[0], header[1]]));
    let end = bytes
        .windows(2)
        .rposition(|w| w == [0xFF, 0xD9])
        .unwrap_or(bytes.len());
    let Some(data) = bytes.get(start..end) else {
        return false;
    };
    let zeros = data.iter().filter(|&&b| b == 0).count();
    data.len() >= 64 && zeros * 10 >= data.len() * 9
}

/// Whether every 8x8 block of `gray` is the same as the first: what zeroed
/// JPEG data decodes to (and a perfectly blank frame; no photo is either,
/// so the scan stops at the first pixel that differs).
fn same_in_every_block(gray: &GrayImage) -> bool {
    let w = gray.width() as usize;
    let pixels = gray.as_raw();
    pixels.iter().enumerate().all(|(k, &value)| {
        let (x, y) = (k % w, k / w);
        pixels[(y % 8) * w + x % 8] == value
    })
}

/// The PNG decoder turns a palette index past the palette's end into
/// black without a word: a damaged file would read as a picture with dark
/// blots. Only an indexed file is read (a second time, as raw indices).
fn check_palette_indices<R: std::io::BufRead + std::io::Seek>(source: R) -> Result<(), Damage> {
    let mut decoder = png::Decoder::new(source);
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().map_err(Damage::Png)?;
    let info = reader.info();
    if info.color_type != png::ColorType::Indexed {
        return Ok(());
    }
    let colours = info.palette.as_ref().map_or(0, |p| p.len() / 3);
    let depth = info.bit_depth as u8;
    if colours >= 1 << depth {
        return Ok(());
    }
    let width = info.width as usize;
    let per_byte = 8 / depth as usize;
    let mask = (1u16 << depth) - 1;
    let mut highest = 0u16;
    while let Some(row) = reader.next_row().map_err(Damage::Png)? {
        // Interlaced passes are narrower than the image; count their own width.
        let pixels = (row.data().len() * per_byte).min(width);
        for k in 0..pixels {
            let byte = u16::from(row.data()[k / per_byte]);
            let shift = 8 - depth as usize * (k % per_byte + 1);
            highest = highest.max((byte >> shift) & mask);
        }
    }
    if usize::from(highest) >= colours {
        return Err(Damage::PastPalette { highest, colours });
    }
    Ok(())
}

/// A PNG turned grey a row at a time, each row converted exactly as
/// [`to_gray`] converts a whole decoded image (the same `image` crate
/// conversions, on one row), so only the grey result is ever whole (and,
/// for 16-bit files, its 16-bit grey before the stretch). `None` for an
/// interlaced file, whose rows come in passes: it is decoded whole.
fn png_rows_to_gray<R: std::io::BufRead + std::io::Seek>(
    source: R,
) -> Result<Option<GrayImage>, Damage> {
    use image::DynamicImage as Dyn;
    let mut decoder = png::Decoder::new(source);
    // Palette and low-bit grey to 8 bits, transparency to alpha: what the
    // `image` crate's own PNG decoder asks for.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(Damage::Png)?;
    if reader.info().interlaced {
        return Ok(None);
    }
    let (width, height) = (reader.info().width, reader.info().height);
    let (colour, depth) = reader.output_color_type();
    let channels = colour.samples();
    let row_of = |raw: Vec<u8>| -> Option<Dyn> {
        Some(match channels {
            1 => Dyn::ImageLuma8(ImageBuffer::from_raw(width, 1, raw)?),
            2 => Dyn::ImageLumaA8(ImageBuffer::from_raw(width, 1, raw)?),
            3 => Dyn::ImageRgb8(ImageBuffer::from_raw(width, 1, raw)?),
            _ => Dyn::ImageRgba8(ImageBuffer::from_raw(width, 1, raw)?),
        })
    };
    let wide_row_of = |raw: Vec<u16>| -> Option<Dyn> {
        Some(match channels {
            1 => Dyn::ImageLuma16(ImageBuffer::from_raw(width, 1, raw)?),
            2 => Dyn::ImageLumaA16(ImageBuffer::from_raw(width, 1, raw)?),
            3 => Dyn::ImageRgb16(ImageBuffer::from_raw(width, 1, raw)?),
            _ => Dyn::ImageRgba16(ImageBuffer::from_raw(width, 1, raw)?),
        })
    };
    let pixels = width as usize * height as usize;
    if depth == png::BitDepth::Sixteen {
        let mut wide: Vec<u16> = Vec::with_capacity(pixels);
        while let Some(row) = reader.next_row().map_err(Damage::Png)? {
            let raw = row
                .data()
                .chunks_exact(2)
                .map(|b| u16::from_be_bytes([b[0], b[1]]))
                .collect();
            wide.extend(
                wide_row_of(raw)
                    .ok_or(Damage::RowLength)?
                    .into_luma16()
                    .into_raw(),
            );
        }
        let wide = ImageBuffer::from_raw(width, height, wide).ok_or(Damage::RowLength)?;
        return Ok(Some(stretched_to_8_bits(wide)));
    }
    let mut grey: Vec<u8> = Vec::with_capacity(pixels);
    while let Some(row) = reader.next_row().map_err(Damage::Png)? {
        let row = row_of(row.data().to_vec()).ok_or(Damage::RowLength)?;
        grey.extend(row.into_luma8().into_raw());
    }
    Ok(Some(
        GrayImage::from_raw(width, height, grey).ok_or(Damage::RowLength)?,
    ))
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

    /// Every PNG colour type and depth, encoded with `png` directly.
    fn png_of(colour: png::ColorType, depth: png::BitDepth, palette: bool) -> Vec<u8> {
        let (w, h) = (37u32, 11u32);
        let samples = match colour {
            png::ColorType::Grayscale | png::ColorType::Indexed => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
        };
        let bits = depth as usize;
        let row_bytes = (w as usize * samples * bits).div_ceil(8);
        let data: Vec<u8> = (0..row_bytes * h as usize)
            .map(|k| ((k * 37 + k / 7) % 251) as u8)
            .collect();
        let mut bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut bytes, w, h);
            encoder.set_color(colour);
            encoder.set_depth(depth);
            if palette {
                encoder.set_palette(
                    (0..=255u8)
                        .flat_map(|i| [i, 255 - i, i / 2])
                        .collect::<Vec<_>>(),
                );
                encoder.set_trns(vec![200u8; 16]);
            }
            let mut writer = encoder.write_header().unwrap();
            writer.write_image_data(&data).unwrap();
        }
        bytes
    }

    #[test]
    fn png_rows_turn_grey_exactly_as_the_whole_image_does() {
        use png::{BitDepth as D, ColorType as C};
        let cases = [
            (C::Grayscale, D::One, false),
            (C::Grayscale, D::Four, false),
            (C::Grayscale, D::Eight, false),
            (C::Grayscale, D::Sixteen, false),
            (C::GrayscaleAlpha, D::Eight, false),
            (C::GrayscaleAlpha, D::Sixteen, false),
            (C::Rgb, D::Eight, false),
            (C::Rgb, D::Sixteen, false),
            (C::Rgba, D::Eight, false),
            (C::Rgba, D::Sixteen, false),
            (C::Indexed, D::Eight, true),
            (C::Indexed, D::Two, true),
        ];
        for (colour, depth, palette) in cases {
            let bytes = png_of(colour, depth, palette);
            let whole = to_gray(image::load_from_memory(&bytes).unwrap());
            let rows = png_rows_to_gray(std::io::Cursor::new(&bytes))
                .unwrap()
                .unwrap();
            assert_eq!(rows, whole, "{colour:?} {depth:?}");
        }
    }

    #[test]
    fn bytes_and_files_read_the_same() {
        let image = GrayImage::from_fn(30, 20, |x, y| image::Luma([(x * 7 + y * 3) as u8]));
        let bytes = png_bytes(&image);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ramp.png");
        std::fs::write(&path, &bytes).unwrap();
        let from_file = load_gray(&path).unwrap();
        let reopened = load_gray_reading_whole(&path, 0).unwrap();
        let from_bytes = decode_gray(Path::new("ramp.png"), &bytes, SizeLimit::FILES).unwrap();
        assert_eq!(from_file, image);
        assert_eq!(reopened, image);
        assert_eq!(from_bytes, image);
    }

    #[test]
    fn a_jpeg_whose_data_was_zeroed_is_refused() {
        let photo = GrayImage::from_fn(64, 48, |x, y| image::Luma([((x * 5 + y * 3) % 256) as u8]));
        let mut bytes = encode_image(Path::new("a.jpg"), &photo, 90).unwrap();
        assert!(decode_gray(Path::new("a.jpg"), &bytes, SizeLimit::FILES).is_ok());
        let sos = bytes.windows(2).rposition(|w| w == [0xFF, 0xDA]).unwrap();
        let start = sos + 2 + usize::from(u16::from_be_bytes([bytes[sos + 2], bytes[sos + 3]]));
        let end = bytes.len() - 2;
        bytes[start..end].fill(0);
        let err = decode_gray(Path::new("z.jpg"), &bytes, SizeLimit::FILES).unwrap_err();
        assert_eq!(
            err.to_string(),
            "z.jpg: damaged JPEG: its image data is zeros (every 8x8 block decodes the same)"
        );
    }

    #[test]
    fn palette_indices_past_the_palette_are_refused() {
        let indexed = |colours: usize| {
            let mut bytes = Vec::new();
            {
                let mut encoder = png::Encoder::new(&mut bytes, 16, 4);
                encoder.set_color(png::ColorType::Indexed);
                encoder.set_depth(png::BitDepth::Eight);
                encoder.set_palette((0..colours * 3).map(|k| k as u8).collect::<Vec<_>>());
                let mut writer = encoder.write_header().unwrap();
                writer
                    .write_image_data(&(0..64u8).map(|k| k % 6).collect::<Vec<_>>())
                    .unwrap();
            }
            bytes
        };
        let limit = SizeLimit::FILES;
        let err = decode_gray(Path::new("blots.png"), &indexed(4), limit).unwrap_err();
        assert_eq!(
            err.to_string(),
            "blots.png: damaged PNG: pixel index 5 runs past its palette of 4 colours"
        );
        assert!(decode_gray(Path::new("fine.png"), &indexed(6), limit).is_ok());
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
        let mut pgm = b"P5\n40 30\n255\n".to_vec();
        pgm.extend([128u8; 500]);
        let err = decode_gray(Path::new("cut.pgm"), &pgm, SizeLimit::FILES).unwrap_err();
        assert_eq!(
            err.to_string(),
            "cut.pgm: PGM/PPM file is truncated (it ends before the pixels its header gives)"
        );
    }
}
