//! Physical size: PDFs rasterised by an independent renderer (poppler's
//! pdftoppm at 600 dpi) show the black disc at the asked diameter and the
//! page at the exact paper size.

use crate::support::{have_tool, run_ok};

use std::path::Path;
use std::process::Command;

const DPI: f64 = 600.0;

/// Rasterises page `page` of a PDF to a grey image with pdftoppm.
fn pdftoppm(pdf: &Path, page: u32) -> image::GrayImage {
    let prefix = pdf.with_extension("");
    let status = Command::new("pdftoppm")
        .args(["-r", "600", "-gray", "-f", &page.to_string(), "-l"])
        .arg(page.to_string())
        .arg("-singlefile")
        .arg(pdf)
        .arg(&prefix)
        .status()
        .unwrap();
    assert!(status.success());
    image::open(prefix.with_extension("pgm"))
        .unwrap()
        .to_luma8()
}

/// Page size in points from pdfinfo.
fn pdfinfo_size(pdf: &Path) -> Option<(f64, f64)> {
    let out = Command::new("pdfinfo").arg(pdf).output().ok()?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let line = text.lines().find(|l| l.starts_with("Page size:"))?;
    let mut nums = line
        .split_whitespace()
        .filter_map(|w| w.parse::<f64>().ok());
    Some((nums.next()?, nums.next()?))
}

/// Sub-pixel position where a row or column profile crosses mid-grey, going
/// from black into white (searching from `from` in direction `step`).
fn edge(profile: &[f64], from: usize, step: isize) -> f64 {
    let mut i = from as isize;
    loop {
        let next = i + step;
        let (a, b) = (profile[i as usize], profile[next as usize]);
        if a < 127.5 && b >= 127.5 {
            // Pixel centres are at index + 0.5.
            let t = (127.5 - a) / (b - a);
            return i as f64 + 0.5 + t * step as f64;
        }
        i = next;
    }
}

/// Black disc diameter in mm measured along the row and column through
/// (cx, cy) (pixels), from the outer white-to-black edges.
fn disc_diameters(img: &image::GrayImage, cx: f64, cy: f64, search_px: usize) -> (f64, f64) {
    let row = cy as u32;
    let col = cx as u32;
    let horizontal: Vec<f64> = (0..img.width())
        .map(|x| f64::from(img.get_pixel(x, row)[0]))
        .collect();
    let vertical: Vec<f64> = (0..img.height())
        .map(|y| f64::from(img.get_pixel(col, y)[0]))
        .collect();
    let (x, y) = (cx as usize, cy as usize);
    let left = edge(&horizontal, x - search_px, -1);
    let right = edge(&horizontal, x + search_px, 1);
    let top = edge(&vertical, y - search_px, -1);
    let bottom = edge(&vertical, y + search_px, 1);
    let px_to_mm = 25.4 / DPI;
    ((right - left) * px_to_mm, (bottom - top) * px_to_mm)
}

#[test]
fn single_marker_pdf_has_the_asked_diameter_and_page_size() {
    if !have_tool("pdftoppm", "poppler-utils") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (diameter, args) in [
        (50.0, vec!["--bits", "8", "--id", "5"]),
        (33.3, vec!["--bits", "12", "--distance", "3", "--id", "7"]),
        (50.8, vec!["--legacy"]),
    ] {
        let pdf = dir
            .path()
            .join(format!("m{}.pdf", (diameter * 10.0) as u32));
        let d_arg = if diameter == 50.8 {
            "2in".to_string()
        } else {
            format!("{diameter}mm")
        };
        let mut all: Vec<&str> = args.clone();
        all.extend(["--diameter", &d_arg, "-o", pdf.to_str().unwrap()]);
        let mut cmd = vec!["marker"];
        cmd.extend(all);
        run_ok(&cmd);
        let side_mm = diameter * 1.3;
        if let Some((w, h)) = pdfinfo_size(&pdf) {
            let expected = side_mm / 25.4 * 72.0;
            assert!(
                (w - expected).abs() < 0.01,
                "page width {w} pt, expected {expected}"
            );
            assert!(
                (h - expected).abs() < 0.01,
                "page height {h} pt, expected {expected}"
            );
        }
        let img = pdftoppm(&pdf, 1);
        let side_px = side_mm / 25.4 * DPI;
        assert!((f64::from(img.width()) - side_px).abs() < 1.01);
        assert!((f64::from(img.height()) - side_px).abs() < 1.01);
        let c = side_px / 2.0;
        // Start inside the black annulus (0.6R..R), walk outwards to the edge.
        let search = (diameter / 2.0 * 0.8 / 25.4 * DPI) as usize;
        let (dx, dy) = disc_diameters(&img, c, c, search);
        assert!(
            (dx - diameter).abs() < 0.1,
            "horizontal diameter {dx} mm, asked {diameter}"
        );
        assert!(
            (dy - diameter).abs() < 0.1,
            "vertical diameter {dy} mm, asked {diameter}"
        );
    }
}

