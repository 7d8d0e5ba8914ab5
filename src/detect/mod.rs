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
//! be (last position plus velocity) by its edges along a few dozen scan
//! lines, and, once its ID is settled, its yaw from the known code's
//! edges (on the rectified ring, once, when a pose is wanted; a ring of
//! another family, or read without one, is tested for the bit count it
//! showed last first); only if that fails does the flood fill run, and
//! only if a marker is lost is the whole frame scanned (else one band of
//! rows per frame looks for newcomers). IDs of tracked markers go through a Bayesian
//! filter ([`idfilter`], paper 5.1); the test tolerances adapt slowly to
//! what is measured (paper 4.2).
//!
//! This file holds the types and the per-frame flow ([`Detector::detect`]);
//! `scan.rs` the scan and candidate tests, `describe.rs` what a candidate
//! reads as (ID, yaw, pose: the choice between the two pose candidates is
//! [`crate::pose`]'s), `follow.rs` the following of tracked markers.

pub mod annotate;
mod describe;
pub mod ellipse;
pub mod family_check;
mod follow;
pub mod idfilter;
pub mod legacy;
pub(crate) mod rectify;
pub mod report;
pub mod ring;
mod scan;
pub(crate) mod segment;
pub(crate) mod threshold;
pub(crate) mod track;

use crate::camera::Camera;
use crate::family::{Family, MatchStatus};
use crate::geometry::Design;
use crate::math::Ellipse;
use crate::pose::Pose;
use segment::{Filler, Gray, Labels};
use threshold::{ThresholdMap, ThresholdSearch};
use track::{Adaptive, Track};

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
}

/// The detector: configuration, tracking state and reusable buffers.
/// Creating one allocates nothing; buffers grow on the first frame.
#[derive(Debug, Clone)]
pub struct Detector {
    config: DetectorConfig,
    rings: ring::Rings,
    labels: Labels,
    filler: Filler,
    edge_scratch: Vec<(f64, f64)>,
    inner_scratch: Vec<(f64, f64)>,
    spokes: ellipse::Spokes,
    pose_points: Vec<crate::pose::RadialPoint>,
    /// Scan tiles covered by markers followed this frame.
    occupied: Vec<bool>,
    /// A follow of this frame fell back to the flood fill.
    follow_filled: bool,
    tracks: Vec<Track>,
    /// How this detector's markers decoded so far.
    check: family_check::FamilyCheck,
    search: ThresholdSearch,
    ratio: Adaptive,
    roundness: Adaptive,
    area: Adaptive,
    frame: u64,
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
/// A tracked frame looks for new markers in one of this many row bands.
const DISCOVERY_BANDS: u64 = 8;

impl Detector {
    /// A detector with no state yet; the first frame is scanned whole.
    pub fn new(config: DetectorConfig) -> Detector {
        let white = config.target.design().white_fraction();
        let check = family_check::FamilyCheck::new(config.target.family().map(Family::bits));
        Detector {
            ratio: Adaptive::new(white, config.ratio_tolerance),
            roundness: Adaptive::new(0.0, config.roundness_tolerance),
            area: Adaptive::new(0.0, config.area_tolerance),
            rings: ring::Rings::new(&config.target),
            config,
            labels: Labels::default(),
            filler: Filler::default(),
            edge_scratch: Vec::new(),
            inner_scratch: Vec::new(),
            spokes: ellipse::Spokes::default(),
            pose_points: Vec::new(),
            occupied: Vec::new(),
            follow_filled: false,
            tracks: Vec::new(),
            check,
            search: ThresholdSearch::default(),
            frame: 0,
        }
    }

    /// The settings the detector was made with.
    pub fn config(&self) -> &DetectorConfig {
        &self.config
    }

