//! Anti-aliased rasters of pages and markers (tiny-skia): the pixels behind
//! PNG output, the sheet self-check and the scene simulator.
//!
//! Pixel (i, j) covers page area [i, i+1) x [j, j+1) in pixel units, so the
//! page point (x mm, y mm) lies at pixel coordinates (x·s, y·s) with
//! s = dpi / 25.4, i.e. at (x·s − 0.5, y·s − 0.5) measured from the centre
//! of the top-left pixel.

use super::font;
use super::page::{marker_black_path, Anchor, Item, Page, Segment};
use super::RenderError;
use crate::geometry::Marker;
use image::GrayImage;
use tiny_skia::{
    FillRule, LineCap, LineJoin, Paint, PathBuilder, Pixmap, Stroke, StrokeDash, Transform,
};

/// Largest raster side we agree to allocate (a 2 m page at 1200 dpi).
const MAX_SIDE_PX: u32 = 100_000;
/// Largest raster area, in pixels (RGBA buffers four bytes each).
const MAX_AREA_PX: u64 = 300_000_000;

/// Pixels per millimetre at a resolution in dots per inch.
pub fn px_per_mm(dpi: f64) -> f64 {
    dpi / 25.4
}

/// Raster size in pixels of a page at a resolution.
pub fn page_size_px(page: &Page, dpi: f64) -> (u32, u32) {
    let s = px_per_mm(dpi);
    (
        (page.width_mm * s).round().max(1.0) as u32,
        (page.height_mm * s).round().max(1.0) as u32,
    )
}

/// Renders a page to an opaque RGBA pixmap at `dpi`.
pub fn page_pixmap(page: &Page, dpi: f64) -> Result<Pixmap, RenderError> {
    if !(dpi.is_finite() && dpi > 0.0) {
        return Err(RenderError::DpiOutOfRange { dpi });
    }
    let (w, h) = page_size_px(page, dpi);
    let too_large = || RenderError::RasterTooLarge {
        width_mm: page.width_mm,
        height_mm: page.height_mm,
        dpi,
        width: w,
        height: h,
    };
    if w > MAX_SIDE_PX || h > MAX_SIDE_PX || u64::from(w) * u64::from(h) > MAX_AREA_PX {
        return Err(too_large());
    }
    let mut pixmap = Pixmap::new(w, h).ok_or_else(too_large)?;
    pixmap.fill(tiny_skia::Color::WHITE);
    let s = px_per_mm(dpi) as f32;
    let transform = Transform::from_scale(s, s);
    for item in &page.items {
        draw_item(&mut pixmap, item, transform);
    }
    Ok(pixmap)
}

/// Renders a page to an 8-bit grey image at `dpi` (labels in the built-in
/// stroke font). This is what the sheet self-check and the simulator see.
pub fn render_page(page: &Page, dpi: f64) -> Result<GrayImage, RenderError> {
    let pixmap = page_pixmap(page, dpi)?;
    Ok(pixmap_to_gray(&pixmap))
}

/// Renders one marker, centred, with `margin_mm` of white around its black
/// disc, at `dpi`.
pub fn render_marker(marker: &Marker, margin_mm: f64, dpi: f64) -> Result<GrayImage, RenderError> {
    let side = marker.diameter_mm + 2.0 * margin_mm;
    let mut page = Page::new(side, side);
    page.push(Item::Marker {
        marker: *marker,
        cx: side / 2.0,
        cy: side / 2.0,
    });
    render_page(&page, dpi)
}

/// The grey channel of an opaque pixmap.
pub fn pixmap_to_gray(pixmap: &Pixmap) -> GrayImage {
    let data: Vec<u8> = pixmap.data().chunks_exact(4).map(|px| px[0]).collect();
    GrayImage::from_raw(pixmap.width(), pixmap.height(), data)
        .expect("pixmap buffer has width·height pixels")
}

fn paint(grey: u8) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color_rgba8(grey, grey, grey, 255);
    paint.anti_alias = true;
    paint
}

fn build_path(segments: &[Segment]) -> Option<tiny_skia::Path> {
    let mut pb = PathBuilder::new();
    for seg in segments {
        match *seg {
            Segment::MoveTo(x, y) => pb.move_to(x as f32, y as f32),
            Segment::LineTo(x, y) => pb.line_to(x as f32, y as f32),
            Segment::CubicTo(x1, y1, x2, y2, x, y) => pb.cubic_to(
                x1 as f32, y1 as f32, x2 as f32, y2 as f32, x as f32, y as f32,
            ),
            Segment::Close => pb.close(),
        }
    }
    pb.finish()
}

fn stroke(width: f64, dash: Option<[f64; 2]>, cap: LineCap) -> Stroke {
    Stroke {
        width: width as f32,
        line_cap: cap,
        line_join: LineJoin::Round,
        dash: dash.and_then(|[on, off]| StrokeDash::new(vec![on as f32, off as f32], 0.0)),
        ..Stroke::default()
    }
}

fn draw_item(pixmap: &mut Pixmap, item: &Item, transform: Transform) {
    match item {
        Item::Marker { marker, cx, cy } => {
            if let Some(path) = build_path(&marker_black_path(marker, *cx, *cy)) {
                pixmap.fill_path(&path, &paint(0), FillRule::Winding, transform, None);
            }
        }
        Item::Rect {
            x,
            y,
            width,
            height,
            grey,
        } => {
            if let Some(rect) =
                tiny_skia::Rect::from_xywh(*x as f32, *y as f32, *width as f32, *height as f32)
            {
                pixmap.fill_rect(rect, &paint(*grey), transform, None);
            }
        }
        Item::Line {
            from,
            to,
            width,
            grey,
            dash,
        } => {
            let segs = [Segment::MoveTo(from.0, from.1), Segment::LineTo(to.0, to.1)];
            if let Some(path) = build_path(&segs) {
                let stroke = stroke(*width, *dash, LineCap::Butt);
                pixmap.stroke_path(&path, &paint(*grey), &stroke, transform, None);
            }
        }
        Item::CircleOutline {
            cx,
            cy,
            radius,
            width,
            grey,
            dash,
        } => {
            let mut segs = Vec::new();
            // Clockwise on the page from angle 0, as SVG strokes circles, so dashes agree.
            super::page::circle_segments(*cx, *cy, *radius, false, &mut segs);
            if let Some(path) = build_path(&segs) {
                let stroke = stroke(*width, *dash, LineCap::Butt);
                pixmap.stroke_path(&path, &paint(*grey), &stroke, transform, None);
            }
        }
        Item::Text {
            x,
            y,
            size_pt,
            anchor,
            grey,
            text,
        } => draw_text(pixmap, text, *x, *y, *size_pt, *anchor, *grey, transform),
    }
}

#[allow(clippy::too_many_arguments)]
fn draw_text(
    pixmap: &mut Pixmap,
    text: &str,
    x: f64,
    y: f64,
    size_pt: f64,
    anchor: Anchor,
    grey: u8,
    transform: Transform,
) {
    let segs = font::stroke_text(text, x, y, size_pt, anchor);
    if let Some(path) = build_path(&segs) {
        let stroke = stroke(font::stroke_pen_mm(size_pt), None, LineCap::Round);
        pixmap.stroke_path(&path, &paint(grey), &stroke, transform, None);
    }
}