#[test]
fn sheet_pdf_puts_markers_where_the_manifest_says_at_their_size() {
    if !have_tool("pdftoppm", "poppler-utils") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let pdf = dir.path().join("swarm.pdf");
    run_ok(&[
        "sheet",
        "--bits",
        "8",
        "--distance",
        "2",
        "--ids",
        "1-16",
        "--diameter",
        "40mm",
        "--template",
        "a4",
        "--no-check",
        "-o",
        pdf.to_str().unwrap(),
    ]);
    if let Some((w, h)) = pdfinfo_size(&pdf) {
        assert!(
            (w - 595.276).abs() < 0.01 && (h - 841.89).abs() < 0.01,
            "{w} x {h}"
        );
    }
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("swarm.json")).unwrap())
            .unwrap();
    assert_eq!(manifest["page_size_mm"], serde_json::json!([210.0, 297.0]));
    let pages = manifest["pages"].as_u64().unwrap() as u32;
    for page in 1..=pages {
        let img = pdftoppm(&pdf, page);
        assert_eq!((img.width(), img.height()), (4961, 7016));
        for m in manifest["markers"].as_array().unwrap() {
            if m["page"].as_u64().unwrap() as u32 != page {
                continue;
            }
            let s = DPI / 25.4;
            let (cx, cy) = (
                m["x_mm"].as_f64().unwrap() * s,
                m["y_mm"].as_f64().unwrap() * s,
            );
            let search = (20.0 * 0.8 * s) as usize;
            let (dx, dy) = disc_diameters(&img, cx, cy, search);
            assert!(
                (dx - 40.0).abs() < 0.1 && (dy - 40.0).abs() < 0.1,
                "{dx} {dy}"
            );
            // The centre: midpoint of the horizontal edges matches the manifest.
            let row: Vec<f64> = (0..img.width())
                .map(|x| f64::from(img.get_pixel(x, cy as u32)[0]))
                .collect();
            let mid =
                (edge(&row, cx as usize - search, -1) + edge(&row, cx as usize + search, 1)) / 2.0;
            assert!(
                (mid - cx).abs() / s < 0.1,
                "centre off by {} mm",
                (mid - cx) / s
            );
        }
    }
}

#[test]
fn scale_bar_is_as_long_as_it_says() {
    if !have_tool("pdftoppm", "poppler-utils") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let pdf = dir.path().join("bar.pdf");
    run_ok(&[
        "sheet",
        "--bits",
        "8",
        "--ids",
        "1",
        "--diameter",
        "30mm",
        "--no-check",
        "-o",
        pdf.to_str().unwrap(),
    ]);
    let img = pdftoppm(&pdf, 1);
    let s = DPI / 25.4;
    // The bar's bottom edge sits on the 10 mm bottom margin; sample 0.4 mm above it.
    let y = ((297.0 - 10.0 - 0.4) * s) as u32;
    let row: Vec<f64> = (0..img.width())
        .map(|x| f64::from(img.get_pixel(x, y)[0]))
        .collect();
    // Walk out of the bar from its middle to both ends.
    let middle = ((10.0 + 50.0) * s) as usize;
    let left = edge(&row, middle, -1);
    let right = edge(&row, middle, 1);
    let length = (right - left) / s;
    assert!((length - 100.0).abs() < 0.1, "bar is {length} mm");
}
