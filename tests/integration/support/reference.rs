//! Stored reference outputs in `tests/data/`: a test compares what this
//! build produces with the stored bytes, so a rendering or detection change
//! shows up as a failing test and, once blessed, as a diff in review.
//!
//! `WHYCODE_BLESS=1 cargo test --test integration reference` rewrites the
//! stored files from this build instead of comparing.

use std::path::PathBuf;

/// Whether this run rewrites the stored files (`WHYCODE_BLESS` set to
/// anything but empty or 0).
pub fn blessing() -> bool {
    std::env::var_os("WHYCODE_BLESS").is_some_and(|v| !v.is_empty() && v != "0")
}

pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// Compares outputs with their stored copies, collecting every difference
/// so one run reports all of them.
#[derive(Default)]
pub struct References {
    differences: Vec<String>,
}

impl References {
    /// Checks `actual` against `tests/data/<name>` (or stores it when
    /// blessing).
    pub fn check(&mut self, name: &str, actual: &[u8]) {
        let stored_path = data_dir().join(name);
        if blessing() {
            std::fs::create_dir_all(stored_path.parent().unwrap()).unwrap();
            std::fs::write(&stored_path, actual).unwrap();
            return;
        }
        let stored = std::fs::read(&stored_path).ok();
        if stored.as_deref() == Some(actual) {
            return;
        }
        let fresh = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
            .join("reference")
            .join(name);
        std::fs::create_dir_all(fresh.parent().unwrap()).unwrap();
        std::fs::write(&fresh, actual).unwrap();
        let what = match &stored {
            None => "is missing".to_string(),
            Some(stored) => format!(
                "differs ({} stored bytes, {} now{})",
                stored.len(),
                actual.len(),
                first_different_line(stored, actual)
            ),
        };
        self.differences.push(format!(
            "tests/data/{name} {what}; this build's output is in {}",
            fresh.display()
        ));
    }

    /// Fails the test if any output differed from its stored copy.
    pub fn finish(self) {
        assert!(
            self.differences.is_empty(),
            "{}\n(if the change is intended, rerun with WHYCODE_BLESS=1 and review the diff)",
            self.differences.join("\n")
        );
    }
}

/// For text files: the first line that differs, to show in the failure.
fn first_different_line(stored: &[u8], actual: &[u8]) -> String {
    let (Ok(stored), Ok(actual)) = (std::str::from_utf8(stored), std::str::from_utf8(actual))
    else {
        return String::new();
    };
    stored
        .lines()
        .zip(actual.lines())
        .enumerate()
        .find(|(_, (a, b))| a != b)
        .map(|(k, (a, b))| format!("; line {}: stored {a:?}, now {b:?}", k + 1))
        .unwrap_or_default()
}
