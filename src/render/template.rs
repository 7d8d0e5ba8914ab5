//! Page templates for print sheets: small TOML files, the standard ones built
//! into the binary from `templates/`, a user's own loaded from a path.

use crate::error::{refuse, FileKind, LoadError, LoadProblem};
use crate::units::Length;
use serde::Deserialize;
use std::path::Path;

/// The built-in templates, by name, as TOML text.
const BUILTIN: &[(&str, &str)] = &[
    ("a3", include_str!("../../templates/a3.toml")),
    ("a4", include_str!("../../templates/a4.toml")),
    ("a5", include_str!("../../templates/a5.toml")),
    ("legal", include_str!("../../templates/legal.toml")),
    ("letter", include_str!("../../templates/letter.toml")),
];

/// A sheet layout: page size and the spacing and decorations around markers.
#[derive(Debug, Clone, PartialEq)]
pub struct Template {
    /// The built-in name, or the file path the template came from.
    pub name: String,
    /// One line saying what the template is for.
    pub description: String,
    /// Page width, mm.
    pub page_width_mm: f64,
    /// Page height, mm.
    pub page_height_mm: f64,
    /// White border kept free of markers, mm (printers cannot print to the edge).
    pub margin_mm: f64,
    /// Space between neighbouring markers' cells, mm.
    pub gap_mm: f64,
    /// Size of the marker labels, points.
    pub label_size_pt: f64,
    /// Dashed circles to cut markers out along.
    pub cut_guides: bool,
    /// Length of the printed scale bar, mm (0 for none): a ruler on the page tells a wrongly scaled print at a glance.
    pub scale_bar_mm: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TemplateFile {
    #[serde(default)]
    description: String,
    page_width: String,
    page_height: String,
    margin: String,
    #[serde(default = "default_gap")]
    gap: String,
    #[serde(default = "default_label_size")]
    label_size_pt: f64,
    #[serde(default)]
    cut_guides: bool,
    #[serde(default = "default_scale_bar")]
    scale_bar: String,
}

fn default_gap() -> String {
    "3mm".to_string()
}

fn default_label_size() -> f64 {
    7.0
}

fn default_scale_bar() -> String {
    "100mm".to_string()
}

fn length(field: &str, text: &str) -> Result<f64, LoadProblem> {
    text.parse::<Length>()
        .map(Length::mm)
        .map_err(|e| LoadProblem::Invalid(format!("{field}: {e}")))
}

fn zero_or_length(field: &str, text: &str) -> Result<f64, LoadProblem> {
    if text.trim().trim_end_matches(|c: char| c.is_alphabetic()) == "0" {
        return Ok(0.0);
    }
    length(field, text)
}

pub use crate::limits::MAX_PAGE_MM;

impl Template {
    /// Parses a template's TOML text; `name` (the file's name) starts every
    /// error message.
    pub fn parse(name: &str, text: &str) -> Result<Template, LoadError> {
        Template::checked(name, text)
            .map_err(|problem| LoadError::new(Path::new(name), FileKind::Template, problem))
    }

    fn checked(name: &str, text: &str) -> Result<Template, LoadProblem> {
        let file: TemplateFile = toml::from_str(text).map_err(|e| {
            LoadProblem::Invalid(
                e.to_string()
                    .lines()
                    .collect::<Vec<_>>()
                    .join(" ")
                    .trim()
                    .to_string(),
            )
        })?;
        let template = Template {
            name: name.to_string(),
            description: file.description,
            page_width_mm: length("page_width", &file.page_width)?,
            page_height_mm: length("page_height", &file.page_height)?,
            margin_mm: zero_or_length("margin", &file.margin)?,
            gap_mm: zero_or_length("gap", &file.gap)?,
            label_size_pt: file.label_size_pt,
            cut_guides: file.cut_guides,
            scale_bar_mm: length("scale_bar", &file.scale_bar)?,
        };
        if !(template.label_size_pt.is_finite() && (3.0..=36.0).contains(&template.label_size_pt)) {
            refuse!(
                "label_size_pt must be between 3 and 36, got {}",
                template.label_size_pt
            );
        }
        for (field, mm) in [
            ("page_width", template.page_width_mm),
            ("page_height", template.page_height_mm),
        ] {
            if !(mm > 0.0 && mm <= MAX_PAGE_MM) {
                refuse!(
                    "{field} must be more than 0 and at most {} m (a plotter roll), got {} mm",
                    MAX_PAGE_MM / 1000.0,
                    crate::units::trim_float(mm)
                );
            }
        }
        if 2.0 * template.margin_mm >= template.page_width_mm.min(template.page_height_mm) {
            refuse!("the margins leave no room on the page");
        }
        // A gap wider than the page leaves room for one marker per page and
        // made the hexagonal packing search for hours.
        if template.gap_mm >= template.page_width_mm.min(template.page_height_mm) {
            refuse!(
                "gap {} mm is wider than the page",
                crate::units::trim_float(template.gap_mm)
            );
        }
        Ok(template)
    }

    /// A built-in template by name (case-insensitive).
    pub fn builtin(name: &str) -> Result<Template, LoadError> {
        let lower = name.to_ascii_lowercase();
        let Some((key, text)) = BUILTIN.iter().find(|(k, _)| *k == lower) else {
            return Err(LoadError::invalid_text(
                FileKind::Template,
                format!(
                    "unknown template '{name}' (known: {}; or give a path to a .toml file)",
                    builtin_names().join(", ")
                ),
            ));
        };
        Template::parse(key, text)
    }

    /// A user's template file.
    pub fn load(path: &Path) -> Result<Template, LoadError> {
        let text = crate::input::read_text(path, FileKind::Template)?;
        Template::parse(&path.display().to_string(), &text)
    }

    /// A built-in name, or a path when the argument looks like one
    /// (contains a path separator or ends in .toml).
    pub fn resolve(name_or_path: &str) -> Result<Template, LoadError> {
        let looks_like_path = name_or_path.contains('/')
            || name_or_path.contains(std::path::MAIN_SEPARATOR)
            || name_or_path.to_ascii_lowercase().ends_with(".toml");
        if looks_like_path {
            Template::load(Path::new(name_or_path))
        } else {
            Template::builtin(name_or_path)
        }
    }

    /// All built-in templates.
    pub fn all_builtin() -> Vec<Template> {
        BUILTIN
            .iter()
            .map(|(k, _)| Template::builtin(k).expect("built-in templates parse"))
            .collect()
    }
}

/// Names of the built-in templates.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(k, _)| *k).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_templates_parse_with_their_paper_sizes() {
        let a4 = Template::builtin("A4").unwrap();
        assert_eq!((a4.page_width_mm, a4.page_height_mm), (210.0, 297.0));
        let letter = Template::builtin("letter").unwrap();
        assert!((letter.page_width_mm - 215.9).abs() < 1e-9);
        assert!((letter.page_height_mm - 279.4).abs() < 1e-9);
        assert_eq!(Template::all_builtin().len(), 5);
    }

    #[test]
    fn unknown_names_list_the_known_ones() {
        let err = Template::builtin("a7").unwrap_err().to_string();
        assert!(err.contains("a3, a4, a5, legal, letter"), "{err}");
    }

    #[test]
    fn typos_in_fields_are_refused() {
        let err = Template::parse(
            "x",
            "page_width = \"100mm\"\npage_height = \"100mm\"\nmargin = \"5mm\"\nmargn = 3",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("margn"), "{err}");
    }
}
