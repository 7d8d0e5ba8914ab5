//! Finding markers in grey images (paper section 4, spec section 4).
//!
//! Pipeline per candidate: flood fill of a dark segment from any dark pixel
//! (thresholds from a local map, so uneven light does not matter), the
//! roundness test (eq. 1), flood fill of the white inside from the dark
//! segment's centre, the area-ratio and concentricity tests, the ellipse
//! area test (eq. 4) on the whole disc, then a sub-pixel outer ellipse from
//! edge points whose fit must be tight (squares and blobs pass the moment
//! tests, not this). With a family, the ring is read ([`ring`]); with a
//! camera and a diameter, the pose comes from the edge points, the normal
//! ambiguity is settled by the inner white edges and the yaw is measured on
//! the rectified ring (`rectify.rs`).
//!
//! With tracking on, each known marker is first followed where it should
//! be, and only the markers lost, or newcomers in one band of rows, are
//! looked for by the scan (`tracking/`).
//!
//! One file per stage: this one holds the types and the per-frame flow
//! ([`Detector::detect`]: follow tracks, scan, look in shade, global
//! fallback, describe, drop unreadable); `threshold.rs` the local
//! threshold map, `segment.rs` the flood fills, `scan.rs` the scans and the
//! candidate tests, [`ellipse`] the sub-pixel outline, `describe.rs` what a
//! candidate is, from [`ring`] (the code ring's verdict) or [`legacy`];
//! `pose.rs` its pose (the geometry is [`crate::pose`]'s) and `rectify.rs`
//! the yaw on the rectified ring; `tracking/` the following of known
//! markers across frames and their ID filter ([`idfilter`]).

mod describe;
pub mod ellipse;
pub mod family_check;
pub mod identity;
pub mod legacy;
mod pose;
pub(crate) mod rectify;
pub mod ring;
mod scan;
pub(crate) mod segment;
pub(crate) mod threshold;
mod timings;
#[cfg(feature = "trace")]
pub mod trace;
mod tracking;

pub use identity::Unnamed;
pub use timings::{Stage, StageTimings};
pub use tracking::idfilter;

use crate::camera::Camera;
use crate::family::{Family, MatchStatus};
use crate::geometry::Design;
use crate::math::Ellipse;
use crate::pose::Pose;
use segment::Gray;
use threshold::ThresholdSearch;
use timings::Stopwatch;
use tracking::track::{Adaptive, PoseMemory, Tolerances, Track};

/// What to look for and how strictly.
#[derive(Debug, Clone)]
pub struct DetectorConfig {
    /// Which markers to look for.
    pub target: Target,
    /// Stop after this many markers in a frame.
    pub max_markers: usize,
    /// Outer diameter of the black disc in metres (needed for pose).
    pub diameter_m: Option<f64>,
    /// Calibrated camera (needed for pose).
    pub camera: Option<Camera>,
    /// Keep state between frames: predicted search, slow adaptation.
    pub tracking: bool,
    /// Smallest outer diameter, pixels, worth reporting: the outline's
    /// major axis, which a tilt does not shorten.
    pub min_diameter_px: f64,
    /// ρ_max of the roundness test (eq. 1), relative.
    pub roundness_tolerance: f64,
    /// ξ of the ellipse area test (eq. 4), relative.
    pub area_tolerance: f64,
    /// Relative tolerance on the white-to-disc pixel ratio.
    pub ratio_tolerance: f64,
    /// Also report round candidates whose ring shows no Manchester code
    /// structure (flagged `unreadable`); by default they are not markers.
    pub report_unreadable: bool,
    /// Smallest area, pixels, of a legacy WhyCon marker's black ring worth
    /// reporting: the original's own floor (its `minSize`, 100 pixels of
    /// the outer segment), below which a bold letter 'o' of WhyCon's
    /// proportions is a marker to any test (legacy markers carry no ring
    /// to tell them apart). Smaller ones are `unreadable`.
    pub legacy_min_ink_px: f64,
    /// Measure how long each stage of every frame takes, for
    /// [`Detector::last_timings`]. Off, the detector reads no clock (nor
    /// does it on wasm32-unknown-unknown, which has none).
    pub timings: bool,
    /// With tracking, look for new markers over the whole frame every
    /// frame. Off (live use), a frame that lost no marker inside the frame
    /// (those lost at its edge left the view) looks in one band of rows
    /// only, so a marker that comes into view is found within 8 frames; on
    /// (a recording read offline, where nothing waits for the frame), in
    /// the frame it comes.
    pub scan_every_frame: bool,
    /// Read each posed marker's circles along a ray every pixel of their
    /// outline instead of every two (at most 48): projected centres about
    /// a fifth closer to the truth, for several times the pose stage's
    /// time ([`ellipse::EdgeRays::FINE`]). For measuring from photos
    /// (camera calibration), not for video rates.
    pub fine_edges: bool,
}

