//! Print sheets: many labelled markers packed onto template pages, each page
//! with a scale check bar, plus the manifest recording where each marker is.

mod footer;
mod packing;

use super::font::CAP_HEIGHT;
use super::marker::{cut_circle, marker_label, LABEL_GAP_MM};
use super::page::{Anchor, Item, Page, MM_PER_PT};
use super::template::Template;
use super::RenderError;
use crate::family::{check_id_list, Family, MAX_LISTED_IDS};
use crate::geometry::Marker;
use crate::manifest::{FamilyRef, Manifest, PrintedMarker};
use crate::spec_error::SpecError;
use crate::units::trim_float;
use footer::push_footer;
use packing::{best_packing, layout_area, Cell};

/// One marker to place on a sheet.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetMarker {
    /// The marker's shape and size.
    pub marker: Marker,
    /// Family ID (0 for a legacy WhyCon circle).
    pub id: u32,
    /// Ring code (0 for a legacy WhyCon circle).
    pub code: u32,
    /// Label lines: the one-line form and a two-line fallback for narrow cells.
    pub label: String,
    /// The label in two lines, for cells too narrow for `label`.
    pub label_lines: [String; 2],
}

/// What to print and how.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetSpec {
    /// The markers, in print order.
    pub markers: Vec<SheetMarker>,
    /// Page size, margins and decorations.
    pub template: Template,
    /// Name printed in each page's footer (usually the output file's stem).
    pub name: String,
    /// The family, recorded in the manifest so the IDs can be checked later.
    pub family: Option<FamilyRef>,
    /// True for legacy WhyCon circles.
    pub legacy: bool,
}

/// A laid-out sheet: its pages and the record of what is where.
#[derive(Debug, Clone, PartialEq)]
pub struct Sheet {
    /// The pages, ready to encode.
    pub pages: Vec<Page>,
    /// What was printed where.
    pub manifest: Manifest,
}

/// Markers of a family for a list of IDs; an ID outside the family is an
/// error naming the valid range.
pub fn family_markers(
    family: &Family,
    ids: &[u32],
    diameter_mm: f64,
) -> Result<Vec<SheetMarker>, RenderError> {
    ids.iter()
        .map(|&id| {
            let Some(code) = family.code(id) else {
                return Err(id_range_error(family, id));
            };
            let marker = Marker::whycode(family.bits(), code, diameter_mm);
            let size = format!("{} mm", trim_float((diameter_mm * 10.0).round() / 10.0));
            Ok(SheetMarker {
                marker,
                id,
                code,
                label: marker_label(&marker, Some(id), Some(family.distance())),
                label_lines: [
                    format!("ID {id}"),
                    format!("{}b d{} · {size}", family.bits(), family.distance()),
                ],
            })
        })
        .collect()
}

/// The error for an ID that is not in a family, naming the IDs it has.
pub fn id_range_error(family: &Family, id: u32) -> RenderError {
    RenderError::IdOutOfRange {
        id,
        bits: family.bits(),
        distance: family.distance(),
        count: family.len(),
    }
}

/// `count` legacy WhyCon circles.
pub fn legacy_markers(count: usize, diameter_mm: f64) -> Vec<SheetMarker> {
    let marker = Marker::whycon(diameter_mm);
    let label = marker_label(&marker, None, None);
    let size = format!("{} mm", trim_float((diameter_mm * 10.0).round() / 10.0));
    (0..count)
        .map(|_| SheetMarker {
            marker,
            id: 0,
            code: 0,
            label: label.clone(),
            label_lines: ["WhyCon".to_string(), size.clone()],
        })
        .collect()
}

