//! The family file: the JSON document `whycode ids --format json` prints,
//! which a lab keeps next to its printed markers so that the detector uses
//! exactly that family.
//!
//! ```json
//! {
//!   "format": "whycode-family",
//!   "version": 1,
//!   "bits": 8,
//!   "distance": 2,
//!   "count": 16,
//!   "min_distance": 2,
//!   "min_self_distance": 2,
//!   "codes": [
//!     {"id": 1, "code": 1, "binary": "00000001", "self_distance": 2},
//!     ...
//!   ]
//! }
//! ```
//!
//! On loading, `format`, `version`, `bits`, `distance` and each code's `id`
//! and `code` are required; the derived fields (`count`, `min_distance`,
//! `min_self_distance`, `binary`, `self_distance`) may be left out, but when
//! present they must agree with the codes, so a hand edit cannot leave the
//! file contradicting itself. Unknown fields are ignored.

use super::necklace::self_distance;
use super::Family;
use crate::error::{refuse, FileKind, LoadError, LoadProblem};
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::Path;

/// Value of the `format` field.
pub const FAMILY_FILE_FORMAT: &str = "whycode-family";
/// Value of the `version` field this build writes and reads.
pub const FAMILY_FILE_VERSION: u32 = 1;

#[derive(Deserialize)]
struct Header {
    format: Option<String>,
    version: Option<serde_json::Value>,
}

#[derive(Deserialize)]
struct Document {
    bits: u32,
    distance: u32,
    count: Option<usize>,
    min_distance: Option<u32>,
    min_self_distance: Option<u32>,
    codes: Vec<CodeEntry>,
}

#[derive(Deserialize)]
struct CodeEntry {
    id: u32,
    code: u32,
    binary: Option<String>,
    self_distance: Option<u32>,
}

impl Family {
    /// The family file as text (one code per line, ending in a newline).
    /// Same family, same bytes.
    pub fn to_json(&self) -> String {
        let bits = self.bits() as usize;
        let self_distances = self.self_distances();
        let min_distance = match self.min_distance() {
            Some(d) => d.to_string(),
            None => "null".to_string(),
        };
        let mut out = String::with_capacity(200 + self.len() * (60 + bits));
        out.push_str("{\n");
        let _ = writeln!(out, "  \"format\": \"{FAMILY_FILE_FORMAT}\",");
        let _ = writeln!(out, "  \"version\": {FAMILY_FILE_VERSION},");
        let _ = writeln!(out, "  \"bits\": {},", self.bits());
        let _ = writeln!(out, "  \"distance\": {},", self.distance());
        let _ = writeln!(out, "  \"count\": {},", self.len());
        let _ = writeln!(out, "  \"min_distance\": {min_distance},");
        let _ = writeln!(
            out,
            "  \"min_self_distance\": {},",
            self_distances.iter().min().copied().unwrap_or(0)
        );
        out.push_str("  \"codes\": [\n");
        for (k, (&code, &sd)) in self.codes().iter().zip(&self_distances).enumerate() {
            let separator = if k + 1 == self.len() { "" } else { "," };
            let _ = writeln!(
                out,
                "    {{\"id\": {}, \"code\": {code}, \"binary\": \"{code:0bits$b}\", \"self_distance\": {sd}}}{separator}",
                k + 1
            );
        }
        out.push_str("  ]\n}\n");
        out
    }

    /// Parses and checks a family file's text (see the module docs). Errors
    /// are one line, naming the problem; [`Family::load`] adds the file name.
    pub fn from_json(text: &str) -> Result<Family, LoadError> {
        parse_family(text).map_err(|problem| {
            LoadError::invalid_text(
                FileKind::Family,
                crate::error::shorten_words(&problem.to_string()),
            )
        })
    }
}

