//! (in progress)

pub mod idfilter;
pub mod ring;