/// The markers a sheet prints and the family its manifest names: `count`
/// WhyCon circles when there is no family, else the family's members `ids`
/// (every member when none are chosen and there are few enough to print).
pub fn chosen_markers(
    family: Option<&Family>,
    ids: Option<Vec<u32>>,
    count: Option<usize>,
    diameter_mm: f64,
) -> Result<(Vec<SheetMarker>, Option<FamilyRef>), SpecError> {
    let Some(family) = family else {
        let count = count.unwrap_or(0);
        if count == 0 || count > MAX_LISTED_IDS {
            return Err(SpecError::invalid(
                "count",
                format!("must be between 1 and {MAX_LISTED_IDS}, got {count}"),
            ));
        }
        return Ok((legacy_markers(count, diameter_mm), None));
    };
    let (bits, distance) = (family.bits(), family.distance());
    let ids = match ids {
        Some(ids) => {
            check_id_list(&ids).map_err(|e| SpecError::invalid("ids", e.to_string()))?;
            ids
        }
        None if family.len() > MAX_LISTED_IDS => {
            return Err(SpecError::invalid(
                "ids",
                format!(
                    "the {bits}-bit family with distance {distance} has {} IDs, too many to print at once; choose some (at most {MAX_LISTED_IDS})",
                    family.len(),
                ),
            ))
        }
        None => (1..=family.len() as u32).collect(),
    };
    let markers = family_markers(family, &ids, diameter_mm)
        .map_err(|e| SpecError::invalid("ids", e.to_string()))?;
    Ok((markers, Some(FamilyRef { bits, distance })))
}

/// Leading between label lines, as a multiple of the font size.
pub(super) const LINE_SPACING: f64 = 1.2;
/// Depth below the baseline kept for descenders, as a multiple of the font size.
pub(super) const DESCENT: f64 = 0.25;

/// The sheet a manifest records, laid out again: for showing the printed
/// page as it was (labels, scale bar, caption) where only the manifest is at
/// hand. `None` unless the template is a built-in one and every marker
/// lands exactly where the manifest says, so it never shows another page.
pub fn relayout(manifest: &Manifest, name: &str) -> Option<Sheet> {
    let template = Template::builtin(&manifest.template).ok()?;
    let diameter = manifest.markers.first()?.diameter_mm;
    let markers = if manifest.legacy {
        legacy_markers(manifest.markers.len(), diameter)
    } else {
        let f = manifest.family?;
        let family = Family::generate(f.bits, f.distance).ok()?;
        let ids: Vec<u32> = manifest.markers.iter().map(|m| m.id).collect();
        family_markers(&family, &ids, diameter).ok()?
    };
    let sheet = layout(&SheetSpec {
        markers,
        template,
        name: name.to_string(),
        family: manifest.family,
        legacy: manifest.legacy,
    })
    .ok()?;
    let same_place = |a: &PrintedMarker, b: &PrintedMarker| {
        a.id == b.id
            && a.page == b.page
            && (a.x_mm - b.x_mm).abs() < 1e-3
            && (a.y_mm - b.y_mm).abs() < 1e-3
            && (a.diameter_mm - b.diameter_mm).abs() < 1e-3
    };
    let faithful = sheet.manifest.markers.len() == manifest.markers.len()
        && sheet
            .manifest
            .markers
            .iter()
            .zip(&manifest.markers)
            .all(|(a, b)| same_place(a, b));
    faithful.then_some(sheet)
}

/// The largest marker diameter (to 0.1 mm) of which one fits on a page.
pub fn largest_fitting_diameter(markers: &[SheetMarker], template: &Template) -> f64 {
    let fits = |d: f64| {
        let resized: Vec<SheetMarker> = markers
            .iter()
            .take(1)
            .map(|m| SheetMarker {
                marker: Marker {
                    diameter_mm: d,
                    ..m.marker
                },
                ..m.clone()
            })
            .collect();
        !best_packing(&resized, d, template).1.centres.is_empty()
    };
    let (mut lo, mut hi) = (0.0, template.page_width_mm.max(template.page_height_mm));
    for _ in 0..60 {
        let mid = (lo + hi) / 2.0;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo * 10.0).floor() / 10.0
}

