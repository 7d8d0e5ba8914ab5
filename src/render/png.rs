//! PNG output: anti-aliased 8-bit grey images with the resolution recorded
//! in the pHYs chunk, so that image viewers and print dialogs know the
//! physical size.

use super::marker::{marker_page, MarkerOptions};
use super::page::Page;
use super::raster;
use super::RenderError;
use crate::geometry::Marker;
use image::GrayImage;

/// Encodes a grey image as PNG bytes with `dpi` recorded in pHYs.
pub fn encode_gray(image: &GrayImage, dpi: f64) -> Result<Vec<u8>, RenderError> {
    let failed = |e: png::EncodingError| RenderError::Encode {
        format: "PNG",
        detail: e.to_string(),
    };
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, image.width(), image.height());
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        let per_metre = (dpi / 0.0254).round() as u32;
        encoder.set_pixel_dims(Some(png::PixelDimensions {
            xppu: per_metre,
            yppu: per_metre,
            unit: png::Unit::Meter,
        }));
        let mut writer = encoder.write_header().map_err(failed)?;
        writer.write_image_data(image.as_raw()).map_err(failed)?;
        writer.finish().map_err(failed)?;
    }
    Ok(bytes)
}

/// A page as PNG bytes at `dpi`.
pub fn page_png(page: &Page, dpi: f64) -> Result<Vec<u8>, RenderError> {
    encode_gray(&raster::render_page(page, dpi)?, dpi)
}

/// One marker as PNG bytes at `dpi`, laid out like `whycode marker` does.
pub fn marker_png(
    marker: &Marker,
    options: &MarkerOptions,
    dpi: f64,
) -> Result<Vec<u8>, RenderError> {
    page_png(&marker_page(marker, options)?, dpi)
}