impl Default for DetectorConfig {
    fn default() -> DetectorConfig {
        DetectorConfig {
            target: Target::WhyCon,
            max_markers: 1024,
            diameter_m: None,
            camera: None,
            tracking: false,
            min_diameter_px: 7.0,
            roundness_tolerance: 0.4,
            area_tolerance: 0.12,
            ratio_tolerance: 0.5,
            report_unreadable: false,
            legacy_min_ink_px: legacy::MIN_INK_PX,
            timings: false,
            scan_every_frame: false,
            fine_edges: false,
        }
    }
}

/// The markers a detector looks for.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// Legacy WhyCon circles: black disc, white disc, no ID.
    WhyCon,
    /// WhyCode markers of one family: the ring is read and decoded to its IDs.
    WhyCode(Family),
    /// WhyCode markers of any bit count (4-24): each ring's count is read
    /// from the ring and reported with its code; with a distance, the ID
    /// in the family of that count and that distance.
    AnyBits {
        /// The families' minimum distance, when IDs are wanted.
        distance: Option<u32>,
    },
}

impl Target {
    /// The marker design to look for, whose proportions the tests use.
    pub fn design(&self) -> Design {
        match self {
            Target::WhyCon => Design::WhyCon,
            Target::WhyCode(_) | Target::AnyBits { .. } => Design::WhyCode,
        }
    }

    /// The family whose codes the rings carry.
    pub fn family(&self) -> Option<&Family> {
        match self {
            Target::WhyCon | Target::AnyBits { .. } => None,
            Target::WhyCode(family) => Some(family),
        }
    }
}

/// One marker found in an image.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    /// Family ID, 0 when unknown (legacy marker, unreadable ring, no member).
    pub id: u32,
    /// The member's code when the ring decoded to one.
    pub code: Option<u32>,
    /// Centre in pixels, origin at the centre of the top-left pixel: the
    /// projected marker centre when a camera and diameter are configured,
    /// otherwise the centre of the outer ellipse (which perspective moves
    /// off the true centre by up to a pixel or two on large tilted markers).
    pub u: f64,
    /// Row of the centre, pixels (see `u`).
    pub v: f64,
    /// Direction of the marker's +x axis in the image, atan2(dv, du);
    /// `None` when it could not be told (legacy markers, unreadable rings).
    pub yaw: Option<f64>,
    /// Semi-axes of the outer ellipse, major first, pixels.
    pub axes: [f64; 2],
    /// Direction of the major axis, atan2(dv, du).
    pub angle: f64,
    /// 0..1: how well the marker passed the tests (and read, with a family).
    pub confidence: f64,
    /// How the ring decoded, with a family.
    pub status: Option<MatchStatus>,
    /// Marker → camera pose, with a camera and a diameter. For legacy
    /// markers (no yaw) the in-plane rotation is arbitrary: +x is the
    /// image +u direction projected onto the marker plane.
    pub pose: Option<Pose>,
    /// Bit count of the code ring as the ring itself shows it (WhyCode
    /// markers whose sectors are wide enough to count); a count other than
    /// the family's means the marker is not of this family (ID 0).
    pub bits: Option<u32>,
    /// A round candidate whose ring shows no Manchester code structure:
    /// reported only with [`DetectorConfig::report_unreadable`].
    pub unreadable: bool,
    /// Why a WhyCode marker has no ID (ID 0): no code ring shows, the ring
    /// could not be read, it reads as no member, ... None when it is
    /// named, and for legacy WhyCon markers, which carry no ID.
    pub unnamed: Option<Unnamed>,
    /// With tracking, the marker's track: the same number in every frame
    /// while it is followed, so markers of one ID (legacy circles are all
    /// ID 0) can be told apart. Numbers start at 1 and are not reused.
    pub track: Option<u32>,
}

