//! Why rendering made no bytes: each case carries its values, and its
//! message is the one line every front end shows.

use crate::units::trim_float;
use std::path::PathBuf;

/// Why a marker, page or sheet could not be rendered or encoded.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The output's extension names no format this crate writes.
    #[error("{}: {}", path.display(), match extension {
        Some(ext) => format!("unknown output format '.{ext}' (use .svg, .pdf or .png)"),
        None => "no file extension to choose the format by (use .svg, .pdf or .png)".to_string(),
    })]
    UnknownFormat {
        /// The output.
        path: PathBuf,
        /// Its extension, if it has one.
        extension: Option<String>,
    },
    /// A PDF asked of a build without the `pdf` feature.
    #[error("{}: this build of whycode writes no PDF (it lacks the `pdf` feature)", path.display())]
    NoPdf {
        /// The output.
        path: PathBuf,
    },
    /// An ID the family does not have.
    #[error("ID {id} is not in the {bits}-bit distance-{distance} family ({})", match count {
        0 => "it has no IDs".to_string(),
        n => format!("IDs 1-{n}"),
    })]
    IdOutOfRange {
        /// The ID asked for.
        id: u32,
        /// The family's bit count.
        bits: u32,
        /// The family's minimum distance.
        distance: u32,
        /// How many IDs the family has.
        count: usize,
    },
    /// A marker of no size (or not a number).
    #[error("the marker diameter must be positive")]
    DiameterNotPositive {
        /// The diameter asked for, mm.
        diameter_mm: f64,
    },
    /// A white margin narrower than the detector needs.
    #[error(
        "a margin of {} mm is too small for a {} mm marker: the detector needs at least {} mm ({}R) of white around the black disc",
        trim_float(*margin_mm),
        trim_float(*diameter_mm),
        trim_float((least_mm * 100.0).ceil() / 100.0),
        crate::geometry::MIN_MARGIN_RATIO
    )]
    MarginTooSmall {
        /// The margin asked for, mm.
        margin_mm: f64,
        /// The marker's diameter, mm.
        diameter_mm: f64,
        /// The least margin the detector needs, mm.
        least_mm: f64,
    },
    /// A sheet of no markers.
    #[error("no markers to print")]
    NoMarkers,
    /// A sheet whose markers differ in size.
    #[error("all markers on a sheet must have the same diameter")]
    MixedDiameters,
    /// A marker larger than the template's printable area.
    #[error(
        "a {} mm marker does not fit on the {template} page ({} x {} mm, {} mm margins); the largest that fits is {} mm",
        trim_float(*diameter_mm),
        trim_float(*page_width_mm),
        trim_float(*page_height_mm),
        trim_float(*margin_mm),
        trim_float(*largest_mm)
    )]
    DoesNotFit {
        /// The marker's diameter, mm.
        diameter_mm: f64,
        /// The template's name.
        template: String,
        /// The page's width, mm.
        page_width_mm: f64,
        /// The page's height, mm.
        page_height_mm: f64,
        /// The template's margins, mm.
        margin_mm: f64,
        /// The largest diameter that fits, mm.
        largest_mm: f64,
    },
    /// A raster resolution that is not a positive number.
    #[error("resolution must be a positive number of dpi, got {dpi}")]
    DpiOutOfRange {
        /// The resolution asked for.
        dpi: f64,
    },
    /// A raster too large to hold.
    #[error(
        "a {width_mm:.0} x {height_mm:.0} mm page at {dpi} dpi would be {width} x {height} pixels, too large"
    )]
    RasterTooLarge {
        /// The page's width, mm.
        width_mm: f64,
        /// The page's height, mm.
        height_mm: f64,
        /// The resolution asked for.
        dpi: f64,
        /// The raster's width, pixels.
        width: u32,
        /// The raster's height, pixels.
        height: u32,
    },
    /// An image too large to draw on.
    #[error("a {width}x{height} image is too large to draw on")]
    ImageTooLarge {
        /// The image's width, pixels.
        width: u32,
        /// The image's height, pixels.
        height: u32,
    },
    /// The encoder of a format failed.
    #[error("cannot encode {format}: {detail}")]
    Encode {
        /// "PNG" or "PDF".
        format: &'static str,
        /// What the encoder said.
        detail: String,
    },
    /// A rendering the detector could not read back as printed.
    #[error("self-check failed: {problem}")]
    SelfCheck {
        /// Which marker, at which resolution, and what went wrong.
        problem: String,
    },
}
