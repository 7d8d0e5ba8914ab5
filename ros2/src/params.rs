//! The node's parameters: their names, types, defaults and ranges
//! ([`Settings`]), and the one place they become the library's
//! [`SessionConfig`] ([`detector_config`]).
//!
//! Every value is checked when it is set, from the command line or through
//! `ros2 param set`; a refused value leaves the settings as they were.

use ros2_client::ParameterValue;
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use whycode::arena::Arena;
use whycode::board::Board;
use whycode::detect::Target;
use whycode::family::{DEFAULT_BITS, DEFAULT_DISTANCE};
use whycode::limits;
use whycode::session::SessionConfig;
use whycode::spec::{DetectSpec, TargetSpec};
use whycode::units::Length;
use whycode::Camera;

/// The node's name unless `-r __node:=` says otherwise.
pub const DEFAULT_NODE_NAME: &str = "whycode";

/// Code length of the family, or every count read from the rings.
pub use whycode::spec::Bits;

/// Which image topic the node subscribes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transport {
    /// `image` (sensor_msgs/Image).
    Raw,
    /// `image/compressed` (sensor_msgs/CompressedImage).
    Compressed,
}

/// What a parameter change touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Change {
    /// The detector's configuration: it starts over.
    Detector,
    /// The image subscription.
    Transport,
    /// Only what is published.
    Output,
}

/// The node's parameters, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// `bits`: the family's code length, or `auto`.
    pub bits: Bits,
    /// `distance`: the family's minimum Hamming distance.
    pub distance: u32,
    /// `family_file`: a family file instead of `bits` and `distance`.
    pub family_file: String,
    /// `legacy`: WhyCon circles without IDs.
    pub legacy: bool,
    /// `diameter`: outer diameter of the black disc, metres; 0 when not set.
    pub diameter: f64,
    /// `max_markers`: at most this many markers a frame.
    pub max_markers: u32,
    /// `tracking`: follow markers from frame to frame.
    pub tracking: bool,
    /// `rectified`: the image topic is rectified (use camera_info's P, no
    /// distortion) rather than raw (K and D).
    pub rectified: bool,
    /// `image_transport`: `raw` or `compressed`.
    pub image_transport: Transport,
    /// `camera_frame`: parent frame of the transforms; empty: the image
    /// header's frame_id.
    pub camera_frame: String,
    /// `frame_prefix`: a marker's frame is this followed by its ID.
    pub frame_prefix: String,
    /// `tag.ids`: IDs with their own frame name or size.
    pub tag_ids: Vec<u32>,
    /// `tag.frames`: frame names of the first `tag.ids`.
    pub tag_frames: Vec<String>,
    /// `tag.sizes`: diameters, metres, of the first `tag.ids`.
    pub tag_sizes: Vec<f64>,
    /// `publish_tf`: publish /tf.
    pub publish_tf: bool,
    /// `debug_image`: publish the annotated image.
    pub debug_image: bool,
    /// `compat_markers`: also publish the original whycode-ros2 node's
    /// `whycode_interfaces/MarkerArray` on `~/markers_compat`.
    pub compat_markers: bool,
    /// `boards`: board files (sheet manifests, bundle YAML): each board's
    /// pose goes on /tf as a frame named after it.
    pub boards: Vec<String>,
    /// `arena_file`: an arena file (`whycode arena`): markers placed on the
    /// floor on `~/arena_markers`, the floor frame on /tf; empty: none.
    pub arena_file: String,
    /// `arena_frame`: the floor frame's name on /tf and in
    /// `~/arena_markers`.
    pub arena_frame: String,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            bits: Bits::Count(DEFAULT_BITS),
            distance: DEFAULT_DISTANCE,
            family_file: String::new(),
            legacy: false,
            diameter: 0.0,
            max_markers: 1024,
            tracking: true,
            rectified: false,
            image_transport: Transport::Raw,
            camera_frame: String::new(),
            frame_prefix: whycode::ros::DEFAULT_FRAME_PREFIX.into(),
            tag_ids: Vec::new(),
            tag_frames: Vec::new(),
            tag_sizes: Vec::new(),
            publish_tf: true,
            debug_image: false,
            compat_markers: false,
            boards: Vec::new(),
            arena_file: String::new(),
            arena_frame: whycode::ros::DEFAULT_ARENA_FRAME.into(),
        }
    }
}

