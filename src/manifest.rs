//! The record of what a sheet printed, and the contract between the stages
//! that share it: `render` writes it next to every sheet, `simulate` lays
//! out a photographed sheet from it and `validate` reads it to know which
//! marker should be where.

use crate::error::{refuse, FileKind, LoadError, LoadProblem};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Current manifest format version.
pub const MANIFEST_VERSION: u32 = 1;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
/// What a sheet printed where: the contract between the renderer that writes it, the simulator that photographs it and the validator that checks photos of the print.
pub struct Manifest {
    /// Format name, always "whycode-sheet" (required: a file without it
    /// is something else that happens to have the same fields).
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
    /// The page files written with this manifest, with their digests
    /// (`fileset`): a reader can tell a PDF from another run beside it.
    /// Absent in manifests from before it was recorded, and in those made
    /// by hand.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<crate::fileset::FileDigest>,
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

fn version_one() -> u32 {
    MANIFEST_VERSION
}

impl Manifest {
    /// Reads and checks a manifest file; errors name the file.
    pub fn load(path: &Path) -> Result<Manifest, LoadError> {
        let text = crate::input::read_text(path, FileKind::Manifest)?;
        let manifest = Manifest::from_json(&path.display().to_string(), &text)?;
        // The pages it lists are what it describes: a command reading the
        // manifest depends on them as much as on the manifest itself.
        let folder = path.parent().unwrap_or(Path::new(""));
        for file in &manifest.files {
            crate::input::note(&folder.join(&file.file));
        }
        Ok(manifest)
    }

    /// Parses and checks a manifest's text; `name` (the file's name) starts
    /// every error message. For callers without files, such as the browser.
    pub fn from_json(name: &str, text: &str) -> Result<Manifest, LoadError> {
        let invalid = |problem| LoadError::new(Path::new(name), FileKind::Manifest, problem);
        let manifest: Manifest = serde_json::from_str(text).map_err(|e| {
            invalid(LoadProblem::Invalid(format!(
                "not a whycode sheet manifest: {e}"
            )))
        })?;
        if manifest.version > MANIFEST_VERSION {
            return Err(invalid(LoadProblem::Invalid(format!(
                "manifest version {} is newer than this tool reads ({MANIFEST_VERSION})",
                manifest.version
            ))));
        }
        manifest.check().map_err(invalid)?;
        Ok(manifest)
    }

    /// What validation relies on: a hand-edited or foreign file that breaks
    /// it would otherwise give a verdict about nothing ("0 printed: OK") or
    /// about the wrong marker.
    fn check(&self) -> std::result::Result<(), LoadProblem> {
        if self.format != "whycode-sheet" {
            refuse!("format is '{}', not a whycode sheet manifest", self.format);
        }
        let [w, h] = self.page_size_mm;
        let side = 0.0..=crate::limits::MAX_PAGE_MM;
        if !(w > 0.0 && h > 0.0 && side.contains(&w) && side.contains(&h)) {
            refuse!("page size {w} x {h} mm is not a page");
        }
        if self.markers.is_empty() {
            refuse!("lists no markers");
        }
        if self.pages == 0 {
            refuse!("pages is 0, but a sheet has at least one page");
        }
        if let Some(problem) = self.files.iter().find_map(|f| f.problem()) {
            return Err(LoadProblem::Invalid(problem));
        }
        // Every page of a sheet holds a marker; a huge count (found by
        // fuzzing: 2147483647) made validation walk billions of empty pages.
        if self.pages as usize > self.markers.len() {
            refuse!(
                "pages is {}, but its {} markers fill at most {} pages",
                self.pages,
                self.markers.len(),
                self.markers.len()
            );
        }
        let mut seen = std::collections::HashSet::new();
        let mut used_pages = std::collections::BTreeSet::new();
        for m in &self.markers {
            used_pages.insert(m.page);
            let inside = (0.0..=w).contains(&m.x_mm) && (0.0..=h).contains(&m.y_mm);
            if !(m.diameter_mm.is_finite() && m.diameter_mm > 0.0 && inside) {
                refuse!(
                    "marker ID {} on page {} has an impossible place or size",
                    m.id,
                    m.page
                );
            }
            if !crate::limits::MARKER_DIAMETER_MM.contains(m.diameter_mm) {
                refuse!(
                    "marker ID {} on page {}: diameter {}",
                    m.id,
                    m.page,
                    crate::limits::MARKER_DIAMETER_MM
                        .check(m.diameter_mm)
                        .unwrap_err()
                );
            }
            if m.page == 0 || m.page > self.pages {
                let pages = match self.pages {
                    1 => "one page".to_string(),
                    n => format!("pages 1-{n}"),
                };
                refuse!(
                    "marker ID {} is on page {}, but the sheet has {pages}",
                    m.id,
                    m.page
                );
            }
            if !self.legacy && !seen.insert(m.id) {
                refuse!(
                    "ID {} is listed more than once, so its markers cannot be told apart",
                    m.id
                );
            }
        }
        // Every page of a sheet holds a marker: a page with none is a
        // record that does not match what was printed.
        if let Some(empty) = (1..=self.pages).find(|p| !used_pages.contains(p)) {
            refuse!("pages is {}, but no marker is on page {empty}", self.pages);
        }
        self.check_ids()?;
        self.check_overlaps()
    }

