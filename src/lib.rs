#![warn(missing_docs)]
//! whycode: WhyCode circular fiducial markers. ID families, print-ready
//! rendering, detection, pose and validation.
//!
//! Pipeline stages, one module each: [`family`] (codes and decoding tables),
//! [`geometry`] (the marker's shape in physical units), [`render`] (SVG, PDF,
//! PNG and print sheets), [`detect`] (finding and decoding markers in
//! images), [`camera`] and [`pose`] (calibration and 6-DoF pose),
//! [`simulate`] (synthetic camera views with ground truth) and [`validate`]
//! (checking printed sheets from photos). Shared by the stages: [`math`]
//! (the one ellipse, sampler, homography, RNG), [`manifest`] (what a sheet
//! printed where) and [`image_io`] (grey image files in and out). The
//! `whycode` command line (src/cli/, compiled into the binary only) is a
//! thin layer over them.
//!
//! The types most programs need are re-exported here, so a short program
//! reads without the module paths: generate (or load) a family, draw a
//! marker, and find it again in an image.
//!
//! ```
//! use whycode::{Detector, DetectorConfig, Family, Marker, Target};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // The default family: 8-bit codes at least 2 bit flips apart.
//! let family = Family::generate(8, 2)?;
//! let id = 3;
//! let code = family.code(id).expect("the family has an ID 3");
//!
//! // A 40 mm marker with 10 mm of white around it, rasterised at 300 dpi.
//! let marker = Marker::whycode(family.bits(), code, 40.0);
//! let image = whycode::render::render_marker(&marker, 10.0, 300.0)?;
//!
//! let mut detector = Detector::new(DetectorConfig {
//!     target: Target::WhyCode(family),
//!     ..Default::default()
//! });
//! let found = detector.detect(&image);
//! assert_eq!(found.len(), 1);
//! assert_eq!(found[0].id, id);
//! # Ok(())
//! # }
//! ```
//!
//! Photos come in through [`load_gray`]; with a [`Camera`] and the printed
//! diameter in the [`DetectorConfig`], each [`Detection`] carries a
//! [`Pose`]. A print [`Sheet`] records what it placed where in a
//! [`Manifest`], against which [`validate`] checks photos of the print
//! (its [`Report`]).

pub mod arena;
pub mod board;
pub mod calibrate;
pub mod camera;
pub mod detect;
pub mod error;
pub mod family;
pub mod fileset;
pub mod geometry;
pub mod image_io;
pub mod input;
#[cfg(feature = "files")]
pub mod io;
pub mod limits;
pub mod manifest;
pub mod math;
mod parallel;
pub mod pose;
#[cfg(feature = "recordings")]
pub mod recording;
pub mod render;
#[cfg(feature = "ros")]
pub mod ros;
pub mod session;
pub mod simulate;
pub mod spec;
mod spec_error;
pub mod units;
pub mod validate;

pub use camera::{Camera, OtherCamera};
pub use detect::{Detection, Detector, DetectorConfig, Target};
pub use error::{FileKind, LoadError, LoadProblem, WriteError};
pub use family::{Decoded, Decoder, Family, FamilyError, MatchStatus};
pub use geometry::{Design, Marker, MarkerKind};
pub use image_io::{decode_gray, load_gray};
pub use manifest::Manifest;
pub use math::Ellipse;
pub use pose::Pose;
pub use render::{Format, MarkerOptions, Sheet, SheetMarker, SheetSpec, Template};
pub use session::{FrameReport, Session, SessionConfig};
pub use simulate::{GroundTruth, Scene};
pub use units::{Angle, Length};
pub use validate::{PhotoReport, Report};
