//! Rendering markers and print sheets (in progress).

pub mod manifest;
