//! PDF output: real vector paths (circles as four cubic Bezier arcs, ring
//! runs as Bezier arc segments of at most 90°, all of a marker's black in
//! one nonzero-filled path), labels in the built-in Helvetica, no rasters.
//! Same pages give the same bytes: dates are fixed and the document ID is a
//! hash of the content.

use super::page::{circle_segments, marker_black_path, Anchor, Item, Page, Segment, MM_PER_PT};
use super::RenderError;
use printpdf::{
    BuiltinFont, Color, Greyscale, Line, LineCapStyle, LineDashPattern, LinePoint, Mm, Op,
    PaintMode, PdfDocument, PdfFontHandle, PdfPage, PdfSaveOptions, Point, Polygon, PolygonRing,
    Pt, TextItem, WindingOrder,
};

/// Converts page millimetres (origin top-left, y down) to PDF points
/// (origin bottom-left, y up), rounded to 0.01 pt (3.5 µm) to keep files small.
struct Frame {
    height_mm: f64,
}

impl Frame {
    fn point(&self, x: f64, y: f64) -> Point {
        let to_pt = |mm: f64| ((mm / MM_PER_PT) * 100.0).round() / 100.0;
        Point {
            x: Pt(to_pt(x) as f32),
            y: Pt(to_pt(self.height_mm - y) as f32),
        }
    }

    /// Path segments as PDF rings (one per subpath).
    fn rings(&self, segments: &[Segment]) -> Vec<PolygonRing> {
        let mut rings = Vec::new();
        let mut points: Vec<LinePoint> = Vec::new();
        let plain = |p| LinePoint { p, bezier: false };
        for seg in segments {
            match *seg {
                Segment::MoveTo(x, y) => {
                    if !points.is_empty() {
                        rings.push(PolygonRing {
                            points: std::mem::take(&mut points),
                        });
                    }
                    points.push(plain(self.point(x, y)));
                }
                Segment::LineTo(x, y) => points.push(plain(self.point(x, y))),
                Segment::CubicTo(x1, y1, x2, y2, x, y) => {
                    points.push(LinePoint {
                        p: self.point(x1, y1),
                        bezier: true,
                    });
                    points.push(LinePoint {
                        p: self.point(x2, y2),
                        bezier: true,
                    });
                    points.push(plain(self.point(x, y)));
                }
                Segment::Close => {}
            }
        }
        if !points.is_empty() {
            rings.push(PolygonRing { points });
        }
        rings
    }
}

fn grey(level: u8) -> Color {
    Color::Greyscale(Greyscale {
        percent: f32::from(level) / 255.0,
        icc_profile: None,
    })
}

fn page_ops(page: &Page) -> Vec<Op> {
    let frame = Frame {
        height_mm: page.height_mm,
    };
    let mut ops = Vec::new();
    for item in &page.items {
        match item {
            Item::Marker { marker, cx, cy } => {
                ops.push(Op::SetFillColor { col: grey(0) });
                ops.push(Op::DrawPolygon {
                    polygon: Polygon {
                        rings: frame.rings(&marker_black_path(marker, *cx, *cy)),
                        mode: PaintMode::Fill,
                        winding_order: WindingOrder::NonZero,
                    },
                });
            }
            Item::Rect {
                x,
                y,
                width,
                height,
                grey: level,
            } => {
                let corners = [
                    Segment::MoveTo(*x, *y),
                    Segment::LineTo(x + width, *y),
                    Segment::LineTo(x + width, y + height),
                    Segment::LineTo(*x, y + height),
                    Segment::Close,
                ];
                ops.push(Op::SetFillColor { col: grey(*level) });
                ops.push(Op::DrawPolygon {
                    polygon: Polygon {
                        rings: frame.rings(&corners),
                        mode: PaintMode::Fill,
                        winding_order: WindingOrder::NonZero,
                    },
                });
            }
            Item::Line {
                from,
                to,
                width,
                grey: level,
                dash,
            } => {
                let segs = [Segment::MoveTo(from.0, from.1), Segment::LineTo(to.0, to.1)];
                stroke_ops(&mut ops, &frame, &segs, false, *width, *level, *dash);
            }
            Item::CircleOutline {
                cx,
                cy,
                radius,
                width,
                grey: level,
                dash,
            } => {
                let mut segs = Vec::new();
                // Clockwise on the page from angle 0, as SVG strokes circles, so dashes agree.
                circle_segments(*cx, *cy, *radius, false, &mut segs);
                stroke_ops(&mut ops, &frame, &segs, true, *width, *level, *dash);
            }
            Item::Text {
                x,
                y,
                size_pt,
                anchor,
                grey: level,
                text,
            } => {
                let width = super::font::helvetica_width_mm(text, *size_pt);
                let left = match anchor {
                    Anchor::Start => *x,
                    Anchor::Middle => x - width / 2.0,
                    Anchor::End => x - width,
                };
                ops.push(Op::SetFillColor { col: grey(*level) });
                ops.push(Op::StartTextSection);
                ops.push(Op::SetFont {
                    font: PdfFontHandle::Builtin(BuiltinFont::Helvetica),
                    size: Pt(*size_pt as f32),
                });
                ops.push(Op::SetTextCursor {
                    pos: frame.point(left, *y),
                });
                ops.push(Op::ShowText {
                    items: vec![TextItem::Text(text.clone())],
                });
                ops.push(Op::EndTextSection);
            }
        }
    }
    ops
}