/// The detector: configuration, tracking state and reusable buffers.
/// Creating one allocates nothing; buffers grow on the first frame.
#[derive(Debug, Clone)]
pub struct Detector {
    config: DetectorConfig,
    rings: ring::Rings,
    /// What the scan's walk writes.
    walker: scan::Walker,
    /// One more per thread but this one, for the flood fills of a
    /// tracked frame's markers whose edges were missed.
    #[cfg(feature = "parallel")]
    spare_walkers: Vec<scan::Walker>,
    /// What describing a candidate works in, on this thread.
    workspace: Workspace,
    /// One more per thread, for a frame's new candidates described in
    /// parallel.
    workspaces: Vec<Workspace>,
    /// Scan tiles covered by markers followed this frame.
    occupied: Vec<bool>,
    /// A large frame's seed pixels, found before the scan walks them.
    seed_words: Vec<u64>,
    /// A follow of this frame fell back to the flood fill.
    follow_filled: bool,
    tracks: Vec<Track>,
    /// The number the next new track gets.
    next_track: u32,
    /// The configured camera fitted to this frame's size (rescaled for the
    /// same sensor at another resolution); None without a camera, or for a
    /// frame of another aspect ratio, which then gets no pose rather than a
    /// wrong one.
    frame_camera: Option<crate::camera::Camera>,
    /// How this detector's markers decoded so far.
    check: family_check::FamilyCheck,
    /// Discs of this frame that only a legacy WhyCon marker would explain.
    legacy_looking: usize,
    search: ThresholdSearch,
    tolerances: Tolerances,
    frame: u64,
    stopwatch: Stopwatch,
    /// The last frame's stage timings, with `config.timings`.
    timings: Option<StageTimings>,
}

/// The buffers describing a candidate works in, apart from the detector's
/// state: describing reads that state only, so the candidates a scan found
/// can be described on several threads at once, one workspace each.
#[derive(Debug, Clone, Default)]
struct Workspace {
    spokes: ellipse::Spokes,
    inner_scratch: Vec<(f64, f64)>,
    pose_points: Vec<crate::pose::RadialPoint>,
    /// Discs described that only a legacy WhyCon marker would explain.
    legacy_looking: usize,
}

/// A disc that passed every test.
#[derive(Debug, Clone)]
struct Candidate {
    outer: Ellipse,
    /// Sub-pixel points of the outer edge (for pose under distortion).
    edge: Vec<(f64, f64)>,
    black: f64,
    white: f64,
    /// Test values, for adaptation and confidence.
    ratio: f64,
    roundness: f64,
    area_error: f64,
    /// The values above were measured (not a marker followed by its edge).
    tested: bool,
    track: Option<usize>,
    /// What describing it gave, when a scan on several threads had that
    /// done while it went on (never in a build without threads, whose
    /// page this would only make larger).
    #[cfg(feature = "parallel")]
    described: Option<Box<Described>>,
}

/// A new candidate described (see [`Detector::describe_found`]).
#[cfg(feature = "parallel")]
#[derive(Debug, Clone)]
struct Described {
    detection: Detection,
    memory: PoseMemory,
    /// Whether only a legacy WhyCon marker would explain it (0 or 1).
    legacy_looking: usize,
}

impl Candidate {
    /// How far from its centre the marker's pixels reach: the outline's
    /// semi-major axis and the blurred edge beyond it.
    fn reach(&self) -> f64 {
        self.outer.semi_major + 2.0
    }
}

/// Width of the scan's chunks (and of the tiles of the followed-marker mask).
const SCAN_CHUNK: usize = 16;
// The scan's tiles are the threshold map's (seed masks come from the map).
const _: () = assert!(SCAN_CHUNK == 1 << threshold::TILE_SHIFT);

impl Detector {
    /// A detector with no state yet; the first frame is scanned whole.
    pub fn new(config: DetectorConfig) -> Detector {
        let white = config.target.design().white_fraction();
        let check = family_check::FamilyCheck::new(config.target.family().map(Family::bits));
        Detector {
            tolerances: Tolerances {
                ratio: Adaptive::new(white, config.ratio_tolerance),
                roundness: Adaptive::new(0.0, config.roundness_tolerance),
                area: Adaptive::new(0.0, config.area_tolerance),
            },
            rings: ring::Rings::new(&config.target),
            config,
            walker: scan::Walker::default(),
            #[cfg(feature = "parallel")]
            spare_walkers: Vec::new(),
            workspace: Workspace::default(),
            workspaces: Vec::new(),
            occupied: Vec::new(),
            seed_words: Vec::new(),
            follow_filled: false,
            tracks: Vec::new(),
            next_track: 1,
            frame_camera: None,
            check,
            legacy_looking: 0,
            search: ThresholdSearch::default(),
            frame: 0,
            stopwatch: Stopwatch::default(),
            timings: None,
        }
    }

