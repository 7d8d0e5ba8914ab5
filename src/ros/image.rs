//! Camera messages (from DDS or from a bag) to the detector's 8-bit grey pixels: sensor_msgs/Image
//! in any of the encodings camera drivers publish for visible light, and
//! sensor_msgs/CompressedImage (JPEG, PNG). A message that cannot be read
//! gives a [`FrameError`] naming why; nothing here panics on what arrives
//! over the network.
//!
//! A `mono8` image whose rows are packed is read in place; every other
//! layout is converted into a buffer kept from frame to frame.

use super::msg::{CompressedImage, Image};
use crate::image_io::SizeLimit;
use image::{GrayImage, ImageBuffer, Luma};
use std::fmt;

/// Grey pixels borrowed from a message or from the converter's buffer.
pub type GrayView<'a> = ImageBuffer<Luma<u8>, &'a [u8]>;

/// Why a frame could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FrameError {
    /// Width or height is zero.
    Empty {
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
    },
    /// An encoding this node does not read.
    UnknownEncoding(String),
    /// Rows shorter than the encoding's pixels need.
    StepTooSmall {
        /// The encoding.
        encoding: String,
        /// Bytes per row given.
        step: u32,
        /// Bytes per row needed.
        needed: u64,
    },
    /// `data` is not `step * height` bytes.
    DataLength {
        /// Bytes received.
        len: usize,
        /// `step * height`.
        expected: u64,
    },
    /// A packed 4:2:2 image of odd width.
    OddWidth(u32),
    /// A compressed image that does not decode.
    Undecodable(String),
}

impl FrameError {
    /// What the error is about, for logging each cause once: the same
    /// cause with other numbers is still the same cause.
    pub fn cause(&self) -> String {
        match self {
            FrameError::Empty { .. } => "empty".into(),
            FrameError::UnknownEncoding(e) => format!("encoding {}", e.escape_debug()),
            FrameError::StepTooSmall { encoding, .. } => format!("step {encoding}"),
            FrameError::DataLength { .. } => "data length".into(),
            FrameError::OddWidth(_) => "odd width".into(),
            FrameError::Undecodable(_) => "undecodable".into(),
        }
    }
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::Empty { width, height } => {
                write!(f, "empty image ({width}x{height} pixels)")
            }
            // Escaped: the name comes from the message, and a NUL or a
            // line break in it must not reach a terminal or a log raw.
            FrameError::UnknownEncoding(e) => write!(
                f,
                "encoding '{}' is not read (mono8, mono16, rgb8, bgr8, rgba8, bgra8, \
                 yuv422/uyvy, yuv422_yuy2/yuyv are)",
                e.escape_debug()
            ),
            FrameError::StepTooSmall {
                encoding,
                step,
                needed,
            } => write!(
                f,
                "step of {step} bytes is less than a row of {encoding} needs ({needed} bytes)"
            ),
            FrameError::DataLength { len, expected } => write!(
                f,
                "data holds {len} bytes where step x height is {expected}"
            ),
            FrameError::OddWidth(w) => {
                write!(f, "a 4:2:2 image must have an even width, not {w}")
            }
            FrameError::Undecodable(e) => write!(f, "compressed image does not decode: {e}"),
        }
    }
}

/// How the pixels of an encoding are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Layout {
    Mono8,
    Mono16,
    /// Colour: bytes per pixel and the offsets of red, green and blue.
    Colour {
        bytes: usize,
        rgb: [usize; 3],
    },
    /// Packed 4:2:2, luma at this byte of each pair (UYVY: 1, YUYV: 0).
    Yuv422 {
        luma: usize,
    },
}

impl Layout {
    /// The layout of a sensor_msgs/image_encodings name.
    fn of(encoding: &str) -> Option<Layout> {
        Some(match encoding {
            "mono8" | "8UC1" => Layout::Mono8,
            "mono16" | "16UC1" => Layout::Mono16,
            "rgb8" => Layout::Colour {
                bytes: 3,
                rgb: [0, 1, 2],
            },
            "bgr8" | "8UC3" => Layout::Colour {
                bytes: 3,
                rgb: [2, 1, 0],
            },
            "rgba8" => Layout::Colour {
                bytes: 4,
                rgb: [0, 1, 2],
            },
            "bgra8" | "8UC4" => Layout::Colour {
                bytes: 4,
                rgb: [2, 1, 0],
            },
            "yuv422" | "uyvy" => Layout::Yuv422 { luma: 1 },
            "yuv422_yuy2" | "yuyv" => Layout::Yuv422 { luma: 0 },
            _ => return None,
        })
    }

