//! Text for labels: Helvetica advance widths (PDF and SVG use the real font,
//! layout needs its widths) and a small stroke font for raster output, where
//! no font file is available. Stroke glyphs are drawn on a grid whose cap
//! height is 6 units.

use super::page::{Anchor, Segment, MM_PER_PT};

/// Helvetica advance widths for ASCII 32..=126, in 1/1000 em (Adobe AFM).
const HELVETICA_WIDTHS: [u16; 95] = [
    278, 278, 355, 556, 556, 889, 667, 191, 333, 333, 389, 584, 278, 333, 278, 278, // ' '../
    556, 556, 556, 556, 556, 556, 556, 556, 556, 556, // 0-9
    278, 278, 584, 584, 584, 556, 1015, // :;<=>?@
    667, 667, 722, 722, 667, 611, 778, 722, 278, 500, 667, 556, 833, // A-M
    722, 778, 667, 778, 722, 667, 611, 722, 667, 944, 667, 667, 611, // N-Z
    278, 278, 278, 469, 556, 333, // [\]^_`
    556, 556, 500, 556, 556, 278, 556, 556, 222, 222, 500, 222, 833, // a-m
    556, 556, 556, 556, 333, 500, 278, 556, 500, 722, 500, 500, 500, // n-z
    334, 260, 334, 584, // {|}~
];

/// Width of `text` set in Helvetica at `size_pt`, in millimetres.
pub fn helvetica_width_mm(text: &str, size_pt: f64) -> f64 {
    let units: u32 = text
        .chars()
        .map(|c| match c {
            ' '..='~' => u32::from(HELVETICA_WIDTHS[c as usize - 32]),
            '·' => 278,
            _ => 556,
        })
        .sum();
    f64::from(units) / 1000.0 * size_pt * MM_PER_PT
}

/// Helvetica's cap height as a fraction of the font size.
pub const CAP_HEIGHT: f64 = 0.718;