/// The checks behind [`Family::from_json`].
fn parse_family(text: &str) -> Result<Family, LoadProblem> {
    let header: Header = serde_json::from_str(text)
        .map_err(|e| LoadProblem::Invalid(format!("not valid JSON: {e}")))?;
    match header.format.as_deref() {
        Some(FAMILY_FILE_FORMAT) => {}
        Some(other) => refuse!("format is \"{other}\", expected \"{FAMILY_FILE_FORMAT}\""),
        None => refuse!("not a whycode family file (no \"format\" field)"),
    }
    match header.version {
        Some(serde_json::Value::Number(n))
            if n.as_u64() == Some(u64::from(FAMILY_FILE_VERSION)) => {}
        Some(v) => refuse!(
            "unsupported family file version {v} (this build reads version {FAMILY_FILE_VERSION})"
        ),
        None => refuse!("no \"version\" field"),
    }
    let doc: Document = serde_json::from_str(text)
        .map_err(|e| LoadProblem::Invalid(format!("malformed family file: {e}")))?;
    let mut codes = Vec::with_capacity(doc.codes.len());
    for (k, entry) in doc.codes.iter().enumerate() {
        let expected_id = k as u32 + 1;
        if entry.id != expected_id {
            refuse!(
                "code entry {} has ID {}, expected {expected_id} (IDs run 1, 2, 3, ... in order)",
                k + 1,
                entry.id
            );
        }
        codes.push(entry.code);
    }
    if let Some(count) = doc.count {
        if count != codes.len() {
            refuse!("count is {count} but {} codes are listed", codes.len());
        }
    }
    let family = Family::from_codes(doc.bits, doc.distance, codes)
        .map_err(|e| LoadProblem::Invalid(e.to_string()))?;
    let bits = doc.bits as usize;
    for entry in &doc.codes {
        if let Some(binary) = &entry.binary {
            let expected = format!("{:0bits$b}", entry.code);
            if *binary != expected {
                refuse!(
                    "ID {}: binary \"{binary}\" does not match code {} (\"{expected}\")",
                    entry.id,
                    entry.code
                );
            }
        }
        if let Some(sd) = entry.self_distance {
            let actual = self_distance(entry.code, doc.bits);
            if sd != actual {
                refuse!(
                    "ID {}: self_distance is {sd}, the code's is {actual}",
                    entry.id
                );
            }
        }
    }
    if let Some(declared) = doc.min_self_distance {
        let actual = family.min_self_distance();
        if declared != actual {
            refuse!("min_self_distance is {declared}, the codes' is {actual}");
        }
    }
    if let Some(declared) = doc.min_distance {
        match family.min_distance() {
            Some(actual) if actual == declared => {}
            Some(actual) => refuse!("min_distance is {declared}, the codes' is {actual}"),
            None => refuse!("min_distance is {declared}, but a family of one has none"),
        }
    }
    Ok(family)
}

impl Family {
    /// Writes the family file whole or not at all.
    #[cfg(feature = "files")]
    pub fn save(&self, path: &Path) -> Result<(), crate::error::WriteError> {
        crate::io::write_atomic(path, self.to_json().as_bytes())
    }

