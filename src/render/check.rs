//! The sheet self-check: before a sheet is written, every page is
//! rasterised at a typical print resolution and at a deliberately coarse
//! one, the detector runs on each raster, and every marker must be found at
//! its place, read as its own ID, with yaw 0 (markers are printed upright).

use super::page::Page;
use super::raster;
use super::sheet::Sheet;
use super::RenderError;
use crate::detect::{Detection, Detector, DetectorConfig, Target};
use crate::family::Family;
use crate::geometry::{Design, Marker, MarkerKind};
use crate::manifest::PrintedMarker;
use crate::math::angle::wrap_signed;
use crate::parallel::prelude::*;

/// The resolution a sheet is usually printed at.
pub const PRINT_DPI: f64 = 300.0;
/// Outer diameter, in pixels, of the smallest marker in the coarse raster,
/// for codes of up to [`COARSE_BITS`] bits.
pub const COARSE_DIAMETER_PX: f64 = 30.0;
/// Longer codes get a proportionally larger coarse marker: the coarse check
/// is about blur and print dots, not about squeezing 2n ring sectors into a
/// fixed 30 px (a 20-bit marker there has 1.1 px sectors, which no reader
/// attempts, so such markers failed at every printed size).
pub const COARSE_BITS: u32 = 12;
/// Largest yaw error accepted, degrees.
pub const MAX_YAW_ERROR_DEG: f64 = 4.0;

/// Outer diameter, in pixels, the smallest marker is given in the coarse
/// raster: ring sectors never narrower than those of a 12-bit marker 30 px
/// across.
pub fn coarse_diameter_px(bits: Option<u32>) -> f64 {
    let bits = bits.unwrap_or(0).max(COARSE_BITS);
    COARSE_DIAMETER_PX * f64::from(bits) / f64::from(COARSE_BITS)
}

/// The resolutions a sheet is checked at: print resolution, and the one at
/// which its smallest marker is [`coarse_diameter_px`] across (if lower).
pub fn check_resolutions(sheet: &Sheet, target: &Target) -> Vec<f64> {
    resolutions_for(&sheet.manifest.markers, target.family())
}

fn resolutions_for(markers: &[PrintedMarker], family: Option<&Family>) -> Vec<f64> {
    let smallest = markers
        .iter()
        .map(|m| m.diameter_mm)
        .fold(f64::INFINITY, f64::min);
    let coarse_px = coarse_diameter_px(family.map(Family::bits));
    let coarse = (coarse_px / smallest * 25.4 * 10.0).ceil() / 10.0;
    if coarse.is_finite() && coarse < PRINT_DPI {
        vec![PRINT_DPI, coarse]
    } else {
        vec![PRINT_DPI]
    }
}

/// What the check did.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    /// Print resolutions the pages were rendered at, dpi.
    pub resolutions: Vec<f64>,
    /// Marker readings checked (markers x resolutions).
    pub readings: usize,
    /// What was checked: WhyCon circles only for their place, WhyCode
    /// markers also for their ID and an upright yaw.
    pub design: Design,
}

impl CheckReport {
    /// "every marker read back as its own ID, upright, at 300 and 75 dpi".
    pub fn summary(&self) -> String {
        let what = match self.design {
            Design::WhyCon => "found in place",
            Design::WhyCode => "read back as its own ID, upright,",
        };
        let dpis: Vec<String> = self.resolutions.iter().map(|d| format!("{d}")).collect();
        let dpis = match dpis.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
            _ => dpis.join(""),
        };
        format!("every marker {what} at {dpis} dpi")
    }
}

fn describe(m: &PrintedMarker) -> String {
    let what = if m.id == 0 {
        "WhyCon marker".to_string()
    } else {
        format!("ID {}", m.id)
    };
    format!(
        "{what} on page {} (x {:.1} mm, y {:.1} mm)",
        m.page, m.x_mm, m.y_mm
    )
}

fn wrap_degrees(rad: f64) -> f64 {
    wrap_signed(rad.to_degrees(), 360.0)
}

/// How a rendered marker failed to read back as printed.
#[derive(Debug, thiserror::Error)]
enum Misreading {
    #[error("{0} was not found")]
    NotFound(String),
    #[error("{0} could not be read")]
    Unreadable(String),
    #[error("{marker} reads as ID {id}")]
    OtherId { marker: String, id: u32 },
    #[error("{marker} reads with yaw {yaw_deg:.1}°, expected 0°")]
    Turned { marker: String, yaw_deg: f64 },
    #[error("{0} gives no yaw")]
    NoYaw(String),
}