    /// The settings the detector was made with.
    pub fn config(&self) -> &DetectorConfig {
        &self.config
    }

    /// Fits the configured camera to an image of `width` x `height` with
    /// [`Camera::for_image`] (rescaled for the same sensor at another
    /// resolution, refused for another aspect ratio). [`Detector::detect`]
    /// does the same for every frame by itself and gives a frame of another
    /// aspect ratio no pose; a caller calls this first to tell its user why
    /// (a session fits the camera for its front ends).
    pub fn fit_camera(
        &mut self,
        width: u32,
        height: u32,
    ) -> Result<(), crate::camera::OtherCamera> {
        if let Some(camera) = self.config.camera {
            self.config.camera = Some(camera.for_image(width, height)?);
        }
        Ok(())
    }

    /// How the markers of every frame so far decoded: rings of other bit
    /// counts, and IDs that needed error correction (see
    /// [`family_check::FamilyCheck::note`] for a warning to show).
    pub fn family_check(&self) -> &family_check::FamilyCheck {
        &self.check
    }

    /// How many discs of the last frame looked like legacy WhyCon markers
    /// while this detector looked for WhyCode ones (see
    /// [`family_check::FamilyCheck::legacy_looking`]).
    pub fn last_legacy_looking(&self) -> usize {
        self.legacy_looking
    }

    /// How long each stage of the last frame took, with
    /// [`DetectorConfig::timings`] on; None with it off, before the first
    /// frame, and on targets without a clock (wasm32-unknown-unknown).
    pub fn last_timings(&self) -> Option<StageTimings> {
        self.timings
    }

    /// Forgets tracks and adapted tolerances.
    pub fn reset(&mut self) {
        self.restart(self.config.clone());
    }

    /// Starts over as [`Detector::new`] with `config` would, keeping only
    /// the pixel buffers: a worker reading unrelated images one after
    /// another gets the same results as a fresh detector per image without
    /// allocating and clearing a frame-sized buffer each time.
    pub fn restart(&mut self, config: DetectorConfig) {
        *self = Detector {
            walker: std::mem::take(&mut self.walker),
            #[cfg(feature = "parallel")]
            spare_walkers: std::mem::take(&mut self.spare_walkers),
            ..Detector::new(config)
        };
    }

    /// Finds the markers in one frame. With tracking on, state carries over
    /// to the next call.
    ///
    /// Takes any 8-bit grey buffer: an owned [`image::GrayImage`] or a view of
    /// borrowed pixels (`ImageBuffer<Luma<u8>, &[u8]>`), so callers that
    /// hold frames in their own memory (Python's numpy arrays) need no copy.
    pub fn detect<C: std::ops::Deref<Target = [u8]>>(
        &mut self,
        image: &image::ImageBuffer<image::Luma<u8>, C>,
    ) -> Vec<Detection> {
        self.stopwatch.start(self.config.timings);
        let Some(gray) = self.timed(Stage::Prepare, |d| d.begin_frame(image)) else {
            self.timings = self.stopwatch.stop();
            return Vec::new();
        };
        let mut finds = Finds::default();
        if self.config.tracking {
            self.follow_tracks(image, gray, &mut finds);
        }
        let followed = finds.candidates.len();
        // A marker lost inside the frame is looked for in the whole frame;
        // one lost at its edge left the view (or is leaving it): if it
        // comes back, the band finds it as it finds any newcomer.
        let band_only = self.config.tracking
            && !self.config.scan_every_frame
            && followed > 0
            && self.lost_inside(&finds.candidates, gray.width, gray.height) == 0;
        self.timed(Stage::Follow, |d| {
            d.mark_followed(&finds.candidates, gray.width, gray.height)
        });
        let found = &mut finds.candidates;
        if band_only {
            self.timed(Stage::Scan, |d| d.scan_band(gray, found));
        } else {
            let (map, ratio_map) = self.timed(Stage::Scan, |d| d.scan_frame(gray, found));
            self.timed(Stage::Shade, |d| {
                d.look_in_shade(gray, &map, ratio_map, found)
            });
            self.timed(Stage::Fallback, |d| d.global_fallback(gray, &map, found));
        }
        drop_seen_again(found, followed, self.config.max_markers);
        self.describe_new(image, gray, &mut finds);
        let detections = self.timed(Stage::Finish, |d| {
            if !d.config.report_unreadable {
                // Round things without a code ring are not markers (and get
                // no track either).
                finds.drop_unreadable();
            }
            d.end_frame(finds)
        });
        self.timings = self.stopwatch.stop();
        detections
    }

