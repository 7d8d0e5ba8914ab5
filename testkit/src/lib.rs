//! What whycode's integration tests, examples and benchmarks share, in one
//! place (a dev-dependency of the whycode package, built once against the
//! library they test). The library itself holds what a user of the
//! simulator needs too: placing a marker at a pixel
//! (`simulate::Placement::at_pixel`) and scoring detections against the
//! ground truth (`simulate::match_reports`). This kit holds the rest:
//!
//! - [`arena`]: a floor with corner and robots' markers under a
//!   distorting lens, for arena coordinates;
//! - [`scenes`]: markers at pixels of a plain camera on white paper, for
//!   round trips and benchmarks;
//! - [`scenario`]: seeded series of frames with a row's look, as the
//!   detector bar measures them, and [`tally`]: what a detector made of
//!   them ([`tally::Counts`], [`tally::Errors`]);
//! - [`tag36h11`], [`aruco4x4`]: AprilTags and ArUco tags printed in the
//!   markers' places;
//! - [`desk`]: desk clutter without markers, for the phantom rules;
//! - [`speed`]: the frames the detector's speed is measured on;
//! - [`swarm`]: the robots on a floor of the sample recordings
//!   (`samples/`, `examples/make_samples`);
//! - [`fuzz`]: the fuzz harness (the test suite's bounded run and
//!   `examples/fuzz`'s long one).

pub mod arena;
pub mod aruco4x4;
pub mod calibration;
pub mod desk;
pub mod fuzz;
pub mod scenario;
pub mod scenes;
pub mod speed;
pub mod swarm;
pub mod tag36h11;
pub mod tally;
