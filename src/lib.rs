//! whycode: WhyCode circular fiducial markers. ID families, print-ready
//! rendering, detection, pose and validation.
//!
//! Pipeline stages, one module each: [`family`] (codes and decoding tables),
//! [`geometry`] (the marker's shape in physical units), [`render`] (SVG, PDF,
//! PNG and print sheets), [`detect`] (finding and decoding markers in
//! images), [`camera`] and [`pose`] (calibration and 6-DoF pose),
//! [`simulate`] (synthetic camera views with ground truth) and [`validate`]
//! (checking printed sheets from photos). [`cli`] is a thin layer over them.

pub mod camera;
pub mod cli;
pub mod detect;
pub mod family;
pub mod geometry;
pub mod io;
pub mod pose;
pub mod render;
pub mod simulate;
pub mod units;
pub mod validate;
