//! Detect's reports: JSON lines, CSV rows and a table, shared by the command
//! line and the bindings so every front end emits the same fields.

use crate::arena::ArenaPosition;
use crate::detect::Detection;
use std::fmt::Write as _;

/// The detections in one image.
#[derive(Debug, Clone)]
pub struct FrameReport {
    /// The image's name as the caller wants it reported (usually its path).
    pub image: String,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Detection time the caller measured (0 when not measured: the library
    /// has no clock on every target).
    pub elapsed_ms: f64,
    /// What was found, in the detector's order.
    pub markers: Vec<Detection>,
    /// Where each marker lies on the arena, in the markers' order (all
    /// `None` without an arena).
    pub places: Vec<Option<ArenaPosition>>,
    /// The configured boards' poses ([`crate::board::BoardTracker::update`]).
    pub boards: Vec<crate::board::BoardPose>,
    /// How long each stage of the detector took on this frame, when asked
    /// for ([`DetectorConfig::timings`](crate::detect::DetectorConfig::timings)).
    pub timings: Option<crate::detect::StageTimings>,
    /// Where the image sits in a recorded stream (a bag or a video).
    pub stream: Option<StreamPosition>,
    /// Discs that looked like legacy WhyCon markers while WhyCode markers
    /// were looked for ([`crate::detect::Detector::last_legacy_looking`]); feeds the
    /// run's hint, not the frame's output.
    pub legacy_looking: usize,
}

/// A frame's place in a recorded stream.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StreamPosition {
    /// 0-based index in the stream.
    pub frame: u64,
    /// A bag's header stamp or a video's presentation time, nanoseconds.
    pub stamp_ns: i64,
    /// The bag topic the frame came from.
    pub topic: Option<String>,
}

/// The CSV header line (without its newline) of a run without an arena;
/// [`FrameReport::to_csv_rows`] writes the rows under it.
pub const CSV_HEADER: &str =
    "image,id,code,u,v,yaw,axis_major,axis_minor,confidence,x,y,z,qx,qy,qz,qw,bits,unreadable";

/// The columns a run's CSV has. They are fixed for the whole run (the header
/// comes before any frame), so the arena columns follow the configuration,
/// not whether a frame happened to place a marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CsvColumns {
    /// An arena is configured: each row ends in arena_x, arena_y, arena_z
    /// (metres) and arena_yaw (radians), empty for a marker not placed.
    /// Without one the columns are absent, so such output is unchanged.
    pub arena: bool,
}

impl CsvColumns {
    /// The columns of a detector with this configuration.
    pub fn of(config: &super::SessionConfig) -> Self {
        Self {
            arena: config.arena.is_some(),
        }
    }

    /// The header line, without its newline.
    pub fn header(self) -> String {
        if self.arena {
            format!("{CSV_HEADER},arena_x,arena_y,arena_z,arena_yaw")
        } else {
            CSV_HEADER.to_string()
        }
    }
}

fn round(x: f64, decimals: i32) -> f64 {
    let k = 10f64.powi(decimals);
    (x * k).round() / k
}

/// JSON records, fields in the documented order.
#[derive(serde::Serialize)]
struct FrameRecord<'a> {
    image: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    frame: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stamp_ns: Option<i64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    topic: Option<&'a str>,
    width: u32,
    height: u32,
    elapsed_ms: f64,
    markers: Vec<MarkerRecord>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    boards: Vec<BoardRecord>,
    #[serde(skip_serializing_if = "Option::is_none")]
    timings: Option<&'a crate::detect::StageTimings>,
}

#[derive(serde::Serialize)]
struct BoardRecord {
    name: String,
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
    quaternion: [f64; 4],
    used: Vec<u32>,
    seen: Vec<u32>,
    rejected: Vec<u32>,
    rms_px: f64,
}

#[derive(serde::Serialize)]
struct MarkerRecord {
    id: u32,
    /// With tracking, the marker's track number.
    #[serde(skip_serializing_if = "Option::is_none")]
    track: Option<u32>,
    code: Option<u32>,
    /// The ring's bit count as read from the ring.
    bits: Option<u32>,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    unreadable: bool,
    /// Why a WhyCode marker has ID 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    unknown: Option<&'static str>,
    u: f64,
    v: f64,
    yaw: Option<f64>,
    axes: [f64; 2],
    confidence: f64,
    position: Option<[f64; 3]>,
    rotation: Option<[[f64; 3]; 3]>,
    quaternion: Option<[f64; 4]>,
    /// With an arena: where the marker lies on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    arena: Option<ArenaRecord>,
}