    fn bytes_per_pixel(self) -> u64 {
        match self {
            Layout::Mono8 => 1,
            Layout::Mono16 | Layout::Yuv422 { .. } => 2,
            Layout::Colour { bytes, .. } => bytes as u64,
        }
    }
}

/// Luma of a colour pixel with the `image` crate's weights (Rec. 709),
/// rounded: the grey levels `whycode detect` reads from the same picture
/// saved as a PNG, to within the last bit of the crate's float arithmetic.
#[inline]
fn luma(r: u8, g: u8, b: u8) -> u8 {
    ((2126 * u32::from(r) + 7152 * u32::from(g) + 722 * u32::from(b) + 5000) / 10000) as u8
}

/// Turns messages into grey images, reusing one buffer.
#[derive(Debug, Default)]
pub struct Converter {
    buffer: Vec<u8>,
}

impl Converter {
    /// The grey pixels of a raw image message.
    pub fn gray<'a>(&'a mut self, msg: &'a Image) -> Result<GrayView<'a>, FrameError> {
        let (width, height) = (msg.width, msg.height);
        if width == 0 || height == 0 {
            return Err(FrameError::Empty { width, height });
        }
        let layout = Layout::of(&msg.encoding)
            .ok_or_else(|| FrameError::UnknownEncoding(msg.encoding.clone()))?;
        let needed = u64::from(width) * layout.bytes_per_pixel();
        if u64::from(msg.step) < needed {
            return Err(FrameError::StepTooSmall {
                encoding: msg.encoding.clone(),
                step: msg.step,
                needed,
            });
        }
        let expected = u64::from(msg.step) * u64::from(height);
        if msg.data.len() as u64 != expected {
            return Err(FrameError::DataLength {
                len: msg.data.len(),
                expected,
            });
        }
        if matches!(layout, Layout::Yuv422 { .. }) && width % 2 == 1 {
            return Err(FrameError::OddWidth(width));
        }
        let (w, h, step) = (width as usize, height as usize, msg.step as usize);
        let rows = msg
            .data
            .chunks_exact(step)
            .map(|row| &row[..w * layout.bytes_per_pixel() as usize]);
        let pixels: &[u8] = match layout {
            Layout::Mono8 if step == w => &msg.data,
            Layout::Mono8 => {
                self.buffer.clear();
                rows.for_each(|row| self.buffer.extend_from_slice(row));
                &self.buffer
            }
            Layout::Mono16 => {
                let read = if msg.is_bigendian != 0 {
                    u16::from_be_bytes
                } else {
                    u16::from_le_bytes
                };
                let wide: Vec<u16> = rows
                    .flat_map(|row| row.chunks_exact(2).map(|p| read([p[0], p[1]])))
                    .collect();
                // The library's rule for 16-bit grey (10- and 12-bit
                // cameras fill only the low bits): the brightest value
                // present becomes 255.
                self.buffer = crate::image_io::stretched_values(&wide);
                &self.buffer
            }
            Layout::Colour { bytes, rgb } => {
                self.buffer.clear();
                self.buffer.reserve(w * h);
                for row in rows {
                    self.buffer.extend(
                        row.chunks_exact(bytes)
                            .map(|p| luma(p[rgb[0]], p[rgb[1]], p[rgb[2]])),
                    );
                }
                &self.buffer
            }
            Layout::Yuv422 { luma } => {
                self.buffer.clear();
                self.buffer.reserve(w * h);
                for row in rows {
                    self.buffer.extend(row.iter().skip(luma).step_by(2));
                }
                &self.buffer
            }
        };
        Ok(ImageBuffer::from_raw(width, height, pixels).expect("width x height pixels"))
    }

