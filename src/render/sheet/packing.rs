//! Packing marker cells onto a page: a cell is a marker's footprint plus its
//! label, packed in a grid or in hexagonal rows, whichever fits more.

use super::footer::FOOTER_MM;
use super::{SheetMarker, DESCENT, LINE_SPACING};
use crate::geometry::MIN_MARGIN_RATIO;
use crate::render::font::{helvetica_width_mm, CAP_HEIGHT};
use crate::render::marker::{CUT_CLEARANCE_MM, LABEL_GAP_MM, MIN_LABEL_PT};
use crate::render::page::MM_PER_PT;
use crate::render::template::Template;

/// The geometry of one marker cell: footprint and label block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Cell {
    /// Radius of black disc plus white margin, plus the clearance outside
    /// it when a cut guide runs around the marker.
    pub(super) footprint: f64,
    pub(super) label_pt: f64,
    pub(super) two_lines: bool,
    pub(super) label_width: f64,
    /// From the top of the footprint circle to the bottom of the label.
    pub(super) height: f64,
    /// Horizontal pitch (cell width plus gap).
    pub(super) pitch_x: f64,
}

impl Cell {
    pub(super) fn label_height(&self) -> f64 {
        let s = self.label_pt * MM_PER_PT;
        let lines = if self.two_lines { 2.0 } else { 1.0 };
        (lines - 1.0) * LINE_SPACING * s + (CAP_HEIGHT + DESCENT) * s
    }
}

fn cell_for(markers: &[SheetMarker], diameter_mm: f64, template: &Template) -> Cell {
    let clearance = if template.cut_guides {
        CUT_CLEARANCE_MM
    } else {
        0.0
    };
    let footprint = diameter_mm / 2.0 * (1.0 + MIN_MARGIN_RATIO) + clearance;
    let room = 2.0 * footprint + template.gap_mm;
    let widest = |f: &dyn Fn(&SheetMarker) -> f64| markers.iter().map(f).fold(0.0, f64::max);
    let wanted = template.label_size_pt;
    let one_line = widest(&|m| helvetica_width_mm(&m.label, wanted));
    let (two_lines, label_pt, label_width) = if one_line <= room {
        (false, wanted, one_line)
    } else {
        let two = widest(&|m| {
            m.label_lines
                .iter()
                .map(|l| helvetica_width_mm(l, wanted))
                .fold(0.0, f64::max)
        });
        let size = if two <= room {
            wanted
        } else {
            (wanted * room / two).max(MIN_LABEL_PT)
        };
        (true, size, two * size / wanted)
    };
    let mut cell = Cell {
        footprint,
        label_pt,
        two_lines,
        label_width,
        height: 0.0,
        pitch_x: (2.0 * footprint).max(label_width) + template.gap_mm,
    };
    cell.height = 2.0 * footprint + LABEL_GAP_MM + cell.label_height();
    cell
}

/// Where markers go on a page: centres relative to the layout area's
/// top-left corner.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Packing {
    pub(super) centres: Vec<(f64, f64)>,
}

fn grid_packing(cell: &Cell, width: f64, height: f64, gap: f64) -> Packing {
    let cols = ((width + gap) / cell.pitch_x + 1e-9).floor() as usize;
    let pitch_y = cell.height + gap;
    let rows = ((height + gap) / pitch_y + 1e-9).floor() as usize;
    let block = cols as f64 * cell.pitch_x - gap;
    let x0 = (width - block) / 2.0 + (cell.pitch_x - gap) / 2.0;
    let y0 = (height - (rows as f64 * pitch_y - gap)) / 2.0;
    let mut centres = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            centres.push((
                x0 + c as f64 * cell.pitch_x,
                y0 + cell.footprint + r as f64 * pitch_y,
            ));
        }
    }
    Packing { centres }
}

/// Distance from point (px, py) to the rectangle [x0, x1] x [y0, y1].
pub(super) fn point_rect_distance(px: f64, py: f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let dx = (x0 - px).max(px - x1).max(0.0);
    let dy = (y0 - py).max(py - y1).max(0.0);
    dx.hypot(dy)
}

/// The least row pitch at which rows shifted by half a column keep every
/// footprint and label clear of their neighbours by `gap`.
fn hex_row_pitch(cell: &Cell, gap: f64) -> f64 {
    let dx = cell.pitch_x / 2.0;
    let f = cell.footprint;
    let half_label = cell.label_width / 2.0;
    let label_top = f + LABEL_GAP_MM;
    let label_bottom = f + LABEL_GAP_MM + cell.label_height();
    let fits = |p: f64| {
        // Footprints of diagonal neighbours.
        dx.hypot(p) >= 2.0 * f + gap
            // The upper marker's label against the lower neighbour's footprint.
            && point_rect_distance(dx, p, -half_label, half_label, label_top, label_bottom) >= f + gap
            // Labels of diagonal neighbours.
            && (dx >= 2.0 * half_label + gap || p >= label_bottom - label_top + gap)
            // Same column two rows apart.
            && 2.0 * p >= cell.height + gap
    };
    let mut p = f;
    while !fits(p) {
        p += 0.05;
    }
    p
}

fn hex_packing(cell: &Cell, width: f64, height: f64, gap: f64) -> Packing {
    let full = ((width + gap) / cell.pitch_x + 1e-9).floor() as usize;
    let shifted = ((width + gap - cell.pitch_x / 2.0) / cell.pitch_x + 1e-9).floor() as usize;
    if full == 0 || height + 1e-9 < cell.height {
        return Packing {
            centres: Vec::new(),
        };
    }
    let pitch_y = hex_row_pitch(cell, gap);
    let rows = 1 + ((height - cell.height) / pitch_y + 1e-9).floor() as usize;
    let block =
        (full as f64 * cell.pitch_x).max(shifted as f64 * cell.pitch_x + cell.pitch_x / 2.0) - gap;
    let x0 = (width - block) / 2.0 + (cell.pitch_x - gap) / 2.0;
    let y0 = (height - ((rows - 1) as f64 * pitch_y + cell.height)) / 2.0;
    let mut centres = Vec::new();
    for r in 0..rows {
        let (cols, offset) = if r % 2 == 0 {
            (full, 0.0)
        } else {
            (shifted, cell.pitch_x / 2.0)
        };
        for c in 0..cols {
            centres.push((
                x0 + offset + c as f64 * cell.pitch_x,
                y0 + cell.footprint + r as f64 * pitch_y,
            ));
        }
    }
    Packing { centres }
}

/// The layout area of a page: left, top, width, height (mm).
pub(super) fn layout_area(template: &Template) -> (f64, f64, f64, f64) {
    let m = template.margin_mm;
    (
        m,
        m,
        template.page_width_mm - 2.0 * m,
        template.page_height_mm - 2.0 * m - FOOTER_MM,
    )
}

/// The packing fitting more markers on a page (grid on a tie).
pub(super) fn best_packing(
    markers: &[SheetMarker],
    diameter_mm: f64,
    template: &Template,
) -> (Cell, Packing) {
    let cell = cell_for(markers, diameter_mm, template);
    let (_, _, w, h) = layout_area(template);
    let grid = grid_packing(&cell, w, h, template.gap_mm);
    let hex = hex_packing(&cell, w, h, template.gap_mm);
    if hex.centres.len() > grid.centres.len() {
        (cell, hex)
    } else {
        (cell, grid)
    }
}