/// Stroke glyphs: polylines separated by ';', points "x,y" with y up from
/// the baseline, cap height 6, x-height 4, descenders to -2.
fn glyph(c: char) -> Option<&'static str> {
    Some(match c {
        '0' => "1,0 3,0 4,1 4,5 3,6 1,6 0,5 0,1 1,0",
        '1' => "1,5 2,6 2,0; 1,0 3,0",
        '2' => "0,5 1,6 3,6 4,5 4,4 0,0 4,0",
        '3' => "0,5 1,6 3,6 4,5 4,4 3,3 1.5,3; 3,3 4,2 4,1 3,0 1,0 0,1",
        '4' => "3,0 3,6 0,2 4,2",
        '5' => "4,6 0,6 0,3.5 3,3.5 4,2.5 4,1 3,0 1,0 0,1",
        '6' => "4,5 3,6 1,6 0,5 0,1 1,0 3,0 4,1 4,2.5 3,3.5 1,3.5 0,2.5",
        '7' => "0,6 4,6 1.5,0",
        '8' => "1,3 0,4 0,5 1,6 3,6 4,5 4,4 3,3 1,3 0,2 0,1 1,0 3,0 4,1 4,2 3,3",
        '9' => "0,1 1,0 3,0 4,1 4,5 3,6 1,6 0,5 0,3.5 1,2.5 3,2.5 4,3.5",
        'A' => "0,0 2,6 4,0; 0.7,2 3.3,2",
        'B' => "0,0 0,6 3,6 4,5 4,4 3,3 0,3; 3,3 4,2 4,1 3,0 0,0",
        'C' => "4,5 3,6 1,6 0,5 0,1 1,0 3,0 4,1",
        'D' => "0,0 0,6 2.5,6 4,4.5 4,1.5 2.5,0 0,0",
        'E' => "4,6 0,6 0,0 4,0; 0,3 3,3",
        'F' => "4,6 0,6 0,0; 0,3 3,3",
        'G' => "4,5 3,6 1,6 0,5 0,1 1,0 3,0 4,1 4,3 2.5,3",
        'H' => "0,0 0,6; 4,0 4,6; 0,3 4,3",
        'I' => "0,6 2,6; 1,6 1,0; 0,0 2,0",
        'J' => "3,6 3,1 2,0 1,0 0,1",
        'K' => "0,0 0,6; 4,6 0,2; 1.3,3.3 4,0",
        'L' => "0,6 0,0 4,0",
        'M' => "0,0 0,6 2.5,2.5 5,6 5,0",
        'N' => "0,0 0,6 4,0 4,6",
        'O' => "1,0 3,0 4,1 4,5 3,6 1,6 0,5 0,1 1,0",
        'P' => "0,0 0,6 3,6 4,5 4,4 3,3 0,3",
        'Q' => "1,0 3,0 4,1 4,5 3,6 1,6 0,5 0,1 1,0; 2.5,1.5 4,-0.5",
        'R' => "0,0 0,6 3,6 4,5 4,4 3,3 0,3; 2,3 4,0",
        'S' => "4,5 3,6 1,6 0,5 0,4 1,3 3,3 4,2 4,1 3,0 1,0 0,1",
        'T' => "0,6 4,6; 2,6 2,0",
        'U' => "0,6 0,1 1,0 3,0 4,1 4,6",
        'V' => "0,6 2,0 4,6",
        'W' => "0,6 1.25,0 2.5,4 3.75,0 5,6",
        'X' => "0,0 4,6; 0,6 4,0",
        'Y' => "0,6 2,3 4,6; 2,3 2,0",
        'Z' => "0,6 4,6 0,0 4,0",
        'a' => "0.5,4 2.5,4 3.5,3 3.5,0; 3.5,2.5 1,2.5 0,1.5 0,1 1,0 2.5,0 3.5,1",
        'b' => "0,6 0,0; 0,3 1,4 2.5,4 3.5,3 3.5,1 2.5,0 1,0 0,1",
        'c' => "3.5,3 2.5,4 1,4 0,3 0,1 1,0 2.5,0 3.5,1",
        'd' => "3.5,6 3.5,0; 3.5,3 2.5,4 1,4 0,3 0,1 1,0 2.5,0 3.5,1",
        'e' => "0,2 3.5,2 3.5,3 2.5,4 1,4 0,3 0,1 1,0 2.5,0 3.5,0.7",
        'f' => "3,6 2,6 1,5 1,0; 0,4 2.5,4",
        'g' => "3.5,4 3.5,-1 2.5,-2 1,-2 0,-1.3; 3.5,3 2.5,4 1,4 0,3 0,1 1,0 2.5,0 3.5,1",
        'h' => "0,6 0,0; 0,3 1,4 2.5,4 3.5,3 3.5,0",
        'i' => "0.5,4 0.5,0; 0.5,5.5 0.5,5.7",
        'j' => "1.5,4 1.5,-1 0.5,-2 0,-2; 1.5,5.5 1.5,5.7",
        'k' => "0,6 0,0; 3.5,4 0,1.5; 1.2,2.3 3.5,0",
        'l' => "0.5,6 0.5,1 1.5,0",
        'm' => "0,4 0,0; 0,3 1,4 2,3 2,0; 2,3 3,4 4,3 4,0",
        'n' => "0,4 0,0; 0,3 1,4 2.5,4 3.5,3 3.5,0",
        'o' => "1,0 2.5,0 3.5,1 3.5,3 2.5,4 1,4 0,3 0,1 1,0",
        'p' => "0,4 0,-2; 0,3 1,4 2.5,4 3.5,3 3.5,1 2.5,0 1,0 0,1",
        'q' => "3.5,4 3.5,-2; 3.5,3 2.5,4 1,4 0,3 0,1 1,0 2.5,0 3.5,1",
        'r' => "0,4 0,0; 0,2.5 1.5,4 3,4",
        's' => "3.5,3.5 2.5,4 1,4 0,3.3 0.5,2.3 3,1.7 3.5,0.7 2.5,0 1,0 0,0.5",
        't' => "1,5.5 1,1 2,0 3,0; 0,4 2.5,4",
        'u' => "0,4 0,1 1,0 2.5,0 3.5,1; 3.5,4 3.5,0",
        'v' => "0,4 1.75,0 3.5,4",
        'w' => "0,4 1,0 2,3 3,0 4,4",
        'x' => "0,4 3.5,0; 0,0 3.5,4",
        'y' => "0,4 1.75,0; 3.5,4 1.2,-2 0.5,-2",
        'z' => "0,4 3.5,4 0,0 3.5,0",
        '.' => "0,0 0,0.2",
        '·' => "0,3 0,3.2",
        ',' => "0.5,0.3 0,-1",
        ':' => "0,0 0,0.2; 0,3.5 0,3.7",
        ';' => "0.5,3.5 0.5,3.7; 0.5,0.3 0,-1",
        '-' => "0,2.5 3,2.5",
        '_' => "0,-0.8 4,-0.8",
        '/' => "0,-0.5 3,6.5",
        '\\' => "0,6.5 3,-0.5",
        '(' => "2,6.5 1,5 1,0.5 2,-1",
        ')' => "0,6.5 1,5 1,0.5 0,-1",
        '[' => "1.5,6.5 0,6.5 0,-1 1.5,-1",
        ']' => "0,6.5 1.5,6.5 1.5,-1 0,-1",
        '{' => "2,6.5 1,6 1,3.5 0,2.75 1,2 1,-0.5 2,-1",
        '}' => "0,6.5 1,6 1,3.5 2,2.75 1,2 1,-0.5 0,-1",
        '+' => "0,2.5 4,2.5; 2,0.5 2,4.5",
        '=' => "0,1.7 4,1.7; 0,3.3 4,3.3",
        '#' => "1,0 1.6,6; 2.6,0 3.2,6; 0,2 4,2; 0,4 4,4",
        '%' => "0,0 4,6; 0,6 1,6 1,5 0,5 0,6; 3,0 4,0 4,1 3,1 3,0",
        '!' => "0,6 0,2; 0,0 0,0.2",
        '?' => "0,5 1,6 3,6 4,5 4,4 2,2.5 2,1.5; 2,0 2,0.2",
        '"' => "0,6 0,4.5; 1.5,6 1.5,4.5",
        '\'' => "0,6 0,4.5",
        '`' => "0,6 1,5",
        '*' => "2,5.5 2,2.5; 0.7,4.7 3.3,3.3; 0.7,3.3 3.3,4.7",
        '<' => "4,5 0,3 4,1",
        '>' => "0,5 4,3 0,1",
        '^' => "0,4 2,6 4,4",
        '|' => "0,6.5 0,-1",
        '~' => "0,3 1,3.7 3,2.7 4,3.4",
        '$' => "4,5 3,6 1,6 0,5 0,4 1,3 3,3 4,2 4,1 3,0 1,0 0,1; 2,6.8 2,-0.8",
        '&' => "4,0 0.5,4.5 0.5,5.3 1.2,6 2.3,6 3,5.3 3,4.6 0,2 0,1 1,0 2.5,0 4,2",
        '@' => "3,2 3,4 1,4 1,2 3,2 4,2.5 4,5 3,6 1,6 0,5 0,1 1,0 3.5,0",
        _ => return None,
    })
}

