//! whycode-ros2: a ROS 2 node for WhyCode markers, on ros2-client (RustDDS,
//! pure Rust), so that neither building nor running it needs a ROS
//! installation. It reads a camera topic and publishes each identified
//! marker's pose on /tf and the detections on `~/markers`.
//!
//! Modules by job: [`args`] (the ROS command line and name resolution),
//! [`params`] (parameters, and the one mapping to the library's detector
//! configuration), [`log`] (rclcpp-style log lines, once per cause) and
//! [`node`] (the DDS entities and the frame loop). The message types
//! ([`msg`]), camera messages to grey pixels ([`image`]) and detections to
//! messages are the library's (`whycode::ros`), shared with the bags
//! `whycode detect` reads and writes.

pub mod args;
pub mod log;
pub mod node;
pub mod params;

pub use whycode::ros::{image, msg};
