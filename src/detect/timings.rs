//! Where a frame's time goes, stage by stage (AprilTag's time profile):
//! opt-in with [`DetectorConfig::timings`](super::DetectorConfig::timings),
//! read with [`Detector::last_timings`](super::Detector::last_timings).
//!
//! The detector's stages run one after another, and each lap charges the
//! time since the one before to its stage, so the stages add up to the
//! frame. Off, the clock is never read. `std::time::Instant` panics on
//! wasm32-unknown-unknown, which has no clock: there the timings stay off.

use std::fmt;
use std::ops::AddAssign;
use std::time::{Duration, Instant};

use serde::ser::{Serialize, SerializeMap, Serializer};

/// Whether the target has a clock `Instant::now` can read.
const HAS_CLOCK: bool = !cfg!(all(target_arch = "wasm32", target_os = "unknown"));

/// A stage of [`Detector::detect`](super::Detector::detect), in the order
/// a frame runs them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Clearing the frame-sized buffers.
    Prepare,
    /// Following tracked markers by their edges (with tracking on).
    Follow,
    /// The local threshold map (of the whole frame, or of a tracked
    /// frame's band of rows).
    Threshold,
    /// The scan for dark segments and the tests a candidate must pass.
    Scan,
    /// The second look under a cast shadow's edge.
    Shade,
    /// The global threshold walk, when the local map found nothing.
    Fallback,
    /// What each candidate is: the code ring's verdict (or a legacy
    /// marker's inside), and a tracked marker's ID filter.
    Describe,
    /// The 6-DoF pose (with a camera and a diameter).
    Pose,
    /// Dropping what is no marker, updating the tracks, sorting.
    Finish,
}

impl Stage {
    /// Every stage, in the order a frame runs them.
    pub const ALL: [Stage; 9] = [
        Stage::Prepare,
        Stage::Follow,
        Stage::Threshold,
        Stage::Scan,
        Stage::Shade,
        Stage::Fallback,
        Stage::Describe,
        Stage::Pose,
        Stage::Finish,
    ];

    /// The stage's name in tables and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Prepare => "prepare",
            Stage::Follow => "follow",
            Stage::Threshold => "threshold",
            Stage::Scan => "scan",
            Stage::Shade => "shade",
            Stage::Fallback => "fallback",
            Stage::Describe => "describe",
            Stage::Pose => "pose",
            Stage::Finish => "finish",
        }
    }
}

/// How long each [`Stage`] took, over one frame or, added up (`+=`), over
/// several.
///
/// Displays as a table (milliseconds per frame and share of the total);
/// serialises as `{"frames": n, "total_ms": t, "stages_ms": {"prepare":
/// ..., ...}}`, the milliseconds summed over the frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StageTimings {
    stages: [Duration; Stage::ALL.len()],
    frames: u32,
}

impl StageTimings {
    /// Time spent in `stage`.
    pub fn get(&self, stage: Stage) -> Duration {
        self.stages[stage as usize]
    }

    /// Time spent in all stages: the whole of the frames measured.
    pub fn total(&self) -> Duration {
        self.stages.iter().sum()
    }

    /// Frames measured.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Every stage with its time, in the order a frame runs them.
    pub fn iter(&self) -> impl Iterator<Item = (Stage, Duration)> + '_ {
        Stage::ALL.iter().map(|&stage| (stage, self.get(stage)))
    }
}

impl AddAssign<&StageTimings> for StageTimings {
    fn add_assign(&mut self, other: &StageTimings) {
        for (sum, more) in self.stages.iter_mut().zip(other.stages) {
            *sum += more;
        }
        self.frames += other.frames;
    }
}

impl fmt::Display for StageTimings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let total = self.total().as_secs_f64();
        let per_frame = |d: Duration| 1e3 * d.as_secs_f64() / f64::from(self.frames.max(1));
        let share = |d: Duration| {
            if total > 0.0 {
                100.0 * d.as_secs_f64() / total
            } else {
                0.0
            }
        };
        writeln!(f, "{:<10} {:>10} {:>7}", "stage", "ms/frame", "share")?;
        for (stage, time) in self.iter() {
            writeln!(
                f,
                "{:<10} {:>10.3} {:>6.1}%",
                stage.name(),
                per_frame(time),
                share(time)
            )?;
        }
        let frames = match self.frames {
            1 => "1 frame".to_string(),
            n => format!("{n} frames"),
        };
        write!(
            f,
            "{:<10} {:>10.3} {:>6.1}%  ({frames})",
            "total",
            per_frame(self.total()),
            share(self.total())
        )
    }
}

impl Serialize for StageTimings {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        struct Stages<'a>(&'a StageTimings);
        impl Serialize for Stages<'_> {
            fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                let mut map = serializer.serialize_map(Some(Stage::ALL.len()))?;
                for (stage, time) in self.0.iter() {
                    map.serialize_entry(stage.name(), &milliseconds(time))?;
                }
                map.end()
            }
        }
        let mut map = serializer.serialize_map(Some(3))?;
        map.serialize_entry("frames", &self.frames)?;
        map.serialize_entry("total_ms", &milliseconds(self.total()))?;
        map.serialize_entry("stages_ms", &Stages(self))?;
        map.end()
    }
}

/// Milliseconds to the tenth of a microsecond: finer than the clock's
/// repeatability, and without binary fractions' long tails in JSON.
fn milliseconds(time: Duration) -> f64 {
    (1e7 * time.as_secs_f64()).round() / 1e4
}

