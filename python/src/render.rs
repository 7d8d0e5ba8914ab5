//! `render_marker`, `render_sheet`, `render_marker_image`, `templates`.

use crate::family::PyFamily;
use crate::{guard, Error};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::{Path, PathBuf};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::render::job::{MarkerJob, SheetJob};
use whycode::render::sheet::id_range_error;
use whycode::render::{write_all, Format, Template};
use whycode::spec::TargetSpec;

/// The output format: from `output`'s extension, else from `format`.
fn output_format(format: Option<&str>, output: Option<&Path>) -> crate::Result<Format> {
    let from_name = |name: &str| match name.to_ascii_lowercase().as_str() {
        "svg" => Ok(Format::Svg),
        "pdf" => Ok(Format::Pdf),
        "png" => Ok(Format::Png),
        other => Err(Error::value(format!(
            "format '{other}' is not one of 'svg', 'pdf', 'png'"
        ))),
    };
    match (format, output) {
        (None, None) => Err(Error::value(
            "say what to render: format='svg', 'pdf' or 'png', or an output path",
        )),
        (Some(f), None) => from_name(f),
        (f, Some(path)) => {
            let by_path = Format::from_path(path)?;
            if let Some(f) = f {
                if from_name(f)? != by_path {
                    return Err(Error::value(format!(
                        "format '{f}' disagrees with the extension of {}",
                        path.display()
                    )));
                }
            }
            Ok(by_path)
        }
    }
}

fn extension(format: Format) -> &'static str {
    match format {
        Format::Svg => "svg",
        Format::Pdf => "pdf",
        Format::Png => "png",
    }
}

/// The family a print job draws (`None`: legacy circles), resolved as
/// every front end resolves it.
fn printed_family(
    family: Option<PyRef<'_, PyFamily>>,
    legacy: bool,
) -> crate::Result<Option<Family>> {
    TargetSpec {
        legacy,
        family: family.map(|f| f.family.clone()),
        ..TargetSpec::default()
    }
    .printable_family()
    .map_err(crate::spec_error)
}

/// Print files name families by bits and distance: a family from a file
/// whose codes differ from the generated one could not be named.
fn check_generated(family: &Family) -> crate::Result<()> {
    if Family::generate(family.bits(), family.distance()).as_ref() != Ok(family) {
        return Err(Error::value(format!(
            "this family's codes differ from the generated {}-bit distance-{} family, which print files name; render with Family({}, {})",
            family.bits(),
            family.distance(),
            family.bits(),
            family.distance()
        )));
    }
    Ok(())
}

/// One marker at exact physical size as SVG, PDF or PNG bytes; with
/// `output`, also written there (whole or not at all). The rendering is
/// read back before it is returned unless `check=False`.
#[pyfunction]
#[pyo3(signature = (id = None, *, diameter, family = None, legacy = false, format = None, output = None, margin = None, dpi = 300.0, cross = false, cut_guide = false, label = false, check = true))]
#[allow(clippy::too_many_arguments)]
fn render_marker<'py>(
    py: Python<'py>,
    id: Option<u32>,
    diameter: &Bound<'py, PyAny>,
    family: Option<PyRef<'py, PyFamily>>,
    legacy: bool,
    format: Option<&str>,
    output: Option<PathBuf>,
    margin: Option<&Bound<'py, PyAny>>,
    dpi: f64,
    cross: bool,
    cut_guide: bool,
    label: bool,
    check: bool,
) -> PyResult<Bound<'py, PyBytes>> {
    let diameter = crate::length(diameter, "diameter")?.mm();
    let margin_mm = margin
        .map(|m| crate::length(m, "margin").map(|l| l.mm()))
        .transpose()?;
    let format = output_format(format, output.as_deref())?;
    let family = printed_family(family, legacy)?;
    let bytes = py.detach(|| {
        guard(|| {
            if let Some(path) = &output {
                whycode::render::check_output_dir(path)?;
            }
            if let Some(family) = &family {
                check_generated(family)?;
            }
            let job = MarkerJob {
                family: family.as_ref(),
                id,
                diameter_mm: diameter,
                margin_mm,
                cross,
                cut_guide,
                label,
                dpi,
                self_check: check,
            };
            let path = output
                .clone()
                .unwrap_or_else(|| PathBuf::from(format!("marker.{}", extension(format))));
            let (mut files, _) = job.print(&path)?;
            if output.is_some() {
                write_all(&files)?;
            }
            Ok(files.swap_remove(0).1)
        })
    })?;
    Ok(PyBytes::new(py, &bytes))
}

