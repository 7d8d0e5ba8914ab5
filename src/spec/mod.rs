//! What a front end asks for, in the library's terms: the one contract the
//! command line, the Python package and the browser page fill.
//!
//! Each job has a spec of plain fields with a `Default` (the command line's
//! defaults) and one method that checks every value against [`limits`] and
//! builds what the library runs: [`TargetSpec`] → [`crate::detect::Target`],
//! [`SceneSpec`] → [`crate::simulate::Scene`], [`DetectSpec`] →
//! [`crate::detect::DetectorConfig`]; printing has its jobs in
//! [`crate::render::job`]. A front end only parses its own syntax into a
//! spec and words the errors in its own option names: a [`SpecError`] says
//! which field was wrong ([`SpecError::option`], in the spec's snake_case)
//! apart from what was wrong with it ([`SpecError::problem`]), so the
//! command line prints `--camera-distance: …` where Python prints
//! `camera_distance: …` for the same mistake.

mod arena;
mod calibrate;
mod detect;
pub mod limits;
#[cfg(feature = "recordings")]
mod recording;
mod scene;
mod target;

pub use arena::ArenaSpec;
pub use calibrate::CalibrateSpec;
pub use detect::DetectSpec;
pub use limits::{Limit, OutOfRange};
#[cfg(feature = "recordings")]
pub use recording::{NotATime, RecordingSpec};
pub use scene::{BackgroundKind, Layout, SceneSpec};
pub use target::{Bits, TargetSpec};

/// A spec that cannot be built: which option (if the problem is one
/// option's) and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{}{problem}", option.map(|o| format!("{o}: ")).unwrap_or_default())]
pub struct SpecError {
    /// The spec's field that holds the wrong value, in snake_case
    /// (`camera_distance`); `None` when the problem is not one option's
    /// (a file that cannot be read names itself).
    pub option: Option<&'static str>,
    /// What is wrong.
    #[source]
    pub problem: Problem,
}

/// What is wrong with a spec.
#[derive(Debug, thiserror::Error)]
pub enum Problem {
    /// A number outside its plausible range.
    #[error(transparent)]
    OutOfRange(#[from] OutOfRange),
    /// Two options that cannot go together.
    #[error("{0}")]
    Conflict(String),
    /// A value that does not fit what else was asked (an ID the family
    /// lacks, a page the sheet does not have), in words.
    #[error("{0}")]
    Invalid(String),
    /// The family's parameters or codes.
    #[error(transparent)]
    Family(#[from] crate::family::FamilyError),
    /// A file (a family file, a manifest, a calibration) that cannot be
    /// read or used.
    #[error(transparent)]
    File(#[from] crate::error::LoadError),
    /// A camera that does not fit the image.
    #[error(transparent)]
    Camera(#[from] crate::camera::OtherCamera),
}

impl SpecError {
    /// A problem with `option`.
    pub fn of(option: &'static str, problem: impl Into<Problem>) -> SpecError {
        SpecError {
            option: Some(option),
            problem: problem.into(),
        }
    }

    /// A problem of no single option.
    pub fn general(problem: impl Into<Problem>) -> SpecError {
        SpecError {
            option: None,
            problem: problem.into(),
        }
    }

    /// `option`'s value is wrong, in words.
    pub fn invalid(option: &'static str, problem: impl Into<String>) -> SpecError {
        SpecError::of(option, Problem::Invalid(problem.into()))
    }

    /// The message with the option spelled by `spell` (the command line
    /// passes `|o| format!("--{}", o.replace('_', "-"))`).
    pub fn message_with(&self, spell: impl Fn(&str) -> String) -> String {
        match self.option {
            Some(option) => format!("{}: {}", spell(option), self.problem),
            None => self.problem.to_string(),
        }
    }

    /// Whether the problem is a file that could not be read (an `OSError`
    /// to Python) rather than a wrong value.
    pub fn is_io(&self) -> bool {
        matches!(&self.problem, Problem::File(err) if err.is_io())
    }
}

/// `value` checked against `limit` as `option`'s.
pub(crate) fn within(option: &'static str, value: f64, limit: Limit) -> Result<f64, SpecError> {
    limit.check(value).map_err(|e| SpecError::of(option, e))
}

/// The command line's spelling of a spec option: `--camera-distance`.
pub fn cli_option(option: &str) -> String {
    format!("--{}", option.replace('_', "-"))
}
