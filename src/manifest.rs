//! The record of what a sheet printed, and the contract between the stages
//! that share it: `render` writes it next to every sheet, `simulate` lays
//! out a photographed sheet from it and `validate` reads it to know which
//! marker should be where.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// Why a manifest could not be used. Each message is one line that starts
/// with the file's name (or says which file it could not read).
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    /// The file could not be read.
    #[error("cannot read manifest {name}: {source}")]
    Io {
        /// The file's name.
        name: String,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// The text is not JSON of a manifest's shape.
    #[error("{name} is not a whycode sheet manifest: {source}")]
    Json {
        /// The file's name.
        name: String,
        /// What the JSON parser said.
        #[source]
        source: serde_json::Error,
    },
    /// Written by a newer whycode than this one.
    #[error(
        "{name}: manifest version {version} is newer than this tool reads ({MANIFEST_VERSION})"
    )]
    TooNew {
        /// The file's name.
        name: String,
        /// The version the file declares.
        version: u32,
    },
    /// Well-formed, but its content breaks what validation relies on
    /// (no markers, a marker off its page, an ID listed twice, ...).
    #[error("{name}: {problem}")]
    Invalid {
        /// The file's name.
        name: String,
        /// What is wrong, in words.
        problem: String,
    },
}

/// Current manifest format version.
pub const MANIFEST_VERSION: u32 = 1;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
/// What a sheet printed where: the contract between the renderer that writes it, the simulator that photographs it and the validator that checks photos of the print.
pub struct Manifest {
    /// Format name, always "whycode-sheet".
    #[serde(default = "format_name")]
    pub format: String,
    #[serde(default = "version_one")]
    /// Format version, [`MANIFEST_VERSION`] when written.
    pub version: u32,
    /// The tool that wrote it, e.g. "whycode 0.1.0".
    #[serde(default)]
    pub tool: String,
    /// The family the IDs belong to; absent for legacy WhyCon sheets.
    pub family: Option<FamilyRef>,
    #[serde(default)]
    /// True for a sheet of legacy WhyCon circles.
    pub legacy: bool,
    /// Name of the page template.
    #[serde(default)]
    pub template: String,
    /// Page width and height in millimetres.
    pub page_size_mm: [f64; 2],
    /// Number of pages.
    pub pages: u32,
    /// Every printed marker, in print order.
    pub markers: Vec<PrintedMarker>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
/// The family a sheet's IDs belong to: enough to generate it again.
pub struct FamilyRef {
    /// Code length.
    pub bits: u32,
    /// Minimum cyclic Hamming distance.
    pub distance: u32,
}

/// One printed marker. Positions are the marker centre, measured from the
/// page's top-left corner, y downwards.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PrintedMarker {
    /// Family ID (0 for a legacy WhyCon circle).
    pub id: u32,
    /// The code in the ring (0 for a legacy WhyCon circle).
    pub code: u32,
    /// Page number, from 1.
    pub page: u32,
    /// Centre, mm from the page's left edge.
    pub x_mm: f64,
    /// Centre, mm from the page's top edge.
    pub y_mm: f64,
    /// Diameter of the black disc as intended, mm.
    pub diameter_mm: f64,
}

fn format_name() -> String {
    "whycode-sheet".to_string()
}

fn version_one() -> u32 {
    MANIFEST_VERSION
}

