//! The record of what a sheet printed: written next to every sheet, read by
//! validation to know which marker should be where.

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Current manifest format version.
pub const MANIFEST_VERSION: u32 = 1;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Format name, always "whycode-sheet".
    #[serde(default = "format_name")]
    pub format: String,
    #[serde(default = "version_one")]
    pub version: u32,
    /// The tool that wrote it, e.g. "whycode 0.1.0".
    #[serde(default)]
    pub tool: String,
    /// The family the IDs belong to; absent for legacy WhyCon sheets.
    pub family: Option<FamilyRef>,
    #[serde(default)]
    pub legacy: bool,
    /// Name of the page template.
    #[serde(default)]
    pub template: String,
    /// Page width and height in millimetres.
    pub page_size_mm: [f64; 2],
    pub pages: u32,
    pub markers: Vec<PrintedMarker>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FamilyRef {
    pub bits: u32,
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
    pub x_mm: f64,
    pub y_mm: f64,
    pub diameter_mm: f64,
}

fn format_name() -> String {
    "whycode-sheet".to_string()
}

fn version_one() -> u32 {
    MANIFEST_VERSION
}

impl Manifest {
    pub fn load(path: &Path) -> Result<Manifest> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read manifest {}", path.display()))?;
        let manifest: Manifest = serde_json::from_str(&text)
            .with_context(|| format!("{} is not a whycode sheet manifest", path.display()))?;
        if manifest.version > MANIFEST_VERSION {
            anyhow::bail!(
                "{}: manifest version {} is newer than this tool reads ({MANIFEST_VERSION})",
                path.display(),
                manifest.version
            );
        }
        Ok(manifest)
    }

    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("manifest serialises");
        s.push('\n');
        s
    }

    pub fn save(&self, path: &Path) -> Result<()> {
        crate::io::write_atomic(path, self.to_json().as_bytes())
    }
}