/// Checks one expected marker against a page's detections.
fn check_marker(
    m: &PrintedMarker,
    detections: &[Detection],
    dpi: f64,
    design: Design,
) -> Result<(), Misreading> {
    let s = raster::px_per_mm(dpi);
    // Detector pixel coordinates have their origin at the top-left pixel's centre.
    let (u, v) = (m.x_mm * s - 0.5, m.y_mm * s - 0.5);
    let radius_px = m.diameter_mm / 2.0 * s;
    let tolerance = (0.1 * radius_px).max(1.5);
    let nearest = detections
        .iter()
        .map(|d| (d, (d.u - u).hypot(d.v - v)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let Some((d, dist)) = nearest.filter(|(_, dist)| *dist <= tolerance) else {
        return Err(Misreading::NotFound(describe(m)));
    };
    let _ = dist;
    if design == Design::WhyCon {
        return Ok(());
    }
    if d.id != m.id {
        return Err(if d.id == 0 {
            Misreading::Unreadable(describe(m))
        } else {
            Misreading::OtherId {
                marker: describe(m),
                id: d.id,
            }
        });
    }
    match d.yaw {
        Some(yaw) if wrap_degrees(yaw).abs() <= MAX_YAW_ERROR_DEG => Ok(()),
        Some(yaw) => Err(Misreading::Turned {
            marker: describe(m),
            yaw_deg: wrap_degrees(yaw),
        }),
        None => Err(Misreading::NoYaw(describe(m))),
    }
}

/// Renders each page at each check resolution, detects, and confirms every
/// marker. `target` says what the sheet holds: for WhyCode markers their
/// family (IDs and yaw are checked), for WhyCon circles only presence and
/// position are.
pub fn check_sheet(sheet: &Sheet, target: &Target) -> Result<CheckReport, RenderError> {
    check_pages(&sheet.pages, &sheet.manifest.markers, target, None)
}

/// [`check_sheet`] for a sheet written as PNG at `output_dpi`: that raster
/// is what gets printed, so it is checked too when it is coarser than print
/// resolution.
pub fn check_sheet_png(
    sheet: &Sheet,
    target: &Target,
    output_dpi: f64,
) -> Result<CheckReport, RenderError> {
    check_pages(
        &sheet.pages,
        &sheet.manifest.markers,
        target,
        Some(output_dpi),
    )
}

/// The same check for one marker laid out alone (`whycode marker`): a
/// marker file nobody can read is no better than a sheet of them. The file
/// ends at the marker's white margin, but it is printed on paper, so it is
/// checked lying on white.
pub fn check_marker_page(
    page: &Page,
    marker: &Marker,
    id: u32,
    target: &Target,
    png_dpi: Option<f64>,
) -> Result<CheckReport, RenderError> {
    let on_paper = page.on_white(marker.outer_radius());
    let Some((_, x_mm, y_mm)) = on_paper.markers().next() else {
        return Err(RenderError::SelfCheck {
            problem: "the page holds no marker".into(),
        });
    };
    let code = match marker.kind {
        MarkerKind::WhyCode { code, .. } => code,
        MarkerKind::WhyCon => 0,
    };
    let expected = PrintedMarker {
        id,
        code,
        page: 1,
        x_mm,
        y_mm,
        diameter_mm: marker.diameter_mm,
    };
    check_pages(
        std::slice::from_ref(&on_paper),
        &[expected],
        target,
        png_dpi,
    )
}

fn check_pages(
    pages: &[Page],
    markers: &[PrintedMarker],
    target: &Target,
    png_dpi: Option<f64>,
) -> Result<CheckReport, RenderError> {
    let mut resolutions = resolutions_for(markers, target.family());
    if let Some(dpi) = png_dpi.filter(|&d| d < PRINT_DPI && !resolutions.contains(&d)) {
        resolutions.push(dpi);
    }
    let jobs: Vec<(usize, f64)> = (0..pages.len())
        .flat_map(|p| resolutions.iter().map(move |&dpi| (p, dpi)))
        .collect();
    let failed = |problem: String| RenderError::SelfCheck { problem };
    let outcomes: Vec<Result<usize, RenderError>> = jobs
        .par_iter()
        .map(|&(p, dpi)| {
            let page = &pages[p];
            let expected: Vec<&PrintedMarker> = markers
                .iter()
                .filter(|m| m.page as usize == p + 1)
                .collect();
            let image = raster::render_page(page, dpi).map_err(|e| failed(e.to_string()))?;
            let mut detector = Detector::new(DetectorConfig {
                target: target.clone(),
                max_markers: expected.len() * 2 + 16,
                // A marker too small or too blurred to read is reported
                // as such, not as missing.
                report_unreadable: true,
                ..DetectorConfig::default()
            });
            let detections = detector.detect(&image);
            for m in &expected {
                check_marker(m, &detections, dpi, target.design()).map_err(|e| {
                    let across = m.diameter_mm * raster::px_per_mm(dpi);
                    failed(format!(
                        "{e} in a {dpi} dpi rendering, where it is {across:.0} px across"
                    ))
                })?;
            }
            Ok(expected.len())
        })
        .collect();
    let mut readings = 0;
    for outcome in outcomes {
        readings += outcome?;
    }
    Ok(CheckReport {
        resolutions,
        readings,
        design: target.design(),
    })
}