/// Every parameter's name, in the order the README documents them.
pub const NAMES: [&str; 20] = [
    "bits",
    "distance",
    "family_file",
    "legacy",
    "diameter",
    "max_markers",
    "tracking",
    "rectified",
    "image_transport",
    "camera_frame",
    "frame_prefix",
    "tag.ids",
    "tag.frames",
    "tag.sizes",
    "publish_tf",
    "debug_image",
    "compat_markers",
    "boards",
    "arena_file",
    "arena_frame",
];

/// Parameters the ROS client library keeps itself.
pub const BUILT_IN: [&str; 1] = ["use_sim_time"];

/// A parameter value the node refuses: the parameter and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("parameter {name}: {problem}")]
pub struct ParamError {
    /// The parameter, as the user named it.
    pub name: String,
    /// What is wrong with its value.
    pub problem: ParamProblem,
}

/// What is wrong with a parameter's value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamProblem {
    /// A value of the wrong type or outside the parameter's range.
    #[error("{value} is not {expected}")]
    Wrong {
        /// The value as the user wrote it.
        value: String,
        /// What the parameter takes, in words.
        expected: &'static str,
    },
    /// A marker diameter outside the toolkit's plausible sizes.
    #[error(
        "{metres} m is not a plausible marker diameter ({} to {} metres{})",
        limits::MARKER_DIAMETER_MM.min / 1000.0,
        limits::MARKER_DIAMETER_MM.max / 1000.0,
        if *zero_unsets { ", or 0: none" } else { "" }
    )]
    Diameter {
        /// The diameter given, metres.
        metres: f64,
        /// Whether 0 ("not set") is taken.
        zero_unsets: bool,
    },
    /// An ID listed twice in `tag.ids`.
    #[error("ID {0} is listed twice")]
    IdTwice(u32),
    /// A frame listed twice in `tag.frames`.
    #[error("frame '{0}' is listed twice")]
    FrameTwice(String),
    /// An empty frame name.
    #[error("a frame name must not be empty")]
    EmptyFrame,
    /// A frame name starting with '/', which tf2 refuses.
    #[error("frame '{0}': tf2 frame names do not start with '/'")]
    RootedFrame(String),
    /// A frame name with a character tf2 does not allow.
    #[error("frame '{frame}': '{character}' is not allowed")]
    FrameCharacter {
        /// The frame name.
        frame: String,
        /// The first character not allowed.
        character: char,
    },
    /// A parameter this node does not have.
    #[error("no such parameter (there are: {})", NAMES.join(", "))]
    Unknown,
    /// More `tag.frames` or `tag.sizes` than `tag.ids`.
    #[error("{count} values for {ids} tag.ids")]
    MoreThanIds {
        /// How many values were given.
        count: usize,
        /// How many `tag.ids` there are.
        ids: usize,
    },
}

/// Why the settings make no detector configuration.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// A parameter's file (a board, the arena) cannot be read or used.
    #[error("parameter {name}: {}", whycode::error::one_line(error))]
    File {
        /// The parameter naming the file.
        name: &'static str,
        /// Why it cannot be used.
        error: whycode::LoadError,
    },
    /// What the library refused, worded in this node's parameter names.
    #[error("{}", in_parameters(.0))]
    Spec(whycode::spec::SpecError),
    /// `tag.ids` lists an ID the family does not have.
    #[error(
        "parameter tag.ids: the {bits}-bit family of distance {distance} has IDs 1 to {count}, \
         not {id}"
    )]
    ForeignId {
        /// The ID.
        id: u32,
        /// The family's code length.
        bits: u32,
        /// The family's minimum distance.
        distance: u32,
        /// How many IDs the family has.
        count: usize,
    },
}

/// A spec error with the option named as this node's parameter.
fn in_parameters(err: &whycode::spec::SpecError) -> String {
    err.message_with(|option| {
        // The spec's names for what this node's parameters call so.
        let name = match option {
            "arena" => "arena_file",
            "board" => "boards",
            other => other,
        };
        format!("parameter {name}")
    })
}