/// A frame's laps through the stages; reads the clock only when on.
#[derive(Debug, Clone, Default)]
pub(super) struct Stopwatch {
    /// When the last lap ended; None when off.
    last: Option<Instant>,
    laps: StageTimings,
}

impl Stopwatch {
    /// Starts a frame's laps when `on` (and the target has a clock).
    pub(super) fn start(&mut self, on: bool) {
        self.last = None;
        if on && HAS_CLOCK {
            self.laps = StageTimings::default();
            self.last = Some(Instant::now());
        }
    }

    /// Charges the time since the last lap to `stage`.
    #[inline]
    pub(super) fn lap(&mut self, stage: Stage) {
        if let Some(last) = self.last {
            let now = Instant::now();
            self.laps.stages[stage as usize] += now - last;
            self.last = Some(now);
        }
    }

    /// Charges the time since the last lap to the stages of `parts`, the
    /// laps of work done on several threads at once, in proportion to each
    /// stage's share of the threads' time: the stages still add up to the
    /// frame.
    pub(super) fn lap_shared(&mut self, parts: &StageTimings) {
        if let Some(last) = self.last {
            let now = Instant::now();
            let (wall, spent) = (now - last, parts.total().as_secs_f64());
            if spent > 0.0 {
                for (stage, time) in parts.iter() {
                    self.laps.stages[stage as usize] += wall.mul_f64(time.as_secs_f64() / spent);
                }
            }
            self.last = Some(now);
        }
    }

    /// The frame's laps; None when off.
    pub(super) fn stop(&mut self) -> Option<StageTimings> {
        self.last.take()?;
        Some(StageTimings {
            frames: 1,
            ..self.laps
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> StageTimings {
        let mut timings = StageTimings {
            frames: 2,
            ..StageTimings::default()
        };
        timings.stages[Stage::Scan as usize] = Duration::from_micros(1500);
        timings.stages[Stage::Describe as usize] = Duration::from_micros(500);
        timings
    }

    #[test]
    fn stages_add_up_to_the_total_and_sum_over_frames() {
        let mut sum = sample();
        assert_eq!(sum.total(), Duration::from_millis(2));
        sum += &sample();
        assert_eq!(sum.frames(), 4);
        assert_eq!(sum.get(Stage::Scan), Duration::from_millis(3));
        assert_eq!(sum.iter().count(), Stage::ALL.len());
    }

    #[test]
    fn the_table_gives_milliseconds_per_frame_and_shares() {
        let table = sample().to_string();
        let scan = table.lines().find(|l| l.starts_with("scan")).unwrap();
        assert_eq!(
            scan.split_whitespace().collect::<Vec<_>>(),
            ["scan", "0.750", "75.0%"]
        );
        let total = table.lines().last().unwrap();
        assert!(
            total.starts_with("total") && total.ends_with("(2 frames)"),
            "{total}"
        );
    }

    #[test]
    fn json_names_every_stage_in_order() {
        let json = serde_json::to_string(&sample()).unwrap();
        assert!(
            json.starts_with(r#"{"frames":2,"total_ms":2.0,"stages_ms":{"prepare":0.0,"#),
            "{json}"
        );
        assert!(json.contains(r#""scan":1.5,"#), "{json}");
    }

    #[test]
    fn a_detector_times_its_stages_only_when_asked_and_finds_the_same() {
        use crate::detect::{Detector, DetectorConfig, Target};
        use crate::family::Family;
        use crate::geometry::Marker;
        use crate::simulate::{self, LooseMarker, Placement, Scene, SceneObject};

        let family = Family::generate(8, 2).unwrap();
        let mut scene = Scene::new(crate::camera::Camera::ideal(320, 240, 60.0));
        let marker = Marker::whycode(8, family.code(3).unwrap(), 50.0);
        let placement = Placement::facing(0.4);
        scene.objects = vec![SceneObject::Marker(LooseMarker::new(marker, 3, placement))];
        let (image, _) = simulate::render(&scene);
        let config = DetectorConfig {
            target: Target::WhyCode(family),
            tracking: true,
            ..DetectorConfig::default()
        };
        let mut plain = Detector::new(config.clone());
        let mut timed = Detector::new(DetectorConfig {
            timings: true,
            ..config
        });
        for _ in 0..2 {
            let found = plain.detect(&image);
            assert_eq!(found.iter().map(|d| d.id).collect::<Vec<_>>(), [3]);
            assert_eq!(timed.detect(&image), found);
            assert_eq!(plain.last_timings(), None);
            let laps = timed.last_timings().expect("timings on");
            assert_eq!(laps.frames(), 1);
            assert!(laps.get(Stage::Describe) > Duration::ZERO, "{laps}");
            assert_eq!(laps.iter().map(|(_, t)| t).sum::<Duration>(), laps.total());
        }
        // The second frame followed the marker by its edges.
        assert!(timed.last_timings().unwrap().get(Stage::Follow) > Duration::ZERO);
    }

    #[test]
    fn a_stopwatch_that_is_off_gives_nothing() {
        let mut watch = Stopwatch::default();
        watch.start(false);
        watch.lap(Stage::Scan);
        assert_eq!(watch.stop(), None);
        watch.start(true);
        watch.lap(Stage::Scan);
        let laps = watch.stop().unwrap();
        assert_eq!(laps.frames(), 1);
        assert_eq!(laps.total(), laps.get(Stage::Scan));
    }
}