    /// Fits the configured camera to an image of `width` x `height` with
    /// [`Camera::for_image`] (rescaled for the same sensor at another
    /// resolution, refused for another aspect ratio), so that a calibration
    /// made for another image size never gives silently wrong poses.
    pub fn fit_camera(
        &mut self,
        width: u32,
        height: u32,
    ) -> Result<(), crate::camera::CameraError> {
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
            labels: std::mem::take(&mut self.labels),
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
        let (width, height) = (image.width() as usize, image.height() as usize);
        if width < 3 || height < 3 {
            self.tracks.clear();
            return Vec::new();
        }
        let gray = Gray {
            pixels: image.as_raw(),
            width,
            height,
        };
        self.frame += 1;
        self.labels.begin(width, height);
        let limit = self.config.max_markers;
        let mut found: Vec<Candidate> = Vec::new();
        let tracking = self.config.tracking;
        self.follow_filled = false;
        // A followed marker is described as soon as it is found, while its
        // pixels are still in the cache from following it (on a large
        // frame they would have left it by the time every other marker is
        // followed, and be fetched a second time).
        let mut detections: Vec<Detection> = Vec::new();
        let mut settled_normals = Vec::new();
        if tracking {
            for index in 0..self.tracks.len() {
                if found.len() >= limit {
                    break;
                }
                if let Some(next) = self.tracks.get(index + 1) {
                    // The edge search reaches a window past the outline.
                    let (u, v) = next.predicted();
                    preload_disc(gray, u, v, next.a + follow::edge_window(next.a) + 1.0);
                }
                if let Some(mut c) = self.follow(gray, index) {
                    c.track = Some(index);
                    let (d, settled) = self.describe(image, gray, &c);
                    detections.push(d);
                    settled_normals.push(settled);
                    found.push(c);
                }
            }
        }
        let all_followed = found.len() == self.tracks.len();
        let followed = found.len();
        self.mark_followed(&found, width, height);
        if self.follow_filled {
            // A follow that fell back to the flood fill labelled the
            // pixels it reached with its own threshold, whether or not it
            // found its marker; the scan would skip a marker it missed as
            // already visited. Markers that were followed are kept out of
            // the scan by the occupied tiles and the duplicate test below.
            self.labels.begin(width, height);
        }
        if tracking && all_followed && followed > 0 {
            if found.len() < limit {
                // Every known marker is back: look for new ones in one band
                // of rows per frame, so a tracked frame stays cheap and a
                // newcomer is found within DISCOVERY_BANDS frames.
                let band = (self.frame % DISCOVERY_BANDS) as usize;
                let rows = height * band / DISCOVERY_BANDS as usize
                    ..height * (band + 1) / DISCOVERY_BANDS as usize;
                // The map reaches past the band by the largest marker's
                // diameter, so a newcomer straddling the band's edge lies
                // wholly within it (a dark fill stops where the map does).
                let reach =
                    self.tracks.iter().map(|t| 2.0 * t.a).fold(0.0, f64::max) as usize + SCAN_CHUNK;
                let map_rows = rows.start.saturating_sub(reach)..(rows.end + reach).min(height);
                let map = ThresholdMap::adaptive_rows(gray.pixels, width, height, map_rows);
                self.scan(gray, &map, rows, &[], &mut found);
            }
        } else {
            let map = ThresholdMap::adaptive(gray.pixels, width, height);
            self.scan(gray, &map, 0..height, &[], &mut found);
            let shaded = map
                .shaded_rows()
                .filter(|_| self.config.target.family().is_some());
            if let Some(rows) = shaded {
                // A cast shadow's edge: shaded paper fell below the
                // mid-level threshold. Look again there with thresholds
                // that keep the paper's ratio to the ink. Only where a
                // family's ring test stands between grey clutter (which
                // looks shaded too) and a report.
                let ratio_map =
                    ThresholdMap::adaptive_ratio(gray.pixels, width, height, rows.clone(), &map);
                self.labels.begin(width, height);
                let mut again = Vec::new();
                self.scan_tiles(
                    gray,
                    &ratio_map,
                    rows,
                    map.near_shaded(),
                    &found,
                    &mut again,
                );
                merge_new(&mut found, again, limit);
            }
            if found.is_empty() {
                // The local map found nothing (noise above the markers'
                // contrast, say): a few levels of the reference's global
                // threshold walk. Under a light gradient no one level suits
                // the whole frame, so what each finds is pooled, and the
                // level that found most is tried first next time.
                // Only where the local map was blind (see
                // `ThresholdMap::blind_tiles`) can a level find what it
                // missed; a level that cuts no blind tile is not scanned.
                let histogram = threshold::sampled_histogram(gray.pixels, width);
                let blind = map.blind_tiles(width, height);
                let mut best = 0;
                let mut seeds = Vec::new();
                for t in self.search.levels_after_miss(&histogram) {
                    seeds.clear();
                    seeds.extend(blind.iter().map(|&(lo, hi)| lo < t && t <= hi));
                    if !seeds.contains(&true) {
                        continue;
                    }
                    self.labels.begin(width, height);
                    let mut level = Vec::new();
                    self.scan_tiles(
                        gray,
                        &ThresholdMap::constant(t),
                        0..height,
                        &seeds,
                        &[],
                        &mut level,
                    );
                    if level.len() > best {
                        best = level.len();
                        self.search.hit(t);
                    }
                    merge_new(&mut found, level, limit);
                }
            } else {
                self.search.reset();
            }
        }
        // A marker followed by its edges left no labels; should the scan
        // have met it again, keep the followed one.
        let (old, new) = found.split_at(followed);
        let fresh: Vec<Candidate> = new
            .iter()
            .filter(|c| {
                !old.iter().any(|o| {
                    (o.outer.u - c.outer.u).hypot(o.outer.v - c.outer.v) < o.outer.semi_minor
                })
            })
            .cloned()
            .collect();
        found.truncate(followed);
        found.extend(fresh);
        found.truncate(limit);
        for (k, c) in found.iter().enumerate().skip(followed) {
            if let Some(next) = found.get(k + 1) {
                preload_disc(gray, next.outer.u, next.outer.v, next.reach());
            }
            let (d, settled) = self.describe(image, gray, c);
            detections.push(d);
            settled_normals.push(settled);
        }
        if !self.config.report_unreadable {
            // Round things without a code ring are not markers (and get no
            // track either).
            let keep: Vec<bool> = detections.iter().map(|d| !d.unreadable).collect();
            let mut k = 0;
            found.retain(|_| (keep[k], k += 1).0);
            let mut k = 0;
            settled_normals.retain(|_| (keep[k], k += 1).0);
            detections.retain(|d| !d.unreadable);
        }
        if tracking {
            self.update_tracks(&found, &detections, &settled_normals);
            for c in found.iter().filter(|c| c.tested) {
                self.ratio.learn(c.ratio);
                self.roundness.learn(c.roundness);
                self.area.learn(c.area_error);
            }
        }
        detections.sort_by(|a, b| a.v.total_cmp(&b.v).then(a.u.total_cmp(&b.u)));
        self.check.observe(&detections);
        detections
    }
}

/// Brings the pixels of the square around a marker (centre, half side) on
/// their way into the cache while the marker before it is worked on: on a
/// large frame every marker's pixels have left the cache since they were
/// last read.
fn preload_disc(gray: Gray<'_>, u: f64, v: f64, reach: f64) {
    gray.preload(u - reach..u + reach + 1.0, v - reach..v + reach + 1.0);
}

/// Adds the candidates of another look that are not already found (no
/// found centre within their semi-minor axis), up to `limit`.
fn merge_new(found: &mut Vec<Candidate>, more: Vec<Candidate>, limit: usize) {
    for c in more {
        if found.len() < limit
            && !found
                .iter()
                .any(|o| (o.outer.u - c.outer.u).hypot(o.outer.v - c.outer.v) < o.outer.semi_minor)
        {
            found.push(c);
        }
    }
}
