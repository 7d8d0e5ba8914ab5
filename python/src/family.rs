//! `Family`, its codes and decoding.

use crate::{guard, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use whycode::family::{CountTable, Decoder, Family, MatchStatus};

/// A family of WhyCode IDs: rotation-free necklace codes with a least
/// cyclic Hamming distance.
#[pyclass(name = "Family", module = "whycode", frozen)]
pub struct PyFamily {
    pub(crate) family: Family,
    decoder: std::sync::OnceLock<Decoder>,
}

impl PyFamily {
    pub(crate) fn wrap(family: Family) -> PyFamily {
        PyFamily {
            family,
            decoder: std::sync::OnceLock::new(),
        }
    }

    fn entry(&self, index: usize) -> PyCode {
        let code = self.family.codes()[index];
        let id = index as u32 + 1;
        PyCode {
            id,
            code,
            binary: format!("{code:0width$b}", width = self.family.bits() as usize),
            self_distance: self.family.self_distance(id).unwrap_or(0),
        }
    }
}

#[pymethods]
impl PyFamily {
    #[new]
    #[pyo3(signature = (bits = 8, distance = 2))]
    fn new(bits: u32, distance: u32) -> PyResult<PyFamily> {
        Ok(guard(|| {
            Ok(PyFamily::wrap(Family::generate(bits, distance)?))
        })?)
    }

    /// Reads a family file (as written by `whycode ids --format json` or `to_json()`).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<PyFamily> {
        Ok(guard(|| Ok(PyFamily::wrap(Family::load(&path)?)))?)
    }

    /// Parses a family file's text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<PyFamily> {
        Ok(guard(|| Ok(PyFamily::wrap(Family::from_json(text)?)))?)
    }

    #[getter]
    fn bits(&self) -> u32 {
        self.family.bits()
    }

    #[getter]
    fn distance(&self) -> u32 {
        self.family.distance()
    }

    /// Least cyclic Hamming distance between two IDs (None for a single ID).
    #[getter]
    fn min_distance(&self) -> Option<u32> {
        self.family.min_distance()
    }

    fn __len__(&self) -> usize {
        self.family.len()
    }

    fn __iter__(slf: Py<Self>) -> PyCodeIter {
        let len = slf.get().family.len();
        PyCodeIter {
            family: slf,
            next: 0,
            len,
        }
    }

    /// The entry of an ID (1-based, like the CLI); IndexError outside the family.
    fn __getitem__(&self, id: isize) -> PyResult<PyCode> {
        if id < 1 || id as usize > self.family.len() {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!(
                "ID {id} is not in this family (IDs 1-{})",
                self.family.len()
            )));
        }
        Ok(self.entry(id as usize - 1))
    }

    /// Decodes an n-bit ring reading: ID, rotation, bit errors and status.
    fn decode(&self, word: u64) -> PyResult<PyDecoded> {
        let bits = self.family.bits();
        if word >> bits != 0 {
            return Err(Error::value(format!("word {word} has more than {bits} bits")).into());
        }
        let decoded = guard(|| {
            let decoder = self.decoder.get_or_init(|| Decoder::new(&self.family));
            Ok(decoder.decode(word as u32))
        })?;
        Ok(PyDecoded {
            id: decoded.id,
            code: decoded.code,
            rotation: decoded.rotation,
            rotation_ambiguous: decoded.rotation_ambiguous,
            errors: decoded.distance,
            status: status_name(decoded.status),
        })
    }

    /// The family file's text (what `whycode ids --format json` writes).
    fn to_json(&self) -> String {
        self.family.to_json()
    }

    /// Writes the family file (whole or not at all).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        Ok(guard(|| Ok(self.family.save(&path)?))?)
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyFamily>()
            .is_ok_and(|o| o.get().family == self.family)
    }

    fn __hash__(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        (
            self.family.bits(),
            self.family.distance(),
            self.family.codes(),
        )
            .hash(&mut h);
        h.finish()
    }

    fn __repr__(&self) -> String {
        format!(
            "Family(bits={}, distance={})  # {} IDs",
            self.family.bits(),
            self.family.distance(),
            self.family.len()
        )
    }
}

pub(crate) fn status_name(status: MatchStatus) -> &'static str {
    match status {
        MatchStatus::Exact => "exact",
        MatchStatus::Corrected => "corrected",
        MatchStatus::Ambiguous => "ambiguous",
        MatchStatus::Rejected => "rejected",
    }
}

#[pyclass(name = "_CodeIterator", module = "whycode")]
pub struct PyCodeIter {
    family: Py<PyFamily>,
    next: usize,
    len: usize,
}

#[pymethods]
impl PyCodeIter {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&mut self) -> Option<PyCode> {
        if self.next >= self.len {
            return None;
        }
        let entry = self.family.get().entry(self.next);
        self.next += 1;
        Some(entry)
    }
}

/// One ID of a family, with the fields of `whycode ids`.
#[pyclass(name = "Code", module = "whycode", frozen, get_all)]
pub struct PyCode {
    id: u32,
    code: u32,
    binary: String,
    self_distance: u32,
}

#[pymethods]
impl PyCode {
    fn __repr__(&self) -> String {
        format!(
            "Code(id={}, code={}, binary='{}', self_distance={})",
            self.id, self.code, self.binary, self.self_distance
        )
    }
}

/// A decoded ring reading.
#[pyclass(name = "Decoded", module = "whycode", frozen, get_all)]
pub struct PyDecoded {
    /// The member's ID; 0 unless status is "exact" or "corrected".
    id: u32,
    /// The member's code (0 when id is 0).
    code: u32,
    /// Left rotation mapping the word onto the code.
    rotation: u32,
    /// Two rotations fit equally well: the ID stands, the yaw does not.
    rotation_ambiguous: bool,
    /// Bits that differ between the rotated word and the code.
    errors: u32,
    /// "exact", "corrected", "ambiguous" or "rejected".
    status: &'static str,
}

#[pymethods]
impl PyDecoded {
    fn __repr__(&self) -> String {
        format!(
            "Decoded(id={}, code={}, rotation={}, errors={}, status='{}')",
            self.id, self.code, self.rotation, self.errors, self.status
        )
    }
}

/// Number of IDs for every (bits, distance) pair with distance <= bits,
/// as `whycode ids --counts` prints them.
#[pyfunction]
fn family_counts(
    py: Python<'_>,
    bits: Vec<u32>,
    distances: Vec<u32>,
) -> PyResult<Py<pyo3::types::PyDict>> {
    let table =
        guard(|| CountTable::new(&bits, &distances).map_err(|e| crate::spec_error(e.into())))?;
    let dict = pyo3::types::PyDict::new(py);
    for (key, count) in table.entries() {
        dict.set_item(key, count)?;
    }
    Ok(dict.unbind())
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyFamily>()?;
    m.add_class::<PyCode>()?;
    m.add_class::<PyDecoded>()?;
    m.add_function(wrap_pyfunction!(family_counts, m)?)?;
    Ok(())
}
