//! Shared numerical building blocks, one home each: the image [`ellipse`]
//! (and its two fits), the bilinear [`sample`]r with its border policies,
//! plane [`homography`] fits, [`least_squares`] (Levenberg–Marquardt), the seeded [`rng`] and [`angle`] helpers.
//! Stage modules (detect, pose, simulate, validate) build on these and never
//! on each other's internals.

pub mod angle;
pub mod ellipse;
pub mod homography;
pub mod least_squares;
pub mod rng;
pub mod sample;

pub use ellipse::Ellipse;
pub use homography::Homography;
pub use rng::Pcg32;
pub use sample::{Border, Plane};