#[derive(serde::Serialize)]
struct ArenaRecord {
    x: f64,
    y: f64,
    z: f64,
    yaw: Option<f64>,
}

impl FrameReport {
    /// A frame of `width` x `height` with nothing found in it.
    pub fn empty(image: impl Into<String>, width: u32, height: u32) -> FrameReport {
        FrameReport {
            image: image.into(),
            width,
            height,
            elapsed_ms: 0.0,
            markers: Vec::new(),
            places: Vec::new(),
            boards: Vec::new(),
            timings: None,
            stream: None,
            legacy_looking: 0,
        }
    }

    /// Where the `k`-th marker lies on the arena, if it was placed.
    pub fn place(&self, k: usize) -> Option<&ArenaPosition> {
        self.places.get(k).and_then(Option::as_ref)
    }

    /// One JSON object on one line (no newline): image (and for a frame
    /// of a recording: frame, stamp_ns and a bag's topic), width, height,
    /// elapsed_ms and the markers with id, code, u, v, yaw, axes,
    /// confidence, position, rotation, quaternion and, with an arena,
    /// `arena` (x, y, z in metres, yaw in radians); then the boards and
    /// the stage timings, when asked for.
    pub fn to_json(&self) -> String {
        let markers = self
            .markers
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let pose = m.pose.as_ref();
                MarkerRecord {
                    id: m.id,
                    track: m.track,
                    code: m.code,
                    bits: m.bits,
                    unreadable: m.unreadable,
                    unknown: m.unnamed.map(crate::detect::Unnamed::key),
                    u: round(m.u, 3),
                    v: round(m.v, 3),
                    yaw: m.yaw.map(|y| round(y, 5)),
                    axes: [round(m.axes[0], 3), round(m.axes[1], 3)],
                    confidence: round(m.confidence, 3),
                    position: pose.map(|p| {
                        [
                            round(p.position.x, 5),
                            round(p.position.y, 5),
                            round(p.position.z, 5),
                        ]
                    }),
                    rotation: pose.map(|p| {
                        std::array::from_fn(|r| {
                            std::array::from_fn(|c| round(p.rotation[(r, c)], 6))
                        })
                    }),
                    quaternion: pose.map(|p| p.quaternion.map(|q| round(q, 6))),
                    arena: self.place(k).map(|a| ArenaRecord {
                        x: round(a.x, 6),
                        y: round(a.y, 6),
                        z: round(a.z, 6),
                        yaw: a.yaw.map(|y| round(y, 6)),
                    }),
                }
            })
            .collect();
        let stream = self.stream.as_ref();
        let record = FrameRecord {
            image: &self.image,
            frame: stream.map(|s| s.frame),
            stamp_ns: stream.map(|s| s.stamp_ns),
            topic: stream.and_then(|s| s.topic.as_deref()),
            width: self.width,
            height: self.height,
            elapsed_ms: round(self.elapsed_ms, 3),
            markers,
            boards: self
                .boards
                .iter()
                .map(|b| BoardRecord {
                    name: b.name.clone(),
                    position: [
                        round(b.position.x, 6),
                        round(b.position.y, 6),
                        round(b.position.z, 6),
                    ],
                    rotation: std::array::from_fn(|r| {
                        std::array::from_fn(|c| round(b.rotation[(r, c)], 7))
                    }),
                    quaternion: b.quaternion.map(|q| round(q, 7)),
                    used: b.used.clone(),
                    seen: b.seen.clone(),
                    rejected: b.rejected.clone(),
                    rms_px: round(b.rms_px, 4),
                })
                .collect(),
            timings: self.timings.as_ref(),
        };
        serde_json::to_string(&record).expect("plain records serialise")
    }

    /// One CSV row per marker, each ending in a newline, in the columns of
    /// [`CsvColumns::header`].
    pub fn to_csv_rows(&self, columns: CsvColumns) -> String {
        let opt = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
        let image = csv_field(&self.image);
        let mut out = String::new();
        for (k, m) in self.markers.iter().enumerate() {
            let pose = m.pose.as_ref();
            let _ = write!(
                out,
                "{image},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                m.id,
                m.code.map_or(String::new(), |c| c.to_string()),
                round(m.u, 3),
                round(m.v, 3),
                opt(m.yaw.map(|y| round(y, 5))),
                round(m.axes[0], 3),
                round(m.axes[1], 3),
                round(m.confidence, 3),
                opt(pose.map(|p| round(p.position.x, 5))),
                opt(pose.map(|p| round(p.position.y, 5))),
                opt(pose.map(|p| round(p.position.z, 5))),
                opt(pose.map(|p| round(p.quaternion[0], 6))),
                opt(pose.map(|p| round(p.quaternion[1], 6))),
                opt(pose.map(|p| round(p.quaternion[2], 6))),
                opt(pose.map(|p| round(p.quaternion[3], 6))),
                m.bits.map_or(String::new(), |b| b.to_string()),
                u8::from(m.unreadable),
            );
            if columns.arena {
                // Same rounding as the JSON's `arena`.
                let a = self.place(k);
                let _ = write!(
                    out,
                    ",{},{},{},{}",
                    opt(a.map(|a| round(a.x, 6))),
                    opt(a.map(|a| round(a.y, 6))),
                    opt(a.map(|a| round(a.z, 6))),
                    opt(a.and_then(|a| a.yaw).map(|y| round(y, 6))),
                );
            }
            out.push('\n');
        }
        out
    }

    /// Aligned columns for reading, sorted by ID: ID ("?" when unknown, last), code, centre,
    /// yaw in degrees, axes, confidence and, when any marker has a pose, its
    /// position. `with_heading` puts the image's name, size, marker count
    /// and time above the rows and a blank line below (for several images).
    pub fn to_table(&self, with_heading: bool) -> String {
        let mut out = String::new();
        if with_heading {
            let _ = writeln!(
                out,
                "{} ({}x{}, {} markers, {:.1} ms)",
                self.image,
                self.width,
                self.height,
                self.markers.len(),
                self.elapsed_ms
            );
        }
        if self.markers.is_empty() {
            out.push_str("  no markers\n");
            if with_heading {
                out.push('\n');
            }
            return out;
        }
        let has_pose = self.markers.iter().any(|m| m.pose.is_some());
        let _ = write!(
            out,
            "{:>5} {:>6} {:>9} {:>9} {:>8} {:>15} {:>5}",
            "id", "code", "u", "v", "yaw_deg", "axes_px", "conf"
        );
        if has_pose {
            let _ = write!(out, " {:>26}", "position_m (x, y, z)");
        }
        let has_arena = self.places.iter().any(Option::is_some);
        if has_arena {
            let _ = write!(out, " {:>36}", "arena_m (x, y, z), yaw_deg");
        }
        out.push('\n');
        // Sorted by ID for reading (unknown IDs last, then left to right);
        // csv and json keep the detector's order.
        let mut sorted: Vec<_> = self
            .markers
            .iter()
            .enumerate()
            .map(|(k, m)| (m, self.place(k)))
            .collect();
        sorted.sort_by(|(a, _), (b, _)| {
            (a.id == 0, a.id)
                .cmp(&(b.id == 0, b.id))
                .then(a.u.total_cmp(&b.u))
                .then(a.v.total_cmp(&b.v))
        });
        for (m, place) in sorted {
            let id = if m.id == 0 {
                "?".to_string()
            } else {
                m.id.to_string()
            };
            // A ring's code without an ID names its bit count too.
            let code = match (m.code, m.bits) {
                (Some(c), Some(b)) if m.id == 0 => format!("{c}/{b}b"),
                (Some(c), _) => c.to_string(),
                _ => "-".to_string(),
            };
            let yaw = m
                .yaw
                .map_or("-".to_string(), |y| format!("{:.1}", y.to_degrees()));
            let axes = format!("{:.1} x {:.1}", m.axes[0], m.axes[1]);
            let _ = write!(
                out,
                "{id:>5} {code:>6} {:>9.2} {:>9.2} {yaw:>8} {axes:>15} {:>5.2}",
                m.u, m.v, m.confidence
            );
            if m.unreadable {
                out.push_str(" unreadable");
            }
            if let Some(p) = m.pose.as_ref() {
                let _ = write!(
                    out,
                    " {:>26}",
                    format!(
                        "{:.3}, {:.3}, {:.3}",
                        p.position.x, p.position.y, p.position.z
                    )
                );
            } else if has_pose && has_arena {
                let _ = write!(out, " {:>26}", "-");
            }
            if let Some(a) = place {
                let yaw = a
                    .yaw
                    .map_or("-".to_string(), |y| format!("{:.1}", y.to_degrees()));
                let _ = write!(
                    out,
                    " {:>36}",
                    format!("{:.4}, {:.4}, {:.4}, {yaw}", a.x, a.y, a.z)
                );
            }
            if let Some(why) = m.unnamed {
                let _ = write!(out, "  (unknown: {})", why.key());
            }
            out.push('\n');
        }
        if with_heading {
            out.push('\n');
        }
        out
    }
}

fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(image: &str, markers: Vec<Detection>) -> FrameReport {
        FrameReport {
            image: image.to_string(),
            width: 640,
            height: 480,
            elapsed_ms: 1.23456,
            places: vec![None; markers.len()],
            markers,
            boards: Vec::new(),
            timings: None,
            stream: None,
            legacy_looking: 0,
        }
    }

    fn marker(id: u32) -> Detection {
        Detection {
            id,
            code: (id > 0).then_some(7),
            u: 10.12345,
            v: 20.5,
            yaw: (id > 0).then_some(0.123456),
            axes: [30.0, 29.0],
            angle: 0.0,
            confidence: 0.9876,
            status: None,
            pose: None,
            bits: (id > 0).then_some(8),
            unreadable: false,
            unnamed: None,
            track: None,
        }
    }

    #[test]
    fn json_has_the_documented_fields_rounded() {
        let json = frame("a.png", vec![marker(3)]).to_json();
        assert_eq!(
            json,
            "{\"image\":\"a.png\",\"width\":640,\"height\":480,\"elapsed_ms\":1.235,\
\"markers\":[{\"id\":3,\"code\":7,\"bits\":8,\"u\":10.123,\"v\":20.5,\"yaw\":0.12346,\
\"axes\":[30.0,29.0],\"confidence\":0.988,\"position\":null,\"rotation\":null,\"quaternion\":null}]}"
        );
    }

    #[test]
    fn json_and_table_say_why_a_marker_has_no_id() {
        let unread = Detection {
            unnamed: Some(crate::detect::Unnamed::NoCodeRing),
            ..marker(0)
        };
        let report = frame("a.png", vec![unread, marker(3)]);
        let json = report.to_json();
        assert_eq!(
            json.matches("\"unknown\":\"no_code_ring\"").count(),
            1,
            "{json}"
        );
        let table = report.to_table(false);
        assert_eq!(
            table.matches("(unknown: no_code_ring)").count(),
            1,
            "{table}"
        );
    }

    #[test]
    fn csv_quotes_awkward_names_and_leaves_unknowns_empty() {
        let rows = frame("a,\"b\".png", vec![marker(0)]).to_csv_rows(CsvColumns::default());
        assert_eq!(
            rows,
            "\"a,\"\"b\"\".png\",0,,10.123,20.5,,30,29,0.988,,,,,,,,,0\n"
        );
    }

    #[test]
    fn csv_arena_columns_follow_the_configuration_not_the_marker() {
        let mut report = frame("a.png", vec![marker(3), marker(4)]);
        report.places[0] = Some(crate::arena::ArenaPosition {
            x: 1.23456789,
            y: 0.5,
            z: 0.12,
            yaw: None,
        });
        let rows = report.to_csv_rows(CsvColumns { arena: true });
        let lines: Vec<&str> = rows.lines().collect();
        assert!(lines[0].ends_with(",1.234568,0.5,0.12,"), "{rows}");
        assert!(lines[1].ends_with(",,,,"), "{rows}");
        let columns = CsvColumns { arena: true }.header().split(',').count();
        assert!(lines.iter().all(|l| l.split(',').count() == columns));
    }

    #[test]
    fn table_marks_unknown_ids_and_empty_frames() {
        let table = frame("a.png", vec![marker(0)]).to_table(false);
        assert!(table.lines().nth(1).unwrap().trim_start().starts_with("? "));
        assert_eq!(frame("a.png", vec![]).to_table(false), "  no markers\n");
        assert!(frame("a.png", vec![])
            .to_table(true)
            .starts_with("a.png (640x480, 0 markers, 1.2 ms)\n"));
    }
}
