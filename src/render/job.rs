//! Print jobs: what `whycode marker` and `whycode sheet` make, as files in
//! memory. The CLI writes them, the Python package returns or writes them,
//! the web page offers them for download; all three make the same bytes
//! because all three come through here (titles, label sizes, which
//! self-check a format gets, the manifest's name).

use super::check::{check_marker_page, check_sheet, check_sheet_png, CheckReport};
use super::marker::{marker_label, marker_page, MarkerOptions, DEFAULT_LABEL_PT};
use super::sheet::{chosen_markers, id_range_error, layout, SheetSpec};
use super::template::Template;
use super::{encode_pages, Format};
use crate::detect::Target;
use crate::family::Family;
use crate::fileset::FileDigest;
use crate::geometry::Marker;
use crate::limits;
use crate::spec_error::{within, SpecError};
use std::path::{Path, PathBuf};

/// Why a print job made no files: an option's value (which front ends word
/// in their own option names), or the rendering itself.
#[derive(Debug, thiserror::Error)]
pub enum PrintError {
    /// An option's value is wrong.
    #[error(transparent)]
    Option(#[from] SpecError),
    /// Laying out, encoding or reading back the pages failed.
    #[error(transparent)]
    Render(#[from] super::RenderError),
}

type Result<T> = std::result::Result<T, PrintError>;

/// The checks every print job makes of its options, whatever the format.
fn check_common(format: Format, diameter_mm: f64, dpi: f64) -> Result<()> {
    within("diameter", diameter_mm, limits::MARKER_DIAMETER_MM)?;
    // PDF and SVG are exact at any size; only a raster has a resolution.
    if format == Format::Png {
        within("dpi", dpi, limits::DPI)?;
    }
    Ok(())
}

/// Files to write together (all or none) or hand over, in order.
pub type Files = Vec<(PathBuf, Vec<u8>)>;

/// One marker on its own page, as `whycode marker` makes it.
#[derive(Debug, Clone)]
pub struct MarkerJob<'a> {
    /// The marker's family; `None` for a legacy WhyCon circle.
    pub family: Option<&'a Family>,
    /// The marker's ID in `family` (required with a family, refused without).
    pub id: Option<u32>,
    /// Outer diameter of the black disc, mm.
    pub diameter_mm: f64,
    /// White margin round the disc, mm; `None` means the least allowed.
    pub margin_mm: Option<f64>,
    /// A thin grey cross in the white centre.
    pub cross: bool,
    /// A dashed circle to cut along.
    pub cut_guide: bool,
    /// A label (ID, family, diameter) under the marker.
    pub label: bool,
    /// PNG resolution, dots per inch (ignored by SVG and PDF).
    pub dpi: f64,
    /// Read the marker back from a rendering before handing it over.
    pub self_check: bool,
}

/// Markers laid out on print pages, as `whycode sheet` makes them.
#[derive(Debug, Clone)]
pub struct SheetJob<'a> {
    /// The markers' family; `None` for legacy WhyCon circles.
    pub family: Option<&'a Family>,
    /// IDs to print, in this order; `None` prints the whole family.
    pub ids: Option<Vec<u32>>,
    /// How many legacy circles (legacy only).
    pub count: Option<usize>,
    /// Outer diameter of every black disc, mm.
    pub diameter_mm: f64,
    /// Page size, margins and spacing.
    pub template: Template,
    /// The sheet's name: the PDF's title and the manifest's `name`.
    pub name: String,
    /// PNG resolution, dots per inch (ignored by SVG and PDF).
    pub dpi: f64,
    /// Read every marker back from renderings before handing the pages over.
    pub self_check: bool,
}

/// A printed sheet: its page files, its manifest, and what the check did.
#[derive(Debug, Clone)]
pub struct PrintedSheet {
    /// One file for a PDF, one per page for SVG and PNG.
    pub pages: Files,
    /// Where the manifest goes (the output's name with `.json`), and its JSON.
    pub manifest: (PathBuf, String),
    /// How many markers the sheet holds.
    pub markers: usize,
    /// How many pages they fill (a PDF holds them all in one file).
    pub page_count: usize,
    /// What the self-check did; `None` when it was skipped.
    pub check: Option<CheckReport>,
}