/// Placeholder drawn for characters the stroke font lacks.
const MISSING_GLYPH: &str = "0,0 3,0 3,6 0,6 0,0";

/// Grid units between glyphs.
const LETTER_SPACING: f64 = 1.6;
/// Advance of a space, in grid units.
const SPACE_ADVANCE: f64 = 3.0;

fn glyph_polylines(c: char) -> impl Iterator<Item = Vec<(f64, f64)>> {
    glyph(c).unwrap_or(MISSING_GLYPH).split(';').map(|line| {
        line.split_whitespace()
            .filter_map(|pt| {
                let (x, y) = pt.split_once(',')?;
                Some((x.parse().ok()?, y.parse().ok()?))
            })
            .collect()
    })
}

fn glyph_advance(c: char) -> f64 {
    if c == ' ' {
        return SPACE_ADVANCE;
    }
    let width = glyph_polylines(c)
        .flatten()
        .map(|(x, _)| x)
        .fold(0.0, f64::max);
    width + LETTER_SPACING
}

/// Millimetres per grid unit for a font size: the cap height (6 units)
/// matches Helvetica's.
fn unit_mm(size_pt: f64) -> f64 {
    size_pt * MM_PER_PT * CAP_HEIGHT / 6.0
}

/// Width of `text` in the stroke font, in millimetres.
pub fn stroke_width_mm(text: &str, size_pt: f64) -> f64 {
    let units: f64 = text.chars().map(glyph_advance).sum::<f64>() - LETTER_SPACING;
    units.max(0.0) * unit_mm(size_pt)
}

/// Pen width of the stroke font at a font size, in millimetres.
pub fn stroke_pen_mm(size_pt: f64) -> f64 {
    0.75 * unit_mm(size_pt)
}

/// The stroke-font outline of a text line as open polylines in page
/// millimetres (y down), baseline at `y`.
pub fn stroke_text(text: &str, x: f64, y: f64, size_pt: f64, anchor: Anchor) -> Vec<Segment> {
    let unit = unit_mm(size_pt);
    let width = stroke_width_mm(text, size_pt);
    let mut pen_x = match anchor {
        Anchor::Start => x,
        Anchor::Middle => x - width / 2.0,
        Anchor::End => x - width,
    };
    let mut out = Vec::new();
    for c in text.chars() {
        if c != ' ' {
            for line in glyph_polylines(c) {
                for (k, &(gx, gy)) in line.iter().enumerate() {
                    let p = (pen_x + gx * unit, y - gy * unit);
                    out.push(if k == 0 {
                        Segment::MoveTo(p.0, p.1)
                    } else {
                        Segment::LineTo(p.0, p.1)
                    });
                }
            }
        }
        pen_x += glyph_advance(c) * unit;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_printable_ascii_character_has_a_glyph() {
        for c in '!'..='~' {
            assert!(glyph(c).is_some(), "no glyph for {c:?}");
            assert!(glyph_polylines(c).all(|l| !l.is_empty()), "{c:?}");
        }
    }

    #[test]
    fn helvetica_widths_match_known_strings() {
        // "ID" = 278 + 722 units; at 10 pt that is 10.00 pt = 3.528 mm.
        assert!((helvetica_width_mm("ID", 10.0) - 10.0 * MM_PER_PT).abs() < 1e-9);
    }
}