/// Lays the markers out on as many pages as they need.
pub fn layout(spec: &SheetSpec) -> Result<Sheet, RenderError> {
    let template = &spec.template;
    if spec.markers.is_empty() {
        return Err(RenderError::NoMarkers);
    }
    let diameter = spec.markers[0].marker.diameter_mm;
    if spec
        .markers
        .iter()
        .any(|m| (m.marker.diameter_mm - diameter).abs() > 1e-9)
    {
        return Err(RenderError::MixedDiameters);
    }
    let (cell, packing) = best_packing(&spec.markers, diameter, template);
    if packing.centres.is_empty() {
        let largest = largest_fitting_diameter(&spec.markers, template);
        return Err(RenderError::DoesNotFit {
            diameter_mm: diameter,
            template: template.name.clone(),
            page_width_mm: template.page_width_mm,
            page_height_mm: template.page_height_mm,
            margin_mm: template.margin_mm,
            largest_mm: largest,
        });
    }
    let (left, top, _, _) = layout_area(template);
    let per_page = packing.centres.len();
    let page_count = spec.markers.len().div_ceil(per_page);
    let mut pages = Vec::with_capacity(page_count);
    let mut printed = Vec::with_capacity(spec.markers.len());
    for (k, chunk) in spec.markers.chunks(per_page).enumerate() {
        let mut page = Page::new(template.page_width_mm, template.page_height_mm);
        for (m, &(x, y)) in chunk.iter().zip(&packing.centres) {
            let (cx, cy) = (left + x, top + y);
            page.push(Item::Marker {
                marker: m.marker,
                cx,
                cy,
            });
            if template.cut_guides {
                page.push(cut_circle(cx, cy, cell.footprint));
            }
            push_label(&mut page, m, &cell, cx, cy);
            printed.push(PrintedMarker {
                id: m.id,
                code: m.code,
                page: k as u32 + 1,
                x_mm: round_um(cx),
                y_mm: round_um(cy),
                diameter_mm: m.marker.diameter_mm,
            });
        }
        push_footer(&mut page, template, &spec.name, k + 1, page_count);
        pages.push(page);
    }
    let manifest = Manifest {
        format: "whycode-sheet".to_string(),
        version: crate::manifest::MANIFEST_VERSION,
        tool: format!("whycode {}", env!("CARGO_PKG_VERSION")),
        family: spec.family,
        legacy: spec.legacy,
        template: template.name.clone(),
        page_size_mm: [template.page_width_mm, template.page_height_mm],
        pages: page_count as u32,
        files: Vec::new(),
        markers: printed,
    };
    Ok(Sheet { pages, manifest })
}