impl Settings {
    /// Defaults overridden by `values` in order; the first refused value
    /// is the error, naming the parameter.
    pub fn from_parameters<'a>(
        values: impl IntoIterator<Item = &'a (String, ParameterValue)>,
    ) -> Result<Settings, ParamError> {
        let mut settings = Settings::default();
        for (name, value) in values {
            if BUILT_IN.contains(&name.as_str()) {
                continue;
            }
            settings = settings.with(name, value)?;
        }
        Ok(settings)
    }

    /// These settings with one parameter changed, checked on its own and
    /// against the others.
    pub fn with(&self, name: &str, value: &ParameterValue) -> Result<Settings, ParamError> {
        let mut next = self.clone();
        next.set(name, value).map_err(|problem| ParamError {
            name: name.to_string(),
            problem,
        })?;
        next.check_tags()?;
        Ok(next)
    }

    /// What changing `name` touches.
    pub fn change_of(name: &str) -> Change {
        match name {
            "bits" | "distance" | "family_file" | "legacy" | "diameter" | "max_markers"
            | "tracking" | "tag.ids" | "tag.sizes" | "boards" | "arena_file" => Change::Detector,
            "image_transport" => Change::Transport,
            _ => Change::Output,
        }
    }

    fn set(&mut self, name: &str, value: &ParameterValue) -> Result<(), ParamProblem> {
        match name {
            "bits" => {
                self.bits = match value {
                    ParameterValue::String(s) if s.trim().eq_ignore_ascii_case("auto") => {
                        Bits::Auto
                    }
                    _ => Bits::Count(integer(value, 2..=24, "the code length, 2 to 24 or auto")?),
                }
            }
            "distance" => self.distance = integer(value, 1..=24, "a Hamming distance, 1 to 24")?,
            "family_file" => self.family_file = string(value)?,
            "legacy" => self.legacy = boolean(value)?,
            "diameter" => self.diameter = diameter(number(value)?, true)?,
            "max_markers" => {
                self.max_markers = integer(value, 1..=100_000, "a count, 1 to 100000")?
            }
            "tracking" => self.tracking = boolean(value)?,
            "rectified" => self.rectified = boolean(value)?,
            "image_transport" => {
                self.image_transport = match string(value)?.as_str() {
                    "raw" => Transport::Raw,
                    "compressed" => Transport::Compressed,
                    _ => return Err(wrong(value, "raw or compressed")),
                }
            }
            "camera_frame" => {
                let frame = string(value)?;
                if !frame.is_empty() {
                    check_frame(&frame)?;
                }
                self.camera_frame = frame;
            }
            "frame_prefix" => {
                let prefix = string(value)?;
                check_frame(&format!("{prefix}1"))?;
                self.frame_prefix = prefix;
            }
            "tag.ids" => {
                let ids = integers(value)?;
                let mut checked = Vec::with_capacity(ids.len());
                for id in ids {
                    let id = u32::try_from(id).ok().filter(|&id| id > 0).ok_or_else(|| {
                        ParamProblem::Wrong {
                            value: id.to_string(),
                            expected: "an ID (IDs start at 1)",
                        }
                    })?;
                    if checked.contains(&id) {
                        return Err(ParamProblem::IdTwice(id));
                    }
                    checked.push(id);
                }
                self.tag_ids = checked;
            }
            "tag.frames" => {
                let frames = strings(value)?;
                for (k, frame) in frames.iter().enumerate() {
                    check_frame(frame)?;
                    if frames[..k].contains(frame) {
                        return Err(ParamProblem::FrameTwice(frame.clone()));
                    }
                }
                self.tag_frames = frames;
            }
            "tag.sizes" => {
                self.tag_sizes = numbers(value)?
                    .into_iter()
                    .map(|d| diameter(d, false))
                    .collect::<Result<_, _>>()?;
            }
            "publish_tf" => self.publish_tf = boolean(value)?,
            "debug_image" => self.debug_image = boolean(value)?,
            "compat_markers" => self.compat_markers = boolean(value)?,
            "boards" => self.boards = strings(value)?,
            "arena_file" => self.arena_file = string(value)?,
            "arena_frame" => {
                let frame = string(value)?;
                check_frame(&frame)?;
                self.arena_frame = frame;
            }
            _ => return Err(ParamProblem::Unknown),
        }
        Ok(())
    }

    /// `tag.frames` and `tag.sizes` name the first of `tag.ids`: never more.
    fn check_tags(&self) -> Result<(), ParamError> {
        for (name, count) in [
            ("tag.frames", self.tag_frames.len()),
            ("tag.sizes", self.tag_sizes.len()),
        ] {
            if count > self.tag_ids.len() {
                return Err(ParamError {
                    name: name.to_string(),
                    problem: ParamProblem::MoreThanIds {
                        count,
                        ids: self.tag_ids.len(),
                    },
                });
            }
        }
        Ok(())
    }

    /// A parameter's current value, as declared to ROS.
    pub fn value(&self, name: &str) -> Option<ParameterValue> {
        Some(match name {
            "bits" => match self.bits {
                Bits::Count(n) => ParameterValue::Integer(n.into()),
                Bits::Auto => ParameterValue::String("auto".into()),
            },
            "distance" => ParameterValue::Integer(self.distance.into()),
            "family_file" => ParameterValue::String(self.family_file.clone()),
            "legacy" => ParameterValue::Boolean(self.legacy),
            "diameter" => ParameterValue::Double(self.diameter),
            "max_markers" => ParameterValue::Integer(self.max_markers.into()),
            "tracking" => ParameterValue::Boolean(self.tracking),
            "rectified" => ParameterValue::Boolean(self.rectified),
            "image_transport" => ParameterValue::String(
                match self.image_transport {
                    Transport::Raw => "raw",
                    Transport::Compressed => "compressed",
                }
                .into(),
            ),
            "camera_frame" => ParameterValue::String(self.camera_frame.clone()),
            "frame_prefix" => ParameterValue::String(self.frame_prefix.clone()),
            "tag.ids" => {
                ParameterValue::IntegerArray(self.tag_ids.iter().map(|&i| i.into()).collect())
            }
            "tag.frames" => ParameterValue::StringArray(self.tag_frames.clone()),
            "tag.sizes" => ParameterValue::DoubleArray(self.tag_sizes.clone()),
            "publish_tf" => ParameterValue::Boolean(self.publish_tf),
            "debug_image" => ParameterValue::Boolean(self.debug_image),
            "compat_markers" => ParameterValue::Boolean(self.compat_markers),
            "boards" => ParameterValue::StringArray(self.boards.clone()),
            "arena_file" => ParameterValue::String(self.arena_file.clone()),
            "arena_frame" => ParameterValue::String(self.arena_frame.clone()),
            _ => return None,
        })
    }

    /// The diameter the detector computes poses for: `diameter`, or
    /// without it the first of `tag.sizes` (other sizes are scaled from it).
    pub fn detector_diameter(&self) -> Option<f64> {
        if self.diameter > 0.0 {
            Some(self.diameter)
        } else {
            self.tag_sizes.first().copied()
        }
    }

    /// The /tf frame and the diameter (metres; None: unknown, so no pose)
    /// of the marker with `id`.
    pub fn tag(&self, id: u32) -> (Cow<'_, str>, Option<f64>) {
        let listed = self.tag_ids.iter().position(|&t| t == id);
        let frame = match listed.and_then(|k| self.tag_frames.get(k)) {
            Some(frame) => Cow::Borrowed(frame.as_str()),
            None => Cow::Owned(format!("{}{id}", self.frame_prefix)),
        };
        let size = listed
            .and_then(|k| self.tag_sizes.get(k).copied())
            .or((self.diameter > 0.0).then_some(self.diameter));
        (frame, size)
    }
}

