//! The one description of a marker's shape, in physical units (millimetres),
//! shared by every renderer, the scene simulator and the detector.
//!
//! Marker frame: origin at the centre, +x along code-sector angle 0, +y along
//! sector angle 90°, angles growing counter-clockwise as seen looking at the
//! printed face (spec sections 1-2). Renderers whose page y axis points down
//! map a marker point (x, y) to page point (cx + x, cy - y).

use std::f64::consts::PI;

/// Black disc radius: 1 (everything below is relative to the outer radius R).
pub const OUTER_RATIO: f64 = 1.0;
/// White disc of a WhyCode marker, 420/700.
pub const WHYCODE_WHITE_RATIO: f64 = 0.6;
/// Inner edge of the code ring, 240/700; the white centre disc inside it.
pub const RING_INNER_RATIO: f64 = 240.0 / 700.0;
/// Radius at which the reference detector samples the ring, 330/700.
pub const RING_SAMPLE_RATIO: f64 = 330.0 / 700.0;
/// White disc of a legacy WhyCon marker, 50/122.
pub const WHYCON_WHITE_RATIO: f64 = 50.0 / 122.0;
/// Least white margin around the black disc that the detector needs.
pub const MIN_MARGIN_RATIO: f64 = 0.3;

/// What a marker carries inside its black disc.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerKind {
    /// Legacy WhyCon circle: black disc and white disc, no ID.
    WhyCon,
    /// WhyCode marker carrying an n-bit necklace code in its ring.
    WhyCode {
        /// Code length n.
        bits: u32,
        /// The code, as its smallest rotation.
        code: u32,
    },
}

impl MarkerKind {
    /// The design this kind is drawn in, whatever its code.
    pub fn design(self) -> Design {
        match self {
            MarkerKind::WhyCon => Design::WhyCon,
            MarkerKind::WhyCode { .. } => Design::WhyCode,
        }
    }
}

/// The two marker designs, whatever the code: the proportions every stage
/// that draws or looks for a marker takes from here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Design {
    /// Black disc with a white disc inside.
    WhyCon,
    /// WhyCon's discs with the code ring between them.
    WhyCode,
}

impl Design {
    /// Ratio of the white disc to the outer radius.
    pub fn white_ratio(self) -> f64 {
        match self {
            Design::WhyCon => WHYCON_WHITE_RATIO,
            Design::WhyCode => WHYCODE_WHITE_RATIO,
        }
    }

    /// Radius (relative) of the solid white disc at the centre: the whole
    /// white disc of a WhyCon marker, the disc inside a WhyCode ring.
    pub fn centre_white_ratio(self) -> f64 {
        match self {
            Design::WhyCon => WHYCON_WHITE_RATIO,
            Design::WhyCode => RING_INNER_RATIO,
        }
    }

    /// Radii (relative) of the concentric circles inside the black disc
    /// where white meets black: WhyCode's show only in part (the ring's
    /// inner border beside black sectors, its outer border beside white).
    pub fn inner_edge_ratios(self) -> &'static [f64] {
        match self {
            Design::WhyCon => &[WHYCON_WHITE_RATIO],
            Design::WhyCode => &[RING_INNER_RATIO, WHYCODE_WHITE_RATIO],
        }
    }

    /// Share of the whole disc (radius R) that is white.
    pub fn white_fraction(self) -> f64 {
        match self {
            Design::WhyCon => WHYCON_WHITE_RATIO.powi(2),
            // Centre disc plus the white half of the ring's 2n sectors
            // (Manchester coding makes exactly half of them black, whatever
            // the code).
            Design::WhyCode => {
                let ring = WHYCODE_WHITE_RATIO.powi(2) - RING_INNER_RATIO.powi(2);
                RING_INNER_RATIO.powi(2) + ring / 2.0
            }
        }
    }
}

/// A filled region of the marker, in marker-frame millimetres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A full disc centred on the origin.
    Disc {
        /// Radius, mm.
        radius: f64,
        /// Black ink when true, white otherwise.
        black: bool,
    },
    /// An annular sector from angle `start` to `end` (radians, CCW, end > start).
    Sector {
        /// Inner radius, mm.
        inner: f64,
        /// Outer radius, mm.
        outer: f64,
        /// Start angle, radians.
        start: f64,
        /// End angle, radians.
        end: f64,
        /// Black ink when true, white otherwise.
        black: bool,
    },
}

/// A marker's shape at a physical size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Marker {
    /// Which design, and the code it carries.
    pub kind: MarkerKind,
    /// Diameter of the black disc, 2R, in millimetres.
    pub diameter_mm: f64,
}

impl Marker {
    /// A WhyCode marker carrying `code` (a `bits`-bit family code), `diameter_mm` across its black disc.
    pub fn whycode(bits: u32, code: u32, diameter_mm: f64) -> Marker {
        Marker {
            kind: MarkerKind::WhyCode { bits, code },
            diameter_mm,
        }
    }

    /// A legacy WhyCon circle, `diameter_mm` across its black disc.
    pub fn whycon(diameter_mm: f64) -> Marker {
        Marker {
            kind: MarkerKind::WhyCon,
            diameter_mm,
        }
    }

    /// Radius R of the black disc, mm: the unit every ratio in this module is relative to.
    pub fn outer_radius(&self) -> f64 {
        self.diameter_mm / 2.0
    }

    /// Radius of the white disc inside the black one.
    pub fn white_radius(&self) -> f64 {
        self.outer_radius() * self.kind.design().white_ratio()
    }