    /// Every ID must be a member of the family, printed with its own code:
    /// anything else would be reported as misread or missing, blaming the
    /// print for a broken record.
    fn check_ids(&self) -> std::result::Result<(), LoadProblem> {
        let family = match (self.legacy, self.family) {
            (true, _) => return Ok(()),
            (false, None) => {
                refuse!("names no family, and is not a legacy WhyCon sheet")
            }
            (false, Some(f)) => crate::family::Family::generate(f.bits, f.distance)
                .map_err(|e| LoadProblem::Invalid(format!("family: {e}")))?,
        };
        for m in &self.markers {
            match family.code(m.id) {
                None => {
                    refuse!(
                        "marker ID {} on page {} is not in the {}-bit family with distance {} \
                         (IDs 1-{})",
                        m.id,
                        m.page,
                        family.bits(),
                        family.distance(),
                        family.len()
                    )
                }
                Some(code) if code != m.code => {
                    refuse!(
                        "marker ID {} on page {} has code {}, but ID {} is code {code}",
                        m.id,
                        m.page,
                        m.code,
                        m.id
                    )
                }
                Some(_) => {}
            }
        }
        Ok(())
    }

    /// Printed discs cannot overlap: two markers at one place are a broken
    /// record (a copied line), and validation could match either.
    fn check_overlaps(&self) -> std::result::Result<(), LoadProblem> {
        let mut order: Vec<&PrintedMarker> = self.markers.iter().collect();
        order.sort_by(|a, b| a.page.cmp(&b.page).then(a.x_mm.total_cmp(&b.x_mm)));
        let widest = order.iter().map(|m| m.diameter_mm).fold(0.0, f64::max);
        for (i, a) in order.iter().enumerate() {
            for b in order[i + 1..]
                .iter()
                .take_while(|b| b.page == a.page && b.x_mm - a.x_mm < widest)
            {
                let apart = (a.x_mm - b.x_mm).hypot(a.y_mm - b.y_mm);
                if apart < (a.diameter_mm + b.diameter_mm) / 2.0 {
                    let name = |m: &PrintedMarker| {
                        if self.legacy {
                            format!("the marker at ({:.1}, {:.1}) mm", m.x_mm, m.y_mm)
                        } else {
                            format!("ID {}", m.id)
                        }
                    };
                    refuse!(
                        "markers {} and {} on page {} overlap ({apart:.1} mm apart)",
                        name(a),
                        name(b),
                        a.page
                    );
                }
            }
        }
        Ok(())
    }

    /// A warning when page files beside `path` (where this manifest was
    /// read) are not the ones it was written with; see [`crate::fileset`].
    pub fn mixed_set_note(&self, path: &Path) -> Option<String> {
        crate::fileset::mismatch_note(path, &self.files)
    }

    /// The manifest as the JSON the `sheet` command writes (stable field order).
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("manifest serialises");
        s.push('\n');
        s
    }

    #[cfg(feature = "files")]
    /// Writes the manifest whole or not at all.
    pub fn save(&self, path: &Path) -> Result<(), crate::error::WriteError> {
        crate::io::write_atomic(path, self.to_json().as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_manifest_without_its_format_or_with_an_empty_page_or_a_dust_sized_marker_is_refused() {
        let good = sheet();
        let text = serde_json::to_string(&good).unwrap();
        assert!(Manifest::from_json("m.json", &text).is_ok());
        let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
        value.as_object_mut().unwrap().remove("format");
        let err = Manifest::from_json("m.json", &value.to_string()).unwrap_err();
        assert!(err.to_string().contains("format"), "{err}");

        let mut two_pages = good.clone();
        two_pages.pages = 2;
        let err =
            Manifest::from_json("m.json", &serde_json::to_string(&two_pages).unwrap()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "m.json: pages is 2, but no marker is on page 2"
        );

        let mut dust = good;
        dust.markers[0].diameter_mm = 1e-9;
        let err =
            Manifest::from_json("m.json", &serde_json::to_string(&dust).unwrap()).unwrap_err();
        assert!(
            err.to_string().contains("is outside 0.5 to 10000 mm"),
            "{err}"
        );
    }

    fn sheet() -> Manifest {
        let family = crate::family::Family::generate(8, 2).unwrap();
        let marker = |id, x_mm| PrintedMarker {
            id,
            code: family.code(id).unwrap(),
            page: 1,
            x_mm,
            y_mm: 50.0,
            diameter_mm: 40.0,
        };
        Manifest {
            format: "whycode-sheet".to_string(),
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
            files: Vec::new(),
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
        assert!(load_error(&m).contains("on page 3, but the sheet has one page"));
        let mut m = sheet();
        m.markers[1].id = 999;
        assert!(load_error(&m).contains("ID 999 on page 1 is not in the 8-bit family"));
        let mut m = sheet();
        m.markers[1].id = 0;
        assert!(load_error(&m).contains("ID 0 on page 1 is not in the 8-bit family"));
        let mut m = sheet();
        m.markers[1].code = 11;
        assert!(load_error(&m).contains("ID 2 on page 1 has code 11, but ID 2 is code 7"));
        let mut m = sheet();
        m.markers[1].x_mm = m.markers[0].x_mm + 1.0;
        assert!(load_error(&m).contains("markers ID 1 and ID 2 on page 1 overlap"));
        let mut m = sheet();
        m.pages = 2147483647;
        assert!(load_error(&m).contains("pages is 2147483647, but its 2 markers"));
        let mut m = sheet();
        m.pages = 0;
        assert!(load_error(&m).contains("pages is 0"), "{}", load_error(&m));
        let mut m = sheet();
        m.format = "other".into();
        assert!(load_error(&m).contains("format is 'other'"));
    }
}
