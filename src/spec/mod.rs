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
#[cfg(feature = "recordings")]
mod recording;
mod scene;
mod target;

use crate::limits;
pub use crate::limits::{Limit, OutOfRange};
pub(crate) use crate::spec_error::within;
pub use crate::spec_error::{cli_option, Problem, SpecError};
pub use arena::ArenaSpec;
pub use calibrate::CalibrateSpec;
pub use detect::DetectSpec;
#[cfg(feature = "recordings")]
pub use recording::{NotATime, RecordingSpec};
pub use scene::{BackgroundKind, Layout, SceneSpec};
pub use target::{Bits, TargetSpec};