    /// Reads and checks a family file. Errors read `<file>: <problem>`.
    pub fn load(path: &Path) -> Result<Family, LoadError> {
        let text = crate::input::read_text(path, FileKind::Family)?;
        Family::from_json(&text).map_err(|err| err.in_file(path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error_of(text: &str) -> String {
        format!("{:#}", Family::from_json(text).unwrap_err())
    }

    #[test]
    fn round_trip_keeps_the_family() {
        for (bits, d) in [(2, 1), (8, 2), (12, 3), (16, 5)] {
            let f = Family::generate(bits, d).unwrap();
            let text = f.to_json();
            assert_eq!(Family::from_json(&text).unwrap(), f);
            // The text is valid JSON with the documented fields.
            let v: serde_json::Value = serde_json::from_str(&text).unwrap();
            assert_eq!(v["format"], "whycode-family");
            assert_eq!(v["count"], f.len());
            assert_eq!(v["codes"][0]["id"], 1);
        }
    }

    #[test]
    fn spec_vector_document() {
        let text = Family::generate(8, 2).unwrap().to_json();
        assert!(text.starts_with(
            "{\n  \"format\": \"whycode-family\",\n  \"version\": 1,\n  \"bits\": 8,\n  \"distance\": 2,\n  \"count\": 16,\n  \"min_distance\": 2,\n  \"min_self_distance\": 2,\n  \"codes\": [\n"
        ));
        assert!(text.contains(
            "    {\"id\": 1, \"code\": 1, \"binary\": \"00000001\", \"self_distance\": 2},\n"
        ));
        assert!(text
            .ends_with("\"code\": 127, \"binary\": \"01111111\", \"self_distance\": 2}\n  ]\n}\n"));
    }

    #[test]
    fn derived_fields_are_optional() {
        let text = r#"{"format":"whycode-family","version":1,"bits":8,"distance":2,
            "codes":[{"id":1,"code":1},{"id":2,"code":7}]}"#;
        let f = Family::from_json(text).unwrap();
        assert_eq!(f.codes(), &[1, 7]);
        assert_eq!(f.id_of(7), Some(2));
    }

    #[test]
    fn unsorted_hand_picked_family_decodes() {
        let text = r#"{"format":"whycode-family","version":1,"bits":8,"distance":2,
            "codes":[{"id":1,"code":127},{"id":2,"code":1},{"id":3,"code":37}]}"#;
        let f = Family::from_json(text).unwrap();
        assert_eq!(f.id_of(127), Some(1));
        assert_eq!(f.id_of(1), Some(2));
        assert_eq!(f.id_of(37), Some(3));
        assert_eq!(f.id_of(7), None);
        let decoder = crate::family::Decoder::new(&f);
        assert_eq!(decoder.decode(37 << 1).id, 3);
    }

    #[test]
    fn bad_files_get_one_line_errors() {
        let base = |bits: u32, distance: u32, codes: &str| {
            format!(
                r#"{{"format":"whycode-family","version":1,"bits":{bits},"distance":{distance},"codes":[{codes}]}}"#
            )
        };
        let cases = [
            ("[1,2]".to_string(), "not valid JSON"),
            ("{".to_string(), "not valid JSON"),
            (r#"{"bits":8}"#.to_string(), "no \"format\" field"),
            (r#"{"format":"whycode-counts","version":1}"#.to_string(), "format is \"whycode-counts\""),
            (r#"{"format":"whycode-family","version":2}"#.to_string(), "unsupported family file version 2"),
            (r#"{"format":"whycode-family","version":1,"bits":8}"#.to_string(), "missing field"),
            (base(1, 1, r#"{"id":1,"code":1}"#), "bits must be between 2 and 24, got 1"),
            (base(25, 1, r#"{"id":1,"code":1}"#), "bits must be between 2 and 24, got 25"),
            (base(8, 0, r#"{"id":1,"code":1}"#), "distance must be between 1 and the bit count 8, got 0"),
            (base(8, 9, r#"{"id":1,"code":1}"#), "distance must be between 1 and the bit count 8, got 9"),
            (base(8, 2, ""), "at least one code"),
            (base(8, 2, r#"{"id":2,"code":1}"#), "code entry 1 has ID 2, expected 1"),
            (base(8, 2, r#"{"id":1,"code":1},{"id":3,"code":7}"#), "code entry 2 has ID 3, expected 2"),
            (base(8, 2, r#"{"id":1,"code":256}"#), "ID 1: code 256 does not fit in 8 bits"),
            (base(8, 2, r#"{"id":1,"code":1},{"id":2,"code":85}"#), "ID 2: code 85 is periodic"),
            (base(8, 2, r#"{"id":1,"code":1},{"id":2,"code":14}"#), "ID 2: code 14 is not stored as its smallest rotation 7"),
            (base(8, 1, r#"{"id":1,"code":7},{"id":2,"code":1},{"id":3,"code":7}"#), "IDs 1 and 3 have the same code 7"),
            (base(8, 2, r#"{"id":1,"code":1},{"id":2,"code":3}"#), "IDs 1 and 2 are at cyclic distance 1, below the family's distance 2"),
            (base(8, 2, r#"{"id":1,"code":1,"binary":"00000010"}"#), "ID 1: binary \"00000010\" does not match code 1"),
            (base(8, 2, r#"{"id":1,"code":1,"self_distance":3}"#), "ID 1: self_distance is 3, the code's is 2"),
            (r#"{"format":"whycode-family","version":1,"bits":8,"distance":2,"count":3,"codes":[{"id":1,"code":1}]}"#.to_string(), "count is 3 but 1 codes are listed"),
            (r#"{"format":"whycode-family","version":1,"bits":8,"distance":2,"min_distance":3,"codes":[{"id":1,"code":1},{"id":2,"code":7}]}"#.to_string(), "min_distance is 3, the codes' is 2"),
            (r#"{"format":"whycode-family","version":1,"bits":8,"distance":2,"min_self_distance":4,"codes":[{"id":1,"code":1}]}"#.to_string(), "min_self_distance is 4, the codes' is 2"),
        ];
        for (text, expected) in cases {
            let err = error_of(&text);
            assert!(
                err.contains(expected),
                "{text}\n  gave: {err}\n  expected: {expected}"
            );
            assert!(!err.contains('\n'), "multi-line error: {err}");
        }
    }

    #[test]
    fn load_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fam.json");
        let f = Family::generate(10, 3).unwrap();
        f.save(&path).unwrap();
        assert_eq!(Family::load(&path).unwrap(), f);
        std::fs::write(&path, "{}").unwrap();
        let err = format!("{:#}", Family::load(&path).unwrap_err());
        assert!(err.starts_with(&format!("{}: ", path.display())), "{err}");
        let missing = dir.path().join("none.json");
        let err = format!("{:#}", Family::load(&missing).unwrap_err());
        assert!(
            err.starts_with(&format!("{}: ", missing.display())),
            "{err}"
        );
    }
}
