//! Rendering markers and print sheets at exact physical size.
//!
//! Everything is first laid out as [`page::Page`]s (items in millimetres,
//! markers drawn from [`crate::geometry::Marker::shapes`]); the SVG, PDF and
//! PNG writers and the rasteriser used for checking all draw those pages.

pub mod check;
mod error;
pub mod font;
pub mod job;
pub mod marker;
pub mod page;
#[cfg(feature = "pdf")]
pub mod pdf;
pub mod png;
pub mod raster;
pub mod sheet;
pub mod svg;
pub mod template;

pub use error::RenderError;
pub use marker::{marker_page, MarkerOptions};
pub use page::{Item, Page};
pub use raster::{render_marker, render_page};
pub use sheet::{layout, Sheet, SheetMarker, SheetSpec};
pub use template::Template;

use std::path::{Path, PathBuf};

/// Output file formats, chosen by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// SVG, for editing and the web.
    Svg,
    /// PDF, for printing at exact size.
    Pdf,
    /// PNG at print resolution.
    Png,
}

impl Format {
    /// The format named by the file's extension, or an error naming the file.
    pub fn from_path(path: &Path) -> Result<Format, RenderError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("pdf") => Ok(Format::Pdf),
            Some("png") => Ok(Format::Png),
            _ => Err(RenderError::UnknownFormat {
                path: path.to_path_buf(),
                extension: ext,
            }),
        }
    }
}

/// Paths of a multi-page output: one page keeps the given name; several
/// pages in SVG or PNG become `stem-1.ext`, `stem-2.ext`, ...
pub fn page_paths(path: &Path, pages: usize) -> Vec<PathBuf> {
    if pages <= 1 {
        return vec![path.to_path_buf()];
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    (1..=pages)
        .map(|k| path.with_file_name(format!("{stem}-{k}.{ext}")))
        .collect()
}

/// Encodes pages for `path`'s format: one file for PDF, one per page for SVG
/// and PNG. Nothing is written; the caller writes all files or none.
pub fn encode_pages(
    pages: &[Page],
    path: &Path,
    title: &str,
    dpi: f64,
) -> Result<Vec<(PathBuf, Vec<u8>)>, RenderError> {
    let format = Format::from_path(path)?;
    Ok(match format {
        #[cfg(feature = "pdf")]
        Format::Pdf => vec![(path.to_path_buf(), pdf::pages_pdf(pages, title)?)],
        #[cfg(not(feature = "pdf"))]
        Format::Pdf => {
            return Err(RenderError::NoPdf {
                path: path.to_path_buf(),
            })
        }
        Format::Svg => page_paths(path, pages.len())
            .into_iter()
            .zip(pages)
            .map(|(p, page)| (p, svg::page_svg(page, title).into_bytes()))
            .collect(),
        Format::Png => {
            let mut out = Vec::with_capacity(pages.len());
            for (p, page) in page_paths(path, pages.len()).into_iter().zip(pages) {
                out.push((p, png::page_png(page, dpi)?));
            }
            out
        }
    })
}

/// Fails early, before any rendering, when the output's folder is missing.
#[cfg(feature = "files")]
pub fn check_output_dir(path: &Path) -> Result<(), crate::error::WriteError> {
    crate::io::check_output_dir(path)
}

/// Writes a sheet's or marker's files together: all of them, or (when one
/// cannot be written) none, with any earlier outputs left as they were.
#[cfg(feature = "files")]
pub fn write_all(files: &[(PathBuf, Vec<u8>)]) -> Result<(), crate::error::WriteError> {
    crate::io::write_all_atomic(files)
}