/// The detector's configuration for `settings`, with `camera` (from
/// camera_info) for poses. The one place where the node's parameters
/// become the library's configuration; a family that cannot be made or
/// loaded, or listed IDs the family lacks, are refused here.
pub fn detector_config(
    settings: &Settings,
    camera: Option<Camera>,
) -> Result<SessionConfig, ConfigError> {
    let family_file = !settings.family_file.is_empty();
    let names_family = !settings.legacy && !family_file;
    let in_parameter = |name, error| ConfigError::File { name, error };
    let mut boards = Vec::new();
    for path in &settings.boards {
        boards.extend(Board::load(Path::new(path)).map_err(|e| in_parameter("boards", e))?);
    }
    let arena = (!settings.arena_file.is_empty())
        .then(|| Arena::load(Path::new(&settings.arena_file)))
        .transpose()
        .map_err(|e| in_parameter("arena_file", e))?;
    let spec = DetectSpec {
        target: TargetSpec {
            legacy: settings.legacy,
            bits: names_family.then_some(settings.bits),
            distance: names_family.then_some(settings.distance),
            family_file: family_file.then(|| PathBuf::from(&settings.family_file)),
            ..TargetSpec::default()
        },
        diameter: settings.detector_diameter().map(Length::from_m),
        camera,
        max_markers: Some(settings.max_markers as usize),
        tracking: settings.tracking,
        // The camera comes from camera_info (the node fits it to each
        // frame); the diameter waits in the configuration until then.
        camera_later: true,
        boards,
        arena,
        ..DetectSpec::default()
    };
    let config = spec.build().map_err(ConfigError::Spec)?;
    if let Target::WhyCode(family) = &config.detector.target {
        if let Some(&id) = settings
            .tag_ids
            .iter()
            .find(|&&id| family.code(id).is_none())
        {
            return Err(ConfigError::ForeignId {
                id,
                bits: family.bits(),
                distance: family.distance(),
                count: family.len(),
            });
        }
    }
    Ok(config)
}

