//! Validation of printed sheets from photos: is every printed marker there,
//! does it read as its own ID, and was the page printed at the right size?
//!
//! Per photo: markers are detected, ID-matched to each page of the
//! manifest, and the page's homography (manifest mm → image pixels) is
//! fitted robustly to the matched centres (RANSAC, then least squares,
//! with the perspective shift between a circle's centre and its ellipse's
//! centre taken out). The homography predicts where every printed marker
//! must be; what was detected there decides its status. The printed scale
//! is measured against the paper's edges ([`scale`]). Over several photos
//! the best observation of each marker counts.

pub mod annotate;
mod photo;
mod report;
pub mod scale;
mod written;

pub use photo::{
    check_image, check_photo, MarkerCheck, MarkerStatus, Observation, OddSize, PageCheck,
    PhotoReport, StrayDetection,
};
pub use report::{summarise, Counts, MarkerVerdict, PageVerdict, Report};

use crate::manifest::Manifest;

/// Why a sheet cannot be validated.
#[derive(Debug, thiserror::Error)]
pub enum UnvalidatableSheet {
    /// Legacy WhyCon circles carry no IDs to match by.
    #[error("the sheet has legacy WhyCon markers without IDs; validation matches markers by ID")]
    LegacyMarkers,
    /// The family the manifest names cannot be made.
    #[error("the manifest's family: {0}")]
    Family(#[from] crate::family::FamilyError),
}

/// A detector for the manifest's family (legacy WhyCon sheets carry no IDs
/// and cannot be validated by ID).
pub fn detector_for(manifest: &Manifest) -> Result<crate::detect::Detector, UnvalidatableSheet> {
    let family_ref = match manifest.family {
        Some(f) if !manifest.legacy => f,
        _ => return Err(UnvalidatableSheet::LegacyMarkers),
    };
    let family = crate::family::Family::generate(family_ref.bits, family_ref.distance)?;
    Ok(crate::detect::Detector::new(
        crate::detect::DetectorConfig {
            target: crate::detect::Target::WhyCode(family),
            max_markers: manifest.markers.len() * 2 + 64,
            tracking: false,
            // A damaged ring is what validation is there to report.
            report_unreadable: true,
            ..Default::default()
        },
    ))
}
