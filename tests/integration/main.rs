//! The integration tests, linked into one binary (as ripgrep and resvg do)
//! so the crate is linked once instead of once per file. Each module is
//! one area seen from outside the library; `support` holds what they share.
//!
//! `WHYCODE_BLESS=1 cargo test --test integration reference` rewrites the
//! stored outputs in `tests/data/` (see `reference`).

mod support;

mod arena_roundtrip;
mod board_roundtrip;
mod calibrate_roundtrip;
mod defects_cli;
mod defects_measuring;
mod detect_cli;
mod detect_compat;
mod detect_real_camera;
mod detect_robustness;
mod detect_roundtrip;
mod detect_rules;
mod detect_simulated;
mod detect_threads;
mod family_props;
mod frame_folders;
mod fuzz_bounded;
mod ids_cli;
mod library_errors;
mod module_graph;
mod output_files;
mod output_streams;
mod pose_properties;
mod pose_roundtrip;
mod pose_synthetic;
mod readme_recordings;
mod recordings;
mod reference;
mod render_cli_errors;
mod render_encoding;
mod render_physical_size;
mod render_svg_png_agree;
mod ring_perspective;
mod ring_roundtrip;
mod sheet_output;
mod sheet_self_check;
mod simulate_detect;
mod simulate_scene;
mod spec_cli;
mod user_hints;
mod validate_cli;
mod validate_matching;
mod validate_photos;