impl PrintedSheet {
    /// Every file `whycode sheet` writes: the pages, then the manifest.
    pub fn into_files(self) -> Files {
        let mut files = self.pages;
        let (path, json) = self.manifest;
        files.push((path, json.into_bytes()));
        files
    }

    /// "16 markers on 2 pages".
    pub fn summary(&self) -> String {
        format!(
            "{} markers on {} page{}",
            self.markers,
            self.page_count,
            if self.page_count == 1 { "" } else { "s" }
        )
    }
}

fn target(family: Option<&Family>) -> Target {
    match family {
        Some(family) => Target::WhyCode(family.clone()),
        None => Target::WhyCon,
    }
}

impl MarkerJob<'_> {
    /// The marker's file for `output` (whose extension picks the format),
    /// and what the self-check did.
    pub fn print(&self, output: &Path) -> Result<(Files, Option<CheckReport>)> {
        let format = Format::from_path(output)?;
        check_common(format, self.diameter_mm, self.dpi)?;
        let (marker, title) = match (self.family, self.id) {
            (None, None) => (
                Marker::whycon(self.diameter_mm),
                "WhyCon marker".to_string(),
            ),
            (None, Some(_)) => {
                return Err(SpecError::invalid("id", "a legacy WhyCon marker has no ID").into())
            }
            (Some(_), None) => {
                return Err(SpecError::invalid("id", "choose the marker's ID").into())
            }
            (Some(family), Some(id)) => {
                let Some(code) = family.code(id) else {
                    return Err(
                        SpecError::invalid("id", id_range_error(family, id).to_string()).into(),
                    );
                };
                (
                    Marker::whycode(family.bits(), code, self.diameter_mm),
                    format!(
                        "WhyCode {}-bit d{} ID {id}",
                        family.bits(),
                        family.distance()
                    ),
                )
            }
        };
        let label = self
            .label
            .then(|| marker_label(&marker, self.id, self.family.map(Family::distance)));
        let options = MarkerOptions {
            margin_mm: self.margin_mm,
            cross: self.cross,
            cut_guide: self.cut_guide,
            label,
            // Larger markers are looked at from further away: grow the label with them.
            label_size_pt: (self.diameter_mm / 8.0).clamp(DEFAULT_LABEL_PT, 14.0),
        };
        let page = marker_page(&marker, &options)?;
        let check = if self.self_check {
            // A PNG is printed as rasterised here, so its own dpi is checked too.
            let png_dpi = (format == Format::Png).then_some(self.dpi);
            let id = self.id.unwrap_or(0);
            Some(check_marker_page(
                &page,
                &marker,
                id,
                &target(self.family),
                png_dpi,
            )?)
        } else {
            None
        };
        let files = encode_pages(std::slice::from_ref(&page), output, &title, self.dpi)?;
        Ok((files, check))
    }
}

impl SheetJob<'_> {
    /// The sheet's files for `output` (whose extension picks the format:
    /// several SVG or PNG pages become `name-1.svg`, ...).
    pub fn print(&self, output: &Path) -> Result<PrintedSheet> {
        let format = Format::from_path(output)?;
        check_common(format, self.diameter_mm, self.dpi)?;
        let (markers, family) =
            chosen_markers(self.family, self.ids.clone(), self.count, self.diameter_mm)?;
        let spec = SheetSpec {
            markers,
            template: self.template.clone(),
            name: self.name.clone(),
            family,
            legacy: self.family.is_none(),
        };
        let mut sheet = layout(&spec)?;
        let check = if !self.self_check {
            None
        } else if format == Format::Png {
            Some(check_sheet_png(&sheet, &target(self.family), self.dpi)?)
        } else {
            Some(check_sheet(&sheet, &target(self.family))?)
        };
        let pages = encode_pages(&sheet.pages, output, &self.name, self.dpi)?;
        // The manifest is renamed into place last and names the pages it
        // belongs to, so a set mixed by an interrupted run is recognisable.
        sheet.manifest.files = pages
            .iter()
            .map(|(path, bytes)| FileDigest::of(path, bytes))
            .collect();
        Ok(PrintedSheet {
            pages,
            manifest: (output.with_extension("json"), sheet.manifest.to_json()),
            markers: sheet.manifest.markers.len(),
            page_count: sheet.pages.len(),
            check,
        })
    }
}