fn integer(
    value: &ParameterValue,
    range: std::ops::RangeInclusive<u32>,
    expected: &'static str,
) -> Result<u32, ParamProblem> {
    match value {
        ParameterValue::Integer(i) => u32::try_from(*i)
            .ok()
            .filter(|v| range.contains(v))
            .ok_or_else(|| wrong(value, expected)),
        other => Err(wrong(other, expected)),
    }
}

/// `value` is not what the parameter takes.
fn wrong(value: &ParameterValue, expected: &'static str) -> ParamProblem {
    ParamProblem::Wrong {
        value: shown(value),
        expected,
    }
}

/// A number: integers are taken for doubles (`-p diameter:=1` is YAML's
/// integer 1).
fn number(value: &ParameterValue) -> Result<f64, ParamProblem> {
    match value {
        ParameterValue::Double(d) => Ok(*d),
        ParameterValue::Integer(i) => Ok(*i as f64),
        other => Err(wrong(other, "a number")),
    }
}

fn boolean(value: &ParameterValue) -> Result<bool, ParamProblem> {
    match value {
        ParameterValue::Boolean(b) => Ok(*b),
        other => Err(wrong(other, "true or false")),
    }
}

fn string(value: &ParameterValue) -> Result<String, ParamProblem> {
    match value {
        ParameterValue::String(s) => Ok(s.clone()),
        other => Err(wrong(other, "a string")),
    }
}

/// A list; an empty list of any type is an empty list.
fn is_empty_list(value: &ParameterValue) -> bool {
    match value {
        ParameterValue::ByteArray(v) => v.is_empty(),
        ParameterValue::BooleanArray(v) => v.is_empty(),
        ParameterValue::IntegerArray(v) => v.is_empty(),
        ParameterValue::DoubleArray(v) => v.is_empty(),
        ParameterValue::StringArray(v) => v.is_empty(),
        _ => false,
    }
}

fn integers(value: &ParameterValue) -> Result<Vec<i64>, ParamProblem> {
    match value {
        ParameterValue::IntegerArray(v) => Ok(v.clone()),
        v if is_empty_list(v) => Ok(Vec::new()),
        other => Err(wrong(other, "a list of integers")),
    }
}

fn numbers(value: &ParameterValue) -> Result<Vec<f64>, ParamProblem> {
    match value {
        ParameterValue::DoubleArray(v) => Ok(v.clone()),
        ParameterValue::IntegerArray(v) => Ok(v.iter().map(|&i| i as f64).collect()),
        v if is_empty_list(v) => Ok(Vec::new()),
        other => Err(wrong(other, "a list of numbers")),
    }
}

fn strings(value: &ParameterValue) -> Result<Vec<String>, ParamProblem> {
    match value {
        ParameterValue::StringArray(v) => Ok(v.clone()),
        v if is_empty_list(v) => Ok(Vec::new()),
        other => Err(wrong(other, "a list of strings")),
    }
}

/// A diameter in metres within the toolkit's plausible marker sizes (or
/// 0, "not set", where `zero_unsets`).
fn diameter(metres: f64, zero_unsets: bool) -> Result<f64, ParamProblem> {
    if (zero_unsets && metres == 0.0) || limits::MARKER_DIAMETER_MM.contains(metres * 1000.0) {
        Ok(metres)
    } else {
        Err(ParamProblem::Diameter {
            metres,
            zero_unsets,
        })
    }
}