    /// Runs one step of a frame, its time charged to `stage` with the
    /// timings on.
    fn timed<R>(&mut self, stage: Stage, step: impl FnOnce(&mut Self) -> R) -> R {
        let result = step(self);
        self.stopwatch.lap(stage);
        result
    }

    /// Sets up the buffers for a frame, and the frame's pixels as the scan
    /// reads them: None (and the tracks dropped) for a frame too small to
    /// hold a marker.
    fn begin_frame<'a, C: std::ops::Deref<Target = [u8]>>(
        &mut self,
        image: &'a image::ImageBuffer<image::Luma<u8>, C>,
    ) -> Option<Gray<'a>> {
        let (width, height) = (image.width() as usize, image.height() as usize);
        if width < 3 || height < 3 {
            self.tracks.clear();
            return None;
        }
        self.frame += 1;
        self.frame_camera = self
            .config
            .camera
            .and_then(|camera| camera.for_image(image.width(), image.height()).ok());
        self.walker.labels.begin(width, height);
        self.follow_filled = false;
        self.legacy_looking = 0;
        Some(Gray {
            pixels: image.as_raw(),
            width,
            height,
        })
    }

    /// Describes the candidates the scans found (followed markers were
    /// described as they were found): on a large frame in runs of
    /// consecutive candidates on the pool's threads, each run in a
    /// workspace of its own, the detections collected in the candidates'
    /// order.
    fn describe_new<C: std::ops::Deref<Target = [u8]>>(
        &mut self,
        image: &image::ImageBuffer<image::Luma<u8>, C>,
        gray: Gray<'_>,
        finds: &mut Finds,
    ) {
        let new = &finds.candidates[finds.detections.len()..];
        // A borrowed view of the pixels, which threads can share whatever
        // holds them.
        let view = image::ImageBuffer::<image::Luma<u8>, &[u8]>::from_raw(
            image.width(),
            image.height(),
            &**image.as_raw(),
        )
        .expect("an image's buffer holds its pixels");
        // Each marker's pixels are brought towards the cache while the
        // one before it is worked on: on a large frame they have left it
        // since the scan.
        let describe =
            |this: &Detector, ws: &mut Workspace, stopwatch: &mut Stopwatch, k: usize| {
                #[cfg(feature = "parallel")]
                if let Some(early) = &new[k].described {
                    ws.legacy_looking += early.legacy_looking;
                    return (early.detection.clone(), early.memory);
                }
                if let Some(next) = new.get(k + 1) {
                    preload_disc(gray, next.outer.u, next.outer.v, next.reach());
                }
                this.describe_found(ws, stopwatch, &view, gray, &new[k])
            };
        let threads = crate::parallel::frame_threads(gray.width * gray.height).min(new.len());
        if threads <= 1 {
            let mut ws = std::mem::take(&mut self.workspace);
            let mut stopwatch = std::mem::take(&mut self.stopwatch);
            let described = (0..new.len())
                .map(|k| describe(self, &mut ws, &mut stopwatch, k))
                .collect();
            self.stopwatch = stopwatch;
            self.legacy_looking += std::mem::take(&mut ws.legacy_looking);
            self.workspace = ws;
            finds.extend_described(described);
            return;
        }
        let mut workspaces = std::mem::take(&mut self.workspaces);
        let this = &*self;
        let (described, spent) = in_runs(
            threads,
            &mut workspaces,
            self.config.timings,
            new,
            |ws, stopwatch, k, _| describe(this, ws, stopwatch, k),
        );
        finds.extend_described(described);
        self.stopwatch.lap_shared(&spent);
        for ws in &mut workspaces {
            self.legacy_looking += std::mem::take(&mut ws.legacy_looking);
        }
        self.workspaces = workspaces;
    }

    /// The frame's detections in reading order, the tracks and tolerances
    /// updated from them.
    fn end_frame(&mut self, finds: Finds) -> Vec<Detection> {
        let Finds {
            candidates,
            mut detections,
            memories,
        } = finds;
        if self.config.tracking {
            self.update_tracks(&candidates, &mut detections, &memories);
            self.learn_tolerances(&candidates);
        }
        detections.sort_by(|a, b| a.v.total_cmp(&b.v).then(a.u.total_cmp(&b.u)));
        self.check.observe(&detections);
        self.check.legacy_looking += self.legacy_looking;
        detections
    }
}

