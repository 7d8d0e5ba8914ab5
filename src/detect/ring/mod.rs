//! Reading a candidate's code ring: is there a WhyCode ring, of how many
//! bits, and which member does it carry?
//!
//! One file per way of looking at a ring, all reading through the shared
//! profile primitives of `profile.rs` (the ellipse's parametrisation, the
//! ring's sampled profile, its sector boundaries and half-sectors):
//! [`manchester`] tests for the Manchester structure of each bit count,
//! [`RingReader`] (`reader.rs`) reads the bits of rings wide enough to
//! sample sector by sector, and [`model`] compares rings too small or too
//! smeared for that with every member rendered as the camera would see it.

pub mod manchester;
pub mod model;
mod profile;
mod reader;

pub use reader::{RingReader, RingReading, MIN_ID_CONFIDENCE, MIN_PIXELS_PER_SECTOR};