impl Manifest {
    /// Reads and checks a manifest file; errors name the file.
    pub fn load(path: &Path) -> Result<Manifest, ManifestError> {
        let name = path.display().to_string();
        let text = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(source) => return Err(ManifestError::Io { name, source }),
        };
        Manifest::from_json(&name, &text)
    }

    /// Parses and checks a manifest's text; `name` (the file's name) starts
    /// every error message. For callers without files, such as the browser.
    pub fn from_json(name: &str, text: &str) -> Result<Manifest, ManifestError> {
        let manifest: Manifest =
            serde_json::from_str(text).map_err(|source| ManifestError::Json {
                name: name.to_string(),
                source,
            })?;
        if manifest.version > MANIFEST_VERSION {
            return Err(ManifestError::TooNew {
                name: name.to_string(),
                version: manifest.version,
            });
        }
        manifest.check().map_err(|problem| ManifestError::Invalid {
            name: name.to_string(),
            problem,
        })?;
        Ok(manifest)
    }

    /// What validation relies on: a hand-edited or foreign file that breaks
    /// it would otherwise give a verdict about nothing ("0 printed: OK") or
    /// about the wrong marker.
    fn check(&self) -> std::result::Result<(), String> {
        if self.format != "whycode-sheet" {
            return Err(format!(
                "format is '{}', not a whycode sheet manifest",
                self.format
            ));
        }
        let [w, h] = self.page_size_mm;
        if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
            return Err(format!("page size {w} x {h} mm is not a page"));
        }
        if self.markers.is_empty() {
            return Err("lists no markers".to_string());
        }
        let mut seen = std::collections::HashSet::new();
        for m in &self.markers {
            let inside = (0.0..=w).contains(&m.x_mm) && (0.0..=h).contains(&m.y_mm);
            if !(m.diameter_mm.is_finite() && m.diameter_mm > 0.0 && inside) {
                return Err(format!(
                    "marker ID {} on page {} has an impossible place or size",
                    m.id, m.page
                ));
            }
            if m.page == 0 || m.page > self.pages {
                return Err(format!(
                    "marker ID {} is on page {}, but the sheet has pages 1-{}",
                    m.id, m.page, self.pages
                ));
            }
            if !self.legacy && !seen.insert(m.id) {
                return Err(format!(
                    "ID {} is listed more than once, so its markers cannot be told apart",
                    m.id
                ));
            }
        }
        Ok(())
    }

    /// The manifest as the JSON the `sheet` command writes (stable field order).
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("manifest serialises");
        s.push('\n');
        s
    }

    #[cfg(feature = "files")]
    /// Writes the manifest whole or not at all.
    pub fn save(&self, path: &Path) -> anyhow::Result<()> {
        crate::io::write_atomic(path, self.to_json().as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sheet() -> Manifest {
        let marker = |id, x_mm| PrintedMarker {
            id,
            code: id,
            page: 1,
            x_mm,
            y_mm: 50.0,
            diameter_mm: 40.0,
        };
        Manifest {
            format: format_name(),
            version: MANIFEST_VERSION,
            tool: String::new(),
            family: Some(FamilyRef {
                bits: 8,
                distance: 2,
            }),
            legacy: false,
            template: "a4".into(),
            page_size_mm: [210.0, 297.0],
            pages: 1,
            markers: vec![marker(1, 40.0), marker(2, 100.0)],
        }
    }

    fn load_error(manifest: &Manifest) -> String {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        std::fs::write(&path, manifest.to_json()).unwrap();
        match Manifest::load(&path) {
            Ok(_) => String::new(),
            Err(e) => format!("{e:#}"),
        }
    }

    #[test]
    fn sound_manifests_load_and_broken_ones_name_the_problem() {
        assert_eq!(load_error(&sheet()), "");
        let mut m = sheet();
        m.markers[1].id = 1;
        assert!(load_error(&m).contains("ID 1 is listed more than once"));
        let mut m = sheet();
        m.markers.clear();
        assert!(load_error(&m).contains("lists no markers"));
        let mut m = sheet();
        m.page_size_mm = [0.0, 297.0];
        assert!(load_error(&m).contains("is not a page"));
        let mut m = sheet();
        m.markers[0].diameter_mm = -4.0;
        assert!(load_error(&m).contains("impossible place or size"));
        let mut m = sheet();
        m.markers[0].page = 3;
        assert!(load_error(&m).contains("on page 3, but the sheet has pages 1-1"));
        let mut m = sheet();
        m.format = "other".into();
        assert!(load_error(&m).contains("format is 'other'"));
    }
}