fn stroke_ops(
    ops: &mut Vec<Op>,
    frame: &Frame,
    segs: &[Segment],
    closed: bool,
    width_mm: f64,
    level: u8,
    dash: Option<[f64; 2]>,
) {
    let to_pt = |mm: f64| (mm / MM_PER_PT) as f32;
    ops.push(Op::SaveGraphicsState);
    ops.push(Op::SetOutlineColor { col: grey(level) });
    ops.push(Op::SetOutlineThickness {
        pt: Pt(to_pt(width_mm)),
    });
    ops.push(Op::SetLineCapStyle {
        cap: LineCapStyle::Butt,
    });
    if let Some([on, off]) = dash {
        ops.push(Op::SetLineDashPattern {
            dash: LineDashPattern::new(0.0, &[to_pt(on), to_pt(off)]),
        });
    }
    let points = frame
        .rings(segs)
        .into_iter()
        .flat_map(|ring| ring.points)
        .collect();
    ops.push(Op::DrawLine {
        line: Line {
            points,
            is_closed: closed,
        },
    });
    ops.push(Op::RestoreGraphicsState);
}

/// FNV-1a, for a content-derived document ID that is stable across runs.
fn fnv1a(bytes: &[u8], seed: u64) -> u64 {
    bytes.iter().fold(seed, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The pages as one PDF document.
pub fn pages_pdf(pages: &[Page], title: &str) -> Result<Vec<u8>, RenderError> {
    let mut doc = PdfDocument::new(title);
    doc.metadata.info.producer = format!("whycode {}", env!("CARGO_PKG_VERSION"));
    doc.metadata.info.creator = doc.metadata.info.producer.clone();
    let pdf_pages: Vec<PdfPage> = pages
        .iter()
        .map(|page| {
            PdfPage::new(
                Mm(page.width_mm as f32),
                Mm(page.height_mm as f32),
                page_ops(page),
            )
        })
        .collect();
    doc.with_pages(pdf_pages);
    let mut warnings = Vec::new();
    let mut lo = doc.to_lopdf_document(&PdfSaveOptions::default(), &mut warnings);
    // printpdf draws the trailer ID from a process-wide counter, which
    // differs from one document to the next; derive it from the content.
    let content = format!("{title}\u{0}{pages:?}");
    let id = format!(
        "{:016x}{:016x}",
        fnv1a(content.as_bytes(), 0xcbf2_9ce4_8422_2325),
        fnv1a(content.as_bytes(), 0x6c62_272e_07bb_0142)
    );
    let id_string = || lopdf::Object::String(id.clone().into_bytes(), lopdf::StringFormat::Literal);
    lo.trailer
        .set("ID", lopdf::Object::Array(vec![id_string(), id_string()]));
    strip_info_noise(&mut lo);
    lo.compress();
    let mut bytes = Vec::new();
    lo.save_to(&mut bytes).map_err(|e| RenderError::Encode {
        format: "PDF",
        detail: e.to_string(),
    })?;
    Ok(bytes)
}

/// printpdf fills the Info dictionary with an empty PDF/X version (viewers
/// then claim PDF/X conformance, which these files, with fonts not
/// embedded, do not have), 1970 dates (a real date would break same inputs,
/// same bytes) and empty fields. Only what is true is kept.
fn strip_info_noise(doc: &mut lopdf::Document) {
    let Ok(info) = doc.trailer.get(b"Info").and_then(|o| o.as_reference()) else {
        return;
    };
    let Ok(dict) = doc.get_object_mut(info).and_then(|o| o.as_dict_mut()) else {
        return;
    };
    for key in [
        &b"GTS_PDFXVersion"[..],
        b"GTS_PDFXConformance",
        b"Trapped",
        b"CreationDate",
        b"ModDate",
    ] {
        dict.remove(key);
    }
    let empty: Vec<Vec<u8>> = dict
        .iter()
        .filter(|(_, value)| matches!(value, lopdf::Object::String(text, _) if text.is_empty()))
        .map(|(key, _)| key.clone())
        .collect();
    for key in empty {
        dict.remove(&key);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Marker;

    #[test]
    fn documents_are_byte_identical_within_one_process() {
        let mut page = Page::new(60.0, 60.0);
        page.push(Item::Marker {
            marker: Marker::whycode(8, 19, 40.0),
            cx: 30.0,
            cy: 30.0,
        });
        let first = pages_pdf(std::slice::from_ref(&page), "t").unwrap();
        let second = pages_pdf(std::slice::from_ref(&page), "t").unwrap();
        assert!(first == second);
        assert!(first.starts_with(b"%PDF-"));
    }

    #[test]
    fn info_claims_no_pdfx_and_no_made_up_dates() {
        let page = Page::new(60.0, 60.0);
        let bytes = pages_pdf(std::slice::from_ref(&page), "t").unwrap();
        let doc = lopdf::Document::load_mem(&bytes).unwrap();
        let info = doc.trailer.get(b"Info").unwrap().as_reference().unwrap();
        let dict = doc.get_dictionary(info).unwrap();
        for key in ["GTS_PDFXVersion", "CreationDate", "ModDate", "Author"] {
            assert!(!dict.has(key.as_bytes()), "Info still has {key}");
        }
        assert!(dict.has(b"Producer"));
    }
}
