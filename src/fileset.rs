//! A run that writes several files (a sheet's pages and its manifest, a
//! simulated image and its ground truth) renames them into place one after
//! another. A run killed between two renames, or two runs racing for one
//! output path, can leave a set whose parts come from different runs; the
//! folder lock in `io` keeps racing runs apart, but nothing can stop a
//! kill -9. So the file renamed last (the manifest, the truth) lists the
//! others with their SHA-256, and a reader can tell a mixed set from a
//! sound one instead of validating photos of one print against the record
//! of another.

use std::path::Path;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// One file of a set, as the set's record lists it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileDigest {
    /// The file's name, beside the record (no folder: the set is moved
    /// and copied as a whole).
    pub file: String,
    /// SHA-256 of its bytes, lower-case hex.
    pub sha256: String,
}

impl FileDigest {
    /// The digest of `bytes`, to be written as `path`'s file name.
    pub fn of(path: &Path, bytes: &[u8]) -> FileDigest {
        FileDigest {
            file: path
                .file_name()
                .map(|name| name.to_string_lossy().into_owned())
                .unwrap_or_default(),
            sha256: sha256_hex(bytes),
        }
    }

    /// Why a record's entry cannot be one this toolkit wrote, if it cannot.
    pub fn problem(&self) -> Option<String> {
        let name_ok = !self.file.is_empty()
            && !self.file.contains(['/', '\\'])
            && self.file != "."
            && self.file != "..";
        if !name_ok {
            return Some(format!(
                "files: {:?} is not a file name beside the record",
                self.file
            ));
        }
        let hex_ok = self.sha256.len() == 64
            && self
                .sha256
                .bytes()
                .all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'));
        (!hex_ok).then(|| {
            format!(
                "files: the sha256 of {} is not 64 lower-case hex digits",
                self.file
            )
        })
    }
}

/// Lower-case hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Lower-case hex SHA-256 of a regular file's bytes, read a block at a
/// time; `None` for a file that cannot be read, or that is not a regular
/// file (a FIFO named like a page would never end).
fn file_sha256_hex(path: &Path) -> Option<String> {
    if !std::fs::metadata(path).ok()?.is_file() {
        return None;
    }
    use std::io::Read;
    let mut file = std::fs::File::open(path).ok()?;
    let mut hasher = Sha256::new();
    let mut block = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut block) {
            Ok(0) => break,
            Ok(n) => hasher.update(&block[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => return None,
        }
    }
    Some(
        hasher
            .finalize()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect(),
    )
}

/// The files `record` (read from `record_path`) lists that lie beside it
/// with other contents than it was written with. A listed file that is
/// missing is not a mismatch: people move the PDF to the printer and keep
/// the manifest.
pub fn mismatched(record_path: &Path, files: &[FileDigest]) -> Vec<String> {
    let folder = record_path.parent().unwrap_or(Path::new(""));
    files
        .iter()
        .filter(|entry| {
            file_sha256_hex(&folder.join(&entry.file)).is_some_and(|sha| sha != entry.sha256)
        })
        .map(|entry| entry.file.clone())
        .collect()
}

/// A warning for a record whose set is mixed ([`mismatched`]), naming the
/// files; `None` when every listed file present is the one it describes.
pub fn mismatch_note(record_path: &Path, files: &[FileDigest]) -> Option<String> {
    let mixed = mismatched(record_path, files);
    (!mixed.is_empty()).then(|| {
        format!(
            "{}: {} beside it {} not the file{} it was written with (an interrupted or \
             concurrent run mixed the set); write them again to be sure they belong together",
            record_path.display(),
            mixed.join(", "),
            if mixed.len() == 1 { "is" } else { "are" },
            if mixed.len() == 1 { "" } else { "s" },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digests_are_sha256_of_the_bytes_named_by_file_name() {
        let d = FileDigest::of(Path::new("/tmp/out/swarm.pdf"), b"abc");
        assert_eq!(d.file, "swarm.pdf");
        assert_eq!(
            d.sha256,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(d.problem(), None);
        let bad = FileDigest {
            file: "../x.pdf".into(),
            ..d.clone()
        };
        assert!(bad.problem().unwrap().contains("not a file name"));
        let short = FileDigest {
            sha256: "abc".into(),
            ..d
        };
        assert!(short.problem().unwrap().contains("64 lower-case hex"));
    }
}