fn round_um(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

fn push_label(page: &mut Page, m: &SheetMarker, cell: &Cell, cx: f64, cy: f64) {
    let s = cell.label_pt * MM_PER_PT;
    let first_baseline = cy + cell.footprint + LABEL_GAP_MM + CAP_HEIGHT * s;
    let lines: Vec<&str> = if cell.two_lines {
        m.label_lines.iter().map(String::as_str).collect()
    } else {
        vec![m.label.as_str()]
    };
    for (i, line) in lines.into_iter().enumerate() {
        page.push(Item::Text {
            x: cx,
            y: first_baseline + i as f64 * LINE_SPACING * s,
            size_pt: cell.label_pt,
            anchor: Anchor::Middle,
            grey: 0,
            text: line.to_string(),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::packing::point_rect_distance;
    use super::*;
    use crate::render::font::helvetica_width_mm;

    fn spec(ids: std::ops::RangeInclusive<u32>, d: f64, template: &str) -> SheetSpec {
        let family = Family::generate(8, 2).unwrap();
        let ids: Vec<u32> = ids.collect();
        SheetSpec {
            markers: family_markers(&family, &ids, d).unwrap(),
            template: Template::builtin(template).unwrap(),
            name: "test".into(),
            family: Some(FamilyRef {
                bits: 8,
                distance: 2,
            }),
            legacy: false,
        }
    }

    #[test]
    fn footprints_and_labels_never_overlap() {
        for d in [8.0, 12.0, 15.0, 25.0, 30.0, 40.0, 63.0, 90.0] {
            let sheet = layout(&spec(1..=16, d, "a4")).unwrap();
            let f = d / 2.0 * 1.3;
            for page in &sheet.pages {
                let centres: Vec<(f64, f64)> = page.markers().map(|(_, x, y)| (x, y)).collect();
                for (i, a) in centres.iter().enumerate() {
                    assert!(a.0 - f >= 10.0 - 1e-9 && a.0 + f <= 200.0 + 1e-9, "d={d}");
                    assert!(a.1 - f >= 10.0 - 1e-9, "d={d}");
                    for b in &centres[i + 1..] {
                        let dist = (a.0 - b.0).hypot(a.1 - b.1);
                        assert!(dist >= 2.0 * f + 3.0 - 1e-6, "d={d} dist={dist}");
                    }
                }
                // Every text box stays on the page inside the margins and
                // clear of every marker's white margin.
                for item in &page.items {
                    let Item::Text {
                        x,
                        y,
                        size_pt,
                        anchor,
                        text,
                        ..
                    } = item
                    else {
                        continue;
                    };
                    let w = helvetica_width_mm(text, *size_pt);
                    let left = match anchor {
                        Anchor::Start => *x,
                        Anchor::Middle => x - w / 2.0,
                        Anchor::End => x - w,
                    };
                    let s = size_pt * MM_PER_PT;
                    let (top, bottom) = (y - CAP_HEIGHT * s, y + DESCENT * s);
                    assert!(left >= 10.0 - 1e-9 && left + w <= 200.0 + 1e-9, "{text}");
                    assert!(top >= 10.0 && bottom <= 287.0, "{text}");
                    for c in &centres {
                        let clear = point_rect_distance(c.0, c.1, left, left + w, top, bottom);
                        assert!(clear >= f + 0.5, "d={d}: '{text}' {clear} from a marker");
                    }
                }
            }
        }
    }

    #[test]
    fn ids_outside_the_family_name_the_range() {
        let family = Family::generate(8, 2).unwrap();
        let err = family_markers(&family, &[40], 40.0)
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "ID 40 is not in the 8-bit distance-2 family (IDs 1-16)"
        );
    }

    #[test]
    fn too_large_markers_name_the_largest_that_fits() {
        let err = layout(&spec(1..=1, 300.0, "a4")).unwrap_err().to_string();
        assert!(err.contains("the largest that fits is"), "{err}");
        let largest: f64 = err.rsplit(' ').nth(1).unwrap().parse().unwrap();
        assert!(layout(&spec(1..=1, largest, "a4")).is_ok());
        assert!(layout(&spec(1..=1, largest + 0.2, "a4")).is_err());
    }

    #[test]
    fn a_manifest_is_laid_out_again_exactly_or_not_at_all() {
        let spec = spec(1..=16, 60.0, "a5");
        let sheet = layout(&spec).unwrap();
        let again = relayout(&sheet.manifest, &spec.name).expect("a built-in layout reproduces");
        assert_eq!(again.pages, sheet.pages);
        let mut moved = sheet.manifest.clone();
        moved.markers[3].x_mm += 0.5;
        assert!(relayout(&moved, &spec.name).is_none());
        let mut custom = sheet.manifest.clone();
        custom.template = "my-layout.toml".into();
        assert!(relayout(&custom, &spec.name).is_none());
    }

    #[test]
    fn overflow_continues_on_new_pages() {
        let sheet = layout(&spec(1..=16, 60.0, "a5")).unwrap();
        assert!(sheet.pages.len() > 1);
        assert_eq!(sheet.manifest.markers.len(), 16);
        assert_eq!(sheet.manifest.pages as usize, sheet.pages.len());
    }
}