/// Markers laid out on print pages. Returns (pages, manifest): one bytes
/// object per page for SVG and PNG, one for the whole PDF, and the manifest
/// as a dict. With `output`, writes the files `whycode sheet -o OUTPUT`
/// writes (pages and OUTPUT.json), all or none.
#[pyfunction]
#[pyo3(signature = (ids = None, *, family = None, legacy = false, count = None, diameter = None, template = "a4", format = None, output = None, name = None, dpi = 300.0, check = true))]
#[allow(clippy::too_many_arguments)]
fn render_sheet<'py>(
    py: Python<'py>,
    ids: Option<Vec<u32>>,
    family: Option<PyRef<'py, PyFamily>>,
    legacy: bool,
    count: Option<usize>,
    diameter: Option<&Bound<'py, PyAny>>,
    template: &str,
    format: Option<&str>,
    output: Option<PathBuf>,
    name: Option<String>,
    dpi: f64,
    check: bool,
) -> PyResult<(Vec<Bound<'py, PyBytes>>, Bound<'py, PyAny>)> {
    let diameter = match diameter {
        Some(d) => crate::length(d, "diameter")?.mm(),
        None => 40.0,
    };
    let format = output_format(format, output.as_deref())?;
    if legacy && ids.is_some() {
        return Err(Error::value("ids: legacy circles have no IDs (give count)").into());
    }
    if legacy != count.is_some() {
        return Err(Error::value("count goes with legacy=True (and legacy needs a count)").into());
    }
    let family = printed_family(family, legacy)?;
    let name = match (&name, &output) {
        (Some(n), _) => n.clone(),
        (None, Some(path)) => path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        (None, None) => "swarm".to_string(),
    };
    let template = template.to_string();
    let (files, manifest) = py.detach(|| {
        guard(|| {
            if let Some(path) = &output {
                whycode::render::check_output_dir(path)?;
            }
            let template = Template::resolve(&template)?;
            if let Some(family) = &family {
                check_generated(family)?;
            }
            let job = SheetJob {
                family: family.as_ref(),
                ids: ids.clone(),
                count,
                diameter_mm: diameter,
                template,
                name: name.clone(),
                dpi,
                self_check: check,
            };
            let path = output
                .clone()
                .unwrap_or_else(|| PathBuf::from(format!("{name}.{}", extension(format))));
            let printed = job.print(&path)?;
            let manifest = printed.manifest.1.clone();
            let pages = printed.pages.len();
            let mut files = printed.into_files();
            if output.is_some() {
                write_all(&files)?;
            }
            files.truncate(pages);
            Ok((files, manifest))
        })
    })?;
    let pages = files
        .iter()
        .map(|(_, bytes)| PyBytes::new(py, bytes))
        .collect();
    Ok((pages, crate::json_to_py(py, &manifest)?))
}

/// One marker rendered into an HxW uint8 array (white margin around the
/// black disc), for synthetic tests: the disc is `diameter_px` across.
#[pyfunction]
#[pyo3(signature = (id = None, *, family = None, legacy = false, diameter_px = 100.0, margin_px = None))]
fn render_marker_image<'py>(
    py: Python<'py>,
    id: Option<u32>,
    family: Option<PyRef<'py, PyFamily>>,
    legacy: bool,
    diameter_px: f64,
    margin_px: Option<f64>,
) -> PyResult<Bound<'py, numpy::PyArray2<u8>>> {
    if !(diameter_px.is_finite() && (4.0..=20_000.0).contains(&diameter_px)) {
        return Err(Error::value("diameter_px must be between 4 and 20000").into());
    }
    let margin_px = margin_px.unwrap_or(diameter_px * 0.25);
    if !(margin_px.is_finite() && (0.0..=20_000.0).contains(&margin_px)) {
        return Err(Error::value("margin_px must be between 0 and 20000").into());
    }
    let marker = match printed_family(family, legacy)? {
        None if id.is_some() => {
            return Err(Error::value("id: a legacy WhyCon marker has no ID").into())
        }
        None => Marker::whycon(diameter_px / 10.0),
        Some(family) => {
            let id =
                id.ok_or_else(|| Error::value("render_marker_image needs an id (or legacy=True)"))?;
            let code = family
                .code(id)
                .ok_or_else(|| Error::value(id_range_error(&family, id).to_string()))?;
            Marker::whycode(family.bits(), code, diameter_px / 10.0)
        }
    };
    // 254 dpi is 10 pixels per millimetre: millimetres are tenths of pixels.
    let image = py.detach(|| {
        guard(|| {
            Ok(whycode::render::render_marker(
                &marker,
                margin_px / 10.0,
                254.0,
            )?)
        })
    })?;
    crate::pixels::to_array(py, image)
}

/// The built-in page templates: name -> (width_mm, height_mm, margin_mm, description).
#[pyfunction]
fn templates() -> Vec<(String, f64, f64, f64, String)> {
    Template::all_builtin()
        .into_iter()
        .map(|t| {
            (
                t.name,
                t.page_width_mm,
                t.page_height_mm,
                t.margin_mm,
                t.description,
            )
        })
        .collect()
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render_marker, m)?)?;
    m.add_function(wrap_pyfunction!(render_sheet, m)?)?;
    m.add_function(wrap_pyfunction!(render_marker_image, m)?)?;
    m.add_function(wrap_pyfunction!(templates, m)?)?;
    Ok(())
}