    /// The grey pixels of a compressed image (JPEG or PNG: the format is
    /// read from the data, whatever `format` says), decoded as the library
    /// decodes image files; `topic` names it in errors.
    pub fn gray_compressed(
        &mut self,
        msg: &CompressedImage,
        topic: &str,
    ) -> Result<GrayImage, FrameError> {
        if msg.format.contains("compressedDepth") {
            return Err(FrameError::UnknownEncoding(msg.format.clone()));
        }
        let gray = crate::decode_gray(std::path::Path::new(topic), &msg.data, SizeLimit::FRAMES)
            .map_err(|e| FrameError::Undecodable(e.to_string()))?;
        if gray.width() == 0 || gray.height() == 0 {
            return Err(FrameError::Empty {
                width: gray.width(),
                height: gray.height(),
            });
        }
        Ok(gray)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::msg::Header;

    fn image(encoding: &str, width: u32, height: u32, step: u32, data: Vec<u8>) -> Image {
        Image {
            header: Header::default(),
            height,
            width,
            encoding: encoding.into(),
            is_bigendian: 0,
            step,
            data,
        }
    }

    /// The grey pixels of a message, owned.
    fn convert(msg: &Image) -> Result<Vec<u8>, FrameError> {
        Converter::default().gray(msg).map(|g| g.as_raw().to_vec())
    }

    /// A 5x3 RGB picture with varied values.
    fn rgb_picture() -> image::RgbImage {
        image::RgbImage::from_fn(5, 3, |x, y| {
            image::Rgb([
                (x * 50 + y * 7) as u8,
                (255 - x * 31 - y * 40) as u8,
                (x * y * 17 + 3) as u8,
            ])
        })
    }

    #[test]
    fn colour_encodings_give_the_same_grey() {
        let picture = rgb_picture();
        let expected: Vec<u8> = picture.pixels().map(|p| luma(p[0], p[1], p[2])).collect();
        let rgb = picture.as_raw().clone();
        let swap = |bytes: usize, alpha: bool, bgr: bool| -> Vec<u8> {
            rgb.chunks_exact(3)
                .flat_map(|p| {
                    let mut px = if bgr {
                        vec![p[2], p[1], p[0]]
                    } else {
                        p.to_vec()
                    };
                    if alpha {
                        px.push(77);
                    }
                    assert_eq!(px.len(), bytes);
                    px
                })
                .collect()
        };
        for (encoding, bytes, alpha, bgr) in [
            ("rgb8", 3, false, false),
            ("bgr8", 3, false, true),
            ("rgba8", 4, true, false),
            ("bgra8", 4, true, true),
        ] {
            let msg = image(encoding, 5, 3, 5 * bytes, swap(bytes as usize, alpha, bgr));
            assert_eq!(convert(&msg).unwrap(), expected, "{encoding}");
        }
    }

    #[test]
    fn every_colour_gives_the_grey_the_image_crate_gives() {
        // All 2^24 colours would take long; every 3rd level of each channel
        // crosses every rounding case of each weight many times.
        let levels: Vec<u8> = (0..=255).step_by(3).collect();
        let n = levels.len() as u32;
        let picture = image::RgbImage::from_fn(n * n, n, |x, y| {
            image::Rgb([
                levels[(x / n) as usize],
                levels[(x % n) as usize],
                levels[y as usize],
            ])
        });
        let expected = image::DynamicImage::ImageRgb8(picture.clone()).into_luma8();
        let ours = picture.pixels().map(|p| luma(p[0], p[1], p[2]));
        let differences: Vec<i32> = ours
            .zip(expected.as_raw())
            .map(|(a, &b)| i32::from(a) - i32::from(b))
            .filter(|&d| d != 0)
            .collect();
        // Exact but where float rounding lands on the other side of a half
        // (0.4 % of these colours).
        assert!(differences.iter().all(|d| d.abs() == 1), "{differences:?}");
        assert!(
            differences.len() * 100 < expected.len(),
            "{}",
            differences.len()
        );
    }

    #[test]
    fn padded_rows_are_cut_to_width() {
        // mono8 with 3 bytes of padding per row, and rgb8 with 2.
        let data: Vec<u8> = (0..3).flat_map(|y| [y, y + 10, y + 20, 0, 0, 0]).collect();
        let gray = convert(&image("mono8", 3, 3, 6, data)).unwrap();
        assert_eq!(gray, [0, 10, 20, 1, 11, 21, 2, 12, 22]);
        let row = [9, 9, 9, 200, 200, 200, 0, 0];
        let gray = convert(&image("rgb8", 2, 2, 8, [row, row].concat())).unwrap();
        assert_eq!(gray, [9, 200, 9, 200]);
    }

    #[test]
    fn packed_mono8_is_read_in_place() {
        let msg = image("mono8", 2, 2, 2, vec![1, 2, 3, 4]);
        let mut converter = Converter::default();
        let gray = converter.gray(&msg).unwrap();
        assert!(std::ptr::eq(gray.as_raw().as_ptr(), msg.data.as_ptr()));
    }

    #[test]
    fn mono16_is_stretched_in_either_byte_order() {
        // 12-bit values: 4095 is the brightest, 0 the darkest.
        let values = [0u16, 1024, 2048, 4095];
        let le: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        assert_eq!(
            convert(&image("mono16", 2, 2, 4, le)).unwrap(),
            [0, 64, 128, 255]
        );
        let be: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
        let mut msg = image("16UC1", 2, 2, 4, be);
        msg.is_bigendian = 1;
        assert_eq!(convert(&msg).unwrap(), [0, 64, 128, 255]);
    }

    #[test]
    fn yuv422_gives_its_luma_bytes() {
        // Two pixels: U Y0 V Y1 (UYVY) and Y0 U Y1 V (YUYV).
        let uyvy = convert(&image("yuv422", 2, 1, 4, vec![128, 10, 128, 200]));
        assert_eq!(uyvy.unwrap(), [10, 200]);
        let yuyv = convert(&image("yuyv", 2, 1, 4, vec![10, 128, 200, 128]));
        assert_eq!(yuyv.unwrap(), [10, 200]);
        let odd = convert(&image("uyvy", 3, 1, 6, vec![0; 6]));
        assert_eq!(odd.unwrap_err(), FrameError::OddWidth(3));
    }

    #[test]
    fn bad_messages_are_refused_with_their_cause() {
        let cases = [
            (image("mono8", 0, 4, 0, vec![]), "empty"),
            (image("mono8", 4, 0, 4, vec![]), "empty"),
            (
                image("bayer_rggb8", 2, 2, 2, vec![0; 4]),
                "encoding bayer_rggb8",
            ),
            (image("rgb8", 4, 2, 4, vec![0; 8]), "step rgb8"),
            (image("mono8", 4, 2, 4, vec![0; 7]), "data length"),
            (image("mono8", 4, 2, 4, vec![0; 9]), "data length"),
            // A step that overflows 32 bits times the height.
            (
                image("mono8", 4, u32::MAX, u32::MAX, vec![0; 4]),
                "data length",
            ),
        ];
        for (msg, cause) in cases {
            let err = convert(&msg).unwrap_err();
            assert_eq!(err.cause(), cause, "{err}");
            assert!(!err.to_string().is_empty());
        }
    }

    #[test]
    fn compressed_images_decode_and_garbage_is_refused() {
        let picture = image::DynamicImage::ImageRgb8(rgb_picture());
        let mut png = Vec::new();
        picture
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let mut converter = Converter::default();
        let msg = CompressedImage {
            header: Header::default(),
            format: "png".into(),
            data: png,
        };
        let gray = converter
            .gray_compressed(&msg, "/cam/image/compressed")
            .unwrap();
        assert_eq!(gray.as_raw(), crate::image_io::to_gray(picture).as_raw());
        let garbage = CompressedImage {
            data: vec![1, 2, 3, 4],
            ..msg.clone()
        };
        let err = converter
            .gray_compressed(&garbage, "/cam/image/compressed")
            .unwrap_err();
        assert_eq!(err.cause(), "undecodable");
        assert!(err.to_string().contains("/cam/image/compressed"), "{err}");
        let depth = CompressedImage {
            format: "16UC1; compressedDepth".into(),
            ..msg
        };
        assert_eq!(
            converter.gray_compressed(&depth, "t").unwrap_err().cause(),
            "encoding 16UC1; compressedDepth"
        );
    }

    #[test]
    fn a_small_message_declaring_a_huge_image_is_refused_before_decoding() {
        // A PNG header of 9000 x 9000 pixels (81 megapixels) and no pixels:
        // under the files' limit, over a stream frame's.
        let mut png = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut png, 9000, 9000);
            encoder.set_color(png::ColorType::Grayscale);
            let mut writer = encoder.write_header().unwrap();
            // The start of a zlib stream: the header is read up to here.
            writer
                .write_chunk(png::chunk::IDAT, &[0x78, 0x9c, 0x63, 0x00, 0x00])
                .unwrap();
            drop(writer);
        }
        assert!(png.len() < 100, "{}", png.len());
        let msg = CompressedImage {
            header: Header::default(),
            format: "png".into(),
            data: png,
        };
        let err = Converter::default()
            .gray_compressed(&msg, "/cam/image/compressed")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("image of 9000x9000 pixels is larger than the supported 16384 px a side and 64 megapixels"),
            "{err}"
        );
    }
}