    /// The least white margin to keep clear around the black disc.
    pub fn min_margin(&self) -> f64 {
        self.outer_radius() * MIN_MARGIN_RATIO
    }

    /// Radius of the area a marker needs, black disc plus its white margin.
    pub fn footprint_radius(&self) -> f64 {
        self.outer_radius() + self.min_margin()
    }

    /// The marker's regions, bottom to top: painting them in order (on a
    /// white background) draws the marker. Adjacent black sectors are merged
    /// so that anti-aliased renderers leave no seams between them.
    pub fn shapes(&self) -> Vec<Shape> {
        let r = self.outer_radius();
        let mut shapes = vec![
            Shape::Disc {
                radius: r,
                black: true,
            },
            Shape::Disc {
                radius: self.white_radius(),
                black: false,
            },
        ];
        if let MarkerKind::WhyCode { bits, code } = self.kind {
            for (start, end) in black_ring_arcs(bits, code) {
                shapes.push(Shape::Sector {
                    inner: r * RING_INNER_RATIO,
                    outer: r * WHYCODE_WHITE_RATIO,
                    start,
                    end,
                    black: true,
                });
            }
        }
        shapes
    }

    /// True when the marker-frame point (x, y) in millimetres is black.
    pub fn is_black_at(&self, x: f64, y: f64) -> bool {
        let r = self.outer_radius();
        let rho = (x * x + y * y).sqrt() / r;
        if rho > OUTER_RATIO {
            return false;
        }
        match self.kind {
            MarkerKind::WhyCon => rho > WHYCON_WHITE_RATIO,
            MarkerKind::WhyCode { bits, code } => {
                if rho > WHYCODE_WHITE_RATIO {
                    true
                } else if rho < RING_INNER_RATIO {
                    false
                } else {
                    let angle = y.atan2(x).rem_euclid(2.0 * PI);
                    let sector = ((angle / sector_width(bits)) as u32).min(2 * bits - 1);
                    sector_is_black(bits, code, sector)
                }
            }
        }
    }
}

/// Angular width of one of the 2n ring sectors, radians.
pub fn sector_width(bits: u32) -> f64 {
    PI / f64::from(bits)
}

/// Colour of ring sector k (0..2n) under Manchester encoding: bit i owns
/// sectors 2i and 2i+1; a 0 bit is black then white, a 1 bit white then black.
pub fn sector_is_black(bits: u32, code: u32, sector: u32) -> bool {
    let bit_index = sector / 2;
    let bit = (code >> (bits - 1 - bit_index)) & 1 == 1;
    let second_half = sector % 2 == 1;
    bit == second_half
}

/// Angular runs [start, end) of black ring sectors, adjacent sectors merged,
/// a run that wraps past 2π kept whole (its end is then above 2π).
pub fn black_ring_arcs(bits: u32, code: u32) -> Vec<(f64, f64)> {
    let sectors = 2 * bits;
    let w = sector_width(bits);
    // Start at a white-to-black transition so no run is split at angle 0.
    let Some(first) = (0..sectors).find(|&k| {
        sector_is_black(bits, code, k) && !sector_is_black(bits, code, (k + sectors - 1) % sectors)
    }) else {
        return Vec::new();
    };
    let mut arcs = Vec::new();
    let mut k = 0;
    while k < sectors {
        let s = (first + k) % sectors;
        if sector_is_black(bits, code, s) {
            let mut len = 1;
            while len + k < sectors && sector_is_black(bits, code, (s + len) % sectors) {
                len += 1;
            }
            arcs.push((f64::from(s) * w, f64::from(s + len) * w));
            k += len;
        } else {
            k += 1;
        }
    }
    arcs.sort_by(|a, b| a.0.total_cmp(&b.0));
    arcs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manchester_sectors_follow_the_spec() {
        // code 0b10 in 2 bits: bit 0 = 1 (white, black), bit 1 = 0 (black, white)
        let colours: Vec<bool> = (0..4).map(|k| sector_is_black(2, 0b10, k)).collect();
        assert_eq!(colours, [false, true, true, false]);
    }

    #[test]
    fn merged_arcs_cover_exactly_the_black_sectors() {
        for (bits, code) in [(8u32, 1u32), (8, 91), (12, 0b1011_0011_1000), (5, 0b10110)] {
            let w = sector_width(bits);
            let arcs = black_ring_arcs(bits, code);
            for k in 0..2 * bits {
                let mid = (f64::from(k) + 0.5) * w;
                let inside = arcs
                    .iter()
                    .any(|&(s, e)| (s..e).contains(&mid) || (s..e).contains(&(mid + 2.0 * PI)));
                assert_eq!(
                    inside,
                    sector_is_black(bits, code, k),
                    "bits={bits} code={code} k={k}"
                );
            }
        }
    }

    #[test]
    fn point_colours_match_layers() {
        let m = Marker::whycode(8, 1, 100.0);
        assert!(m.is_black_at(49.0, 0.0));
        assert!(!m.is_black_at(51.0, 0.0));
        assert!(!m.is_black_at(0.0, 0.0));
        assert!(!m.is_black_at(10.0, 5.0));
        // code 1 = 0000_0001: bit 0 is 0, so sector 0 (just above +x) is black.
        let r = 50.0 * RING_SAMPLE_RATIO;
        assert!(m.is_black_at(r * 0.1f64.cos(), r * 0.1f64.sin()));
    }
}
