//! Turning decoded pixels of any layout into the 8-bit grey the detector
//! reads. [`load_gray`](super::load_gray) and the bindings (numpy arrays)
//! both come through here, so a frame gives the same grey levels, and so
//! the same detections, whether it was read from a file or handed over.

use image::{DynamicImage, GrayImage};

/// 8-bit grey of a decoded image: 8-bit grey as it is, colour by the
/// `image` crate's luma weights (alpha ignored), 16-bit data stretched so
/// the brightest value present becomes 255.
pub fn to_gray(decoded: DynamicImage) -> GrayImage {
    match decoded {
        DynamicImage::ImageLuma8(g) => g,
        DynamicImage::ImageLuma16(_)
        | DynamicImage::ImageLumaA16(_)
        | DynamicImage::ImageRgb16(_)
        | DynamicImage::ImageRgba16(_) => stretched_to_8_bits(decoded.into_luma16()),
        other => other.into_luma8(),
    }
}

/// Many cameras write 10- or 12-bit data into 16-bit files, which a plain
/// division by 257 squeezes into a handful of grey levels. The brightest
/// value present becomes 255 instead (the detector's thresholds are local,
/// so a linear stretch changes nothing else).
pub fn stretched_to_8_bits(wide: image::ImageBuffer<image::Luma<u16>, Vec<u16>>) -> GrayImage {
    let brightest = wide.pixels().map(|p| p.0[0]).max().unwrap_or(0).max(1);
    let scale = 255.0 / f64::from(brightest);
    GrayImage::from_fn(wide.width(), wide.height(), |x, y| {
        image::Luma([(f64::from(wide.get_pixel(x, y).0[0]) * scale).round() as u8])
    })
}
