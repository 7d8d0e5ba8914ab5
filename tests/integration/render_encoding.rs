//! Encoding: read the code back from rendered PNGs by sampling the ring in
//! 2n sectors, with code written here from the spec (section 2) rather than
//! the renderer's own geometry helpers.

use whycode::family::Family;
use whycode::geometry::{Marker, RING_SAMPLE_RATIO};
use whycode::render::png::marker_png;
use whycode::render::MarkerOptions;

/// Reads the n-bit word from a decoded grey image of a centred marker whose
/// black disc has radius `r_px`: bit i is 1 when sector 2i is white.
fn read_ring(img: &image::GrayImage, bits: u32, r_px: f64) -> Option<u32> {
    let (cx, cy) = (f64::from(img.width()) / 2.0, f64::from(img.height()) / 2.0);
    let sectors = 2 * bits;
    let width = std::f64::consts::PI / f64::from(bits);
    let mut black = Vec::new();
    for k in 0..sectors {
        // Average the middle half of the sector over the middle of the ring.
        let mut sum = 0.0;
        let mut n = 0.0;
        for a in 0..9 {
            let theta = (f64::from(k) + 0.25 + 0.5 * f64::from(a) / 8.0) * width;
            for rr in [-0.05, 0.0, 0.05].map(|d| RING_SAMPLE_RATIO + d) {
                let (x, y) = (cx + rr * r_px * theta.cos(), cy - rr * r_px * theta.sin());
                sum += f64::from(img.get_pixel(x as u32, y as u32)[0]);
                n += 1.0;
            }
        }
        let mean = sum / n;
        // Sectors must be clearly black or clearly white.
        if (60.0..195.0).contains(&mean) {
            return None;
        }
        black.push(mean < 128.0);
    }
    let mut word = 0;
    for i in 0..bits as usize {
        // Manchester: each bit's two halves differ.
        if black[2 * i] == black[2 * i + 1] {
            return None;
        }
        word = (word << 1) | u32::from(!black[2 * i]);
    }
    Some(word)
}

#[test]
fn rendered_pngs_carry_the_family_codes() {
    let mut checked = 0;
    for bits in 4..=16 {
        for distance in [1, 2, 3] {
            let family = Family::generate(bits, distance).unwrap();
            if family.is_empty() {
                continue;
            }
            let n = family.len() as u32;
            // First, last and a spread of IDs in between.
            let mut ids: Vec<u32> = (0..6).map(|k| 1 + k * (n - 1) / 5).collect();
            ids.dedup();
            for id in ids {
                let code = family.code(id).unwrap();
                let marker = Marker::whycode(bits, code, 30.0);
                let dpi = 200.0;
                let bytes = marker_png(&marker, &MarkerOptions::default(), dpi).unwrap();
                let img = image::load_from_memory(&bytes).unwrap().to_luma8();
                let r_px = 15.0 / 25.4 * dpi;
                assert_eq!(
                    read_ring(&img, bits, r_px),
                    Some(code),
                    "bits={bits} d={distance} id={id}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "only {checked} markers checked");
}

#[test]
fn png_records_its_resolution() {
    let marker = Marker::whycode(8, 7, 20.0);
    let bytes = marker_png(&marker, &MarkerOptions::default(), 600.0).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let reader = decoder.read_info().unwrap();
    let dims = reader.info().pixel_dims.expect("pHYs chunk");
    assert_eq!(dims.unit, png::Unit::Meter);
    assert_eq!(dims.xppu, 23622);
    assert_eq!(dims.yppu, 23622);
    // 20 mm + 2 x 3 mm margin at 600 dpi.
    assert_eq!(reader.info().width, 614);
}