/// tf2 frame names: no leading slash, no spaces, not empty.
fn check_frame(frame: &str) -> Result<(), ParamProblem> {
    if frame.is_empty() {
        return Err(ParamProblem::EmptyFrame);
    }
    if frame.starts_with('/') {
        return Err(ParamProblem::RootedFrame(frame.to_string()));
    }
    if let Some(character) = frame
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '/' | '-' | '.')))
    {
        return Err(ParamProblem::FrameCharacter {
            frame: frame.to_string(),
            character,
        });
    }
    Ok(())
}

/// A value as the user wrote it, for messages.
fn shown(value: &ParameterValue) -> String {
    match value {
        ParameterValue::NotSet => "no value".into(),
        ParameterValue::Boolean(b) => b.to_string(),
        ParameterValue::Integer(i) => i.to_string(),
        ParameterValue::Double(d) => d.to_string(),
        ParameterValue::String(s) => format!("'{s}'"),
        other => format!("{other:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn int(i: i64) -> ParameterValue {
        ParameterValue::Integer(i)
    }

    fn text(s: &str) -> ParameterValue {
        ParameterValue::String(s.into())
    }

    #[test]
    fn defaults_round_trip_through_their_declared_values() {
        let defaults = Settings::default();
        let declared: Vec<(String, ParameterValue)> = NAMES
            .iter()
            .map(|n| (n.to_string(), defaults.value(n).unwrap()))
            .collect();
        assert_eq!(Settings::from_parameters(&declared).unwrap(), defaults);
        assert!(defaults.value("nonsense").is_none());
    }

    #[test]
    fn values_are_checked_and_a_refusal_names_the_parameter() {
        let s = Settings::default();
        for (name, value, needle) in [
            ("bits", int(1), "2 to 24"),
            ("bits", text("many"), "2 to 24 or auto"),
            ("distance", int(0), "Hamming distance"),
            ("diameter", ParameterValue::Double(-0.05), "plausible"),
            ("diameter", ParameterValue::Double(20.0), "plausible"),
            ("diameter", ParameterValue::Double(f64::NAN), "plausible"),
            ("diameter", text("5cm"), "not a number"),
            ("max_markers", int(0), "a count"),
            ("tracking", int(1), "true or false"),
            ("image_transport", text("theora"), "raw or compressed"),
            ("camera_frame", text("/camera"), "do not start"),
            ("frame_prefix", text("marker "), "' ' is not allowed"),
            (
                "tag.ids",
                ParameterValue::IntegerArray(vec![3, 0]),
                "IDs start at 1",
            ),
            ("tag.ids", ParameterValue::IntegerArray(vec![3, 3]), "twice"),
            (
                "tag.sizes",
                ParameterValue::DoubleArray(vec![0.0]),
                "plausible",
            ),
            ("tag.frames", text("a"), "list of strings"),
            ("colour", int(1), "no such parameter"),
        ] {
            let err = s.with(name, &value).unwrap_err();
            assert_eq!(err.name, name);
            let err = err.to_string();
            assert!(err.starts_with(&format!("parameter {name}: ")), "{err}");
            assert!(err.contains(needle), "{name}: {err}");
        }
    }

    #[test]
    fn integers_stand_for_doubles_and_empty_lists_for_any_list() {
        let s = Settings::default()
            .with("diameter", &int(1))
            .unwrap()
            .with("bits", &text("AUTO"))
            .unwrap()
            .with("tag.ids", &ParameterValue::IntegerArray(vec![4, 9]))
            .unwrap()
            .with("tag.sizes", &ParameterValue::IntegerArray(vec![2]))
            .unwrap()
            .with("tag.frames", &ParameterValue::StringArray(vec![]))
            .unwrap();
        assert_eq!(s.diameter, 1.0);
        assert_eq!(s.bits, Bits::Auto);
        assert_eq!(s.tag_sizes, [2.0]);
        let s = s
            .with("tag.sizes", &ParameterValue::BooleanArray(vec![]))
            .unwrap();
        assert!(s.tag_sizes.is_empty());
    }

    #[test]
    fn per_id_frames_and_sizes_fall_back_to_the_prefix_and_diameter() {
        let s = Settings::from_parameters(&[
            ("diameter".into(), ParameterValue::Double(0.05)),
            ("tag.ids".into(), ParameterValue::IntegerArray(vec![3, 7])),
            (
                "tag.frames".into(),
                ParameterValue::StringArray(vec!["dock".into()]),
            ),
            (
                "tag.sizes".into(),
                ParameterValue::DoubleArray(vec![0.2, 0.1]),
            ),
        ])
        .unwrap();
        assert_eq!(s.tag(3), (Cow::Borrowed("dock"), Some(0.2)));
        assert_eq!(s.tag(7).0, "whycode_7");
        assert_eq!(s.tag(7).1, Some(0.1));
        assert_eq!(s.tag(5), (Cow::Owned("whycode_5".into()), Some(0.05)));
        // Without a diameter, unlisted IDs have no size.
        let s = s.with("diameter", &ParameterValue::Double(0.0)).unwrap();
        assert_eq!(s.tag(5).1, None);
        assert_eq!(s.detector_diameter(), Some(0.2));
        // More frames than IDs is refused, and the settings stay.
        let err = s
            .with("tag.ids", &ParameterValue::IntegerArray(vec![]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("1 values for 0 tag.ids"), "{err}");
    }

    #[test]
    fn the_detector_config_follows_the_settings() {
        let s = Settings::default()
            .with("bits", &int(12))
            .unwrap()
            .with("distance", &int(3))
            .unwrap()
            .with("diameter", &ParameterValue::Double(0.04))
            .unwrap()
            .with("max_markers", &int(5))
            .unwrap()
            .with("tracking", &ParameterValue::Boolean(false))
            .unwrap();
        let camera = Camera::ideal(640, 480, 60.0);
        let config = detector_config(&s, Some(camera)).unwrap();
        let family = config.detector.target.family().unwrap();
        assert_eq!((family.bits(), family.distance()), (12, 3));
        assert_eq!(config.detector.diameter_m, Some(0.04));
        assert_eq!(config.detector.max_markers, 5);
        assert!(!config.detector.tracking);
        assert_eq!(config.detector.camera, Some(camera));
        let legacy = s.with("legacy", &ParameterValue::Boolean(true)).unwrap();
        assert_eq!(
            detector_config(&legacy, None).unwrap().detector.target,
            Target::WhyCon
        );
        let auto = s.with("bits", &text("auto")).unwrap();
        assert_eq!(
            detector_config(&auto, None).unwrap().detector.target,
            Target::AnyBits { distance: Some(3) }
        );
    }

    #[test]
    fn boards_and_an_arena_come_from_their_files() {
        let dir = std::env::temp_dir().join(format!("whycode-ros2-params-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bundle = dir.join("cube.yaml");
        std::fs::write(
            &bundle,
            "bundles:\n  - name: cube\n    layout:\n      - {id: 1, diameter: 0.05, x: 0, y: 0, z: 0}\n",
        )
        .unwrap();
        let s = Settings::default()
            .with(
                "boards",
                &ParameterValue::StringArray(vec![bundle.display().to_string()]),
            )
            .unwrap();
        // The camera comes with camera_info: boards wait for it.
        let config = detector_config(&s, None).unwrap();
        assert_eq!(config.boards.len(), 1);
        assert_eq!(config.boards[0].name, "cube");
        let missing = dir.join("arena.yaml");
        let s = s
            .with("arena_file", &text(&missing.display().to_string()))
            .unwrap();
        let err = detector_config(&s, None).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!(
                "parameter arena_file: {}: cannot read arena file",
                missing.display()
            )),
            "{err}"
        );
        let err = s.with("arena_frame", &text("")).unwrap_err().to_string();
        assert!(err.starts_with("parameter arena_frame: "), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn impossible_families_and_foreign_ids_are_refused() {
        let s = Settings::default().with("bits", &int(4)).unwrap();
        let s = s.with("distance", &int(5)).unwrap();
        let err = detector_config(&s, None).unwrap_err().to_string();
        assert_eq!(
            err,
            "parameter distance: distance must be between 1 and the bit count 4, got 5"
        );
        let s = Settings::default()
            .with("tag.ids", &ParameterValue::IntegerArray(vec![1, 5000]))
            .unwrap();
        let err = detector_config(&s, None).unwrap_err().to_string();
        assert!(err.contains("not 5000"), "{err}");
        let s = Settings::default()
            .with("family_file", &text("/nonexistent/family.json"))
            .unwrap();
        let err = detector_config(&s, None).unwrap_err().to_string();
        assert!(err.contains("/nonexistent/family.json"), "{err}");
    }
}
