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
//! ```no_run
//! use whycode::detect::{Detector, DetectorConfig, Target};
//! use whycode::image_io::load_gray;
//! use whycode::family::Family;
//!
//! # fn main() -> anyhow::Result<()> {
//! let family = Family::generate(8, 2)?;
//! let mut detector = Detector::new(DetectorConfig {
//!     target: Target::WhyCode(family),
//!     ..Default::default()
//! });
//! for d in detector.detect(&load_gray("photo.png".as_ref())?) {
//!     println!("ID {} at ({:.1}, {:.1}), yaw {:?}", d.id, d.u, d.v, d.yaw);
//! }
//! # Ok(())
//! # }
//! ```

pub mod camera;
pub mod detect;
pub mod family;
pub mod geometry;
pub mod image_io;
#[cfg(feature = "files")]
pub mod io;
pub mod manifest;
pub mod math;
mod parallel;
pub mod pose;
pub mod render;
pub mod simulate;
pub mod units;
pub mod validate;
