//! SVG output: the page in millimetres (width/height in mm, viewBox in mm),
//! marker discs as `<circle>`, ring runs as `<path>` arcs, labels as real text.

use super::page::{Anchor, Item, Page, MM_PER_PT};
use crate::geometry::{Marker, Shape};
use crate::units::trim_float;
use svg::node::element::{Circle, Group, Line, Path, Rectangle, Text, Title};
use svg::Document;

fn num(v: f64) -> String {
    trim_float(v)
}

fn grey_hex(grey: u8) -> String {
    match grey {
        0 => "#000".to_string(),
        255 => "#fff".to_string(),
        g => format!("#{g:02x}{g:02x}{g:02x}"),
    }
}

/// The page as an SVG document string.
pub fn page_svg(page: &Page, title: &str) -> String {
    let mut doc = Document::new()
        .set("width", format!("{}mm", num(page.width_mm)))
        .set("height", format!("{}mm", num(page.height_mm)))
        .set(
            "viewBox",
            format!("0 0 {} {}", num(page.width_mm), num(page.height_mm)),
        );
    if !title.is_empty() {
        doc = doc.add(Title::new(title));
    }
    doc = doc.add(
        Rectangle::new()
            .set("width", num(page.width_mm))
            .set("height", num(page.height_mm))
            .set("fill", "#fff"),
    );
    for item in &page.items {
        doc = match item {
            Item::Marker { marker, cx, cy } => doc.add(marker_group(marker, *cx, *cy)),
            Item::Rect {
                x,
                y,
                width,
                height,
                grey,
            } => doc.add(
                Rectangle::new()
                    .set("x", num(*x))
                    .set("y", num(*y))
                    .set("width", num(*width))
                    .set("height", num(*height))
                    .set("fill", grey_hex(*grey)),
            ),
            Item::Line {
                from,
                to,
                width,
                grey,
                dash,
            } => {
                let mut line = Line::new()
                    .set("x1", num(from.0))
                    .set("y1", num(from.1))
                    .set("x2", num(to.0))
                    .set("y2", num(to.1))
                    .set("stroke", grey_hex(*grey))
                    .set("stroke-width", num(*width));
                if let Some([on, off]) = dash {
                    line = line.set("stroke-dasharray", format!("{} {}", num(*on), num(*off)));
                }
                doc.add(line)
            }
            Item::CircleOutline {
                cx,
                cy,
                radius,
                width,
                grey,
                dash,
            } => {
                let mut circle = Circle::new()
                    .set("cx", num(*cx))
                    .set("cy", num(*cy))
                    .set("r", num(*radius))
                    .set("fill", "none")
                    .set("stroke", grey_hex(*grey))
                    .set("stroke-width", num(*width));
                if let Some([on, off]) = dash {
                    circle = circle.set("stroke-dasharray", format!("{} {}", num(*on), num(*off)));
                }
                doc.add(circle)
            }
            Item::Text {
                x,
                y,
                size_pt,
                anchor,
                grey,
                text,
            } => {
                let anchor = match anchor {
                    Anchor::Start => "start",
                    Anchor::Middle => "middle",
                    Anchor::End => "end",
                };
                doc.add(
                    Text::new(text.as_str())
                        .set("x", num(*x))
                        .set("y", num(*y))
                        .set("font-family", "Helvetica, Arial, sans-serif")
                        .set("font-size", num(size_pt * MM_PER_PT))
                        .set("text-anchor", anchor)
                        .set("fill", grey_hex(*grey)),
                )
            }
        };
    }
    let mut out = doc.to_string();
    out.push('\n');
    out
}

/// A marker as painted layers: discs as circles, ring runs as arc paths.
fn marker_group(marker: &Marker, cx: f64, cy: f64) -> Group {
    let r = marker.outer_radius();
    // A black run ending on the white disc's rim meets the black disc there;
    // renderers that paint layers in turn anti-alias both edges and leave a
    // faint light seam. Running the path a little into the black annulus
    // (black on black, the same marker) closes it.
    let seam_overlap = 0.02 * r;
    let mut group = Group::new();
    for shape in marker.shapes() {
        group = match shape {
            Shape::Disc { radius, black } => group.add(
                Circle::new()
                    .set("cx", num(cx))
                    .set("cy", num(cy))
                    .set("r", num(radius))
                    .set("fill", if black { "#000" } else { "#fff" }),
            ),
            Shape::Sector {
                inner,
                outer,
                start,
                end,
                black,
            } => group.add(
                Path::new()
                    .set(
                        "d",
                        sector_path(
                            cx,
                            cy,
                            inner,
                            if black && outer + seam_overlap < r {
                                outer + seam_overlap
                            } else {
                                outer
                            },
                            start,
                            end,
                        ),
                    )
                    .set("fill", if black { "#000" } else { "#fff" }),
            ),
        };
    }
    group
}

/// SVG path data of an annular sector. Page y points down, so growing marker
/// angle turns counter-clockwise on the page: SVG sweep flag 0.
fn sector_path(cx: f64, cy: f64, inner: f64, outer: f64, start: f64, end: f64) -> String {
    let at = |r: f64, a: f64| (cx + r * a.cos(), cy - r * a.sin());
    let large = if end - start > std::f64::consts::PI {
        1
    } else {
        0
    };
    let (x0, y0) = at(outer, start);
    let (x1, y1) = at(outer, end);
    let (x2, y2) = at(inner, end);
    let (x3, y3) = at(inner, start);
    format!(
        "M{} {}A{} {} 0 {large} 0 {} {}L{} {}A{} {} 0 {large} 1 {} {}Z",
        num(x0),
        num(y0),
        num(outer),
        num(outer),
        num(x1),
        num(y1),
        num(x2),
        num(y2),
        num(inner),
        num(inner),
        num(x3),
        num(y3)
    )
}
