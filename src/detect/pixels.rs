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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_bit_data_is_stretched_to_the_brightest_value() {
        let wide = image::ImageBuffer::from_raw(4, 1, vec![0u16, 1, 511, 1023]).unwrap();
        assert_eq!(stretched_to_8_bits(wide).into_raw(), [0, 0, 127, 255]);
    }
}