/// A frame's markers so far: the candidates found, and what the first of
/// them were described as, with what their poses tell their tracks.
#[derive(Debug, Default)]
struct Finds {
    candidates: Vec<Candidate>,
    detections: Vec<Detection>,
    memories: Vec<PoseMemory>,
}

impl Finds {
    /// Adds the detections of the candidates after those already
    /// described, in their order.
    fn extend_described(&mut self, described: Vec<(Detection, PoseMemory)>) {
        for (d, memory) in described {
            self.detections.push(d);
            self.memories.push(memory);
        }
    }

    /// Drops the described candidates that are not markers.
    fn drop_unreadable(&mut self) {
        let keep: Vec<bool> = self.detections.iter().map(|d| !d.unreadable).collect();
        let mut k = 0;
        self.candidates.retain(|_| (keep[k], k += 1).0);
        let mut k = 0;
        self.memories.retain(|_| (keep[k], k += 1).0);
        self.detections.retain(|d| !d.unreadable);
    }
}

/// `work(workspace, stopwatch, index, item)` of every item, in runs of
/// consecutive items on the pool's `threads` (a few runs a thread, so
/// that a run whose items take longer leaves the others' to the rest),
/// each run with a workspace of `workspaces` and a stopwatch of its own
/// (on with `timings`). Gives the results in the items' order and the
/// stopwatches' laps added up.
fn in_runs<T: Sync, R: Send>(
    threads: usize,
    workspaces: &mut Vec<Workspace>,
    timings: bool,
    items: &[T],
    work: impl Fn(&mut Workspace, &mut Stopwatch, usize, &T) -> R + Sync,
) -> (Vec<R>, StageTimings) {
    use crate::parallel::prelude::*;
    let run = items.len().div_ceil(4 * threads).max(1);
    let runs = items.len().div_ceil(run);
    if workspaces.len() < runs {
        workspaces.resize_with(runs, Workspace::default);
    }
    let results: Vec<(Vec<R>, Option<StageTimings>)> = workspaces[..runs]
        .par_iter_mut()
        .zip(items.par_chunks(run))
        .enumerate()
        .map(|(k, (ws, items))| {
            let mut stopwatch = Stopwatch::default();
            stopwatch.start(timings);
            let done = items
                .iter()
                .enumerate()
                .map(|(j, item)| work(ws, &mut stopwatch, k * run + j, item))
                .collect();
            (done, stopwatch.stop())
        })
        .collect();
    let mut spent = StageTimings::default();
    let mut all = Vec::with_capacity(items.len());
    for (done, laps) in results {
        all.extend(done);
        if let Some(laps) = laps {
            spent += &laps;
        }
    }
    (all, spent)
}

/// Drops the candidates after the first `followed` that one of those
/// followed ones found again (a marker followed by its edges left no
/// labels for the scan to skip), and any past `limit`.
fn drop_seen_again(found: &mut Vec<Candidate>, followed: usize, limit: usize) {
    let (old, new) = found.split_at(followed);
    let fresh: Vec<Candidate> = new
        .iter()
        .filter(|c| {
            !old.iter()
                .any(|o| (o.outer.u - c.outer.u).hypot(o.outer.v - c.outer.v) < o.outer.semi_minor)
        })
        .cloned()
        .collect();
    found.truncate(followed);
    found.extend(fresh);
    found.truncate(limit);
}

/// Brings the pixels of the square around a marker (centre, half side) on
/// their way into the cache while the marker before it is worked on: on a
/// large frame every marker's pixels have left the cache since they were
/// last read.
fn preload_disc(gray: Gray<'_>, u: f64, v: f64, reach: f64) {
    gray.preload(u - reach..u + reach + 1.0, v - reach..v + reach + 1.0);
}
