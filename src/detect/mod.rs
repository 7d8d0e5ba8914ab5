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
//! the rectified ring ([`rectify`]).
//!
//! With tracking on, each known marker is first followed where it should
//! be (last position plus velocity) by its edges along a few dozen scan
//! lines, and, once its ID is settled, its yaw from the known code's
//! edges; only if that fails does the flood fill run, and only if a marker
//! is lost is the whole frame scanned (else one band of rows per frame
//! looks for newcomers). IDs of tracked markers go through a Bayesian
//! filter ([`idfilter`], paper 5.1); the test tolerances adapt slowly to
//! what is measured (paper 4.2).

pub mod annotate;
pub mod ellipse;
pub mod idfilter;
pub mod rectify;
pub mod report;
pub mod ring;
pub mod segment;
pub mod threshold;
pub mod track;

use std::f64::consts::PI;
use std::path::Path;

use anyhow::{Context, Result};
use image::GrayImage;

use crate::camera::Camera;
use crate::family::{Decoder, Family, MatchStatus};
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO, WHYCON_WHITE_RATIO};
use crate::pose::{self, CirclePose, Pose};
use ellipse::Ellipse;
use nalgebra::Vector3;
use ring::RingReader;
use segment::{Fill, Filler, Gray, Labels, Stats};
use threshold::{ThresholdMap, ThresholdSearch};
use track::{Adaptive, Track};

/// What to look for and how strictly.
#[derive(Debug, Clone)]
pub struct DetectorConfig {
    /// The ID family of WhyCode markers; None looks for legacy WhyCon
    /// markers (black disc, white disc at 0.41 R, no ID).
    pub family: Option<Family>,
    /// Stop after this many markers in a frame.
    pub max_markers: usize,
    /// Outer diameter of the black disc in metres (needed for pose).
    pub diameter_m: Option<f64>,
    /// Calibrated camera (needed for pose).
    pub camera: Option<Camera>,
    /// Keep state between frames: predicted search, slow adaptation.
    pub tracking: bool,
    /// Smallest outer diameter, pixels, worth reporting.
    pub min_diameter_px: f64,
    /// ρ_max of the roundness test (eq. 1), relative.
    pub roundness_tolerance: f64,
    /// ξ of the ellipse area test (eq. 4), relative.
    pub area_tolerance: f64,
    /// Relative tolerance on the white-to-disc pixel ratio.
    pub ratio_tolerance: f64,
}

impl Default for DetectorConfig {
    fn default() -> DetectorConfig {
        DetectorConfig {
            family: None,
            max_markers: 1024,
            diameter_m: None,
            camera: None,
            tracking: false,
            min_diameter_px: 7.0,
            roundness_tolerance: 0.4,
            area_tolerance: 0.12,
            ratio_tolerance: 0.5,
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
}

/// The detector: configuration, tracking state and reusable buffers.
/// Creating one allocates nothing; buffers grow on the first frame.
#[derive(Debug, Clone)]
pub struct Detector {
    config: DetectorConfig,
    reader: Option<RingReader>,
    labels: Labels,
    filler: Filler,
    edge_scratch: Vec<(f64, f64)>,
    inner_scratch: Vec<(f64, f64)>,
    /// Scan tiles covered by markers followed this frame.
    occupied: Vec<bool>,
    /// A follow of this frame fell back to the flood fill.
    follow_filled: bool,
    tracks: Vec<Track>,
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

/// Width of the scan's chunks (and of the tiles of the followed-marker mask).
const SCAN_CHUNK: usize = 16;
/// A tracked frame looks for new markers in one of this many row bands.
const DISCOVERY_BANDS: u64 = 8;

/// Fraction of the full disc that is white inside the black annulus.
fn expected_white_fraction(whycode: bool) -> f64 {
    if whycode {
        // Centre disc plus the white half of the ring's 2n sectors (Manchester
        // coding makes exactly half of them black, whatever the code).
        let ring = WHYCODE_WHITE_RATIO.powi(2) - RING_INNER_RATIO.powi(2);
        RING_INNER_RATIO.powi(2) + ring / 2.0
    } else {
        WHYCON_WHITE_RATIO.powi(2)
    }
}

/// Slack of the concentricity test, in outer radii: WhyCode's white region
/// has its ring sectors on one side or the other, so its centroid wanders.
fn concentricity_tolerance(whycode: bool) -> f64 {
    if whycode {
        0.2
    } else {
        0.08
    }
}

impl Detector {
    pub fn new(config: DetectorConfig) -> Detector {
        let reader = config
            .family
            .as_ref()
            .map(|family| RingReader::new(Some(Decoder::new(family))));
        let whycode = config.family.is_some();
        let white = expected_white_fraction(whycode);
        Detector {
            ratio: Adaptive::new(white, config.ratio_tolerance),
            roundness: Adaptive::new(0.0, config.roundness_tolerance),
            area: Adaptive::new(0.0, config.area_tolerance),
            config,
            reader,
            labels: Labels::default(),
            filler: Filler::default(),
            edge_scratch: Vec::new(),
            inner_scratch: Vec::new(),
            occupied: Vec::new(),
            follow_filled: false,
            tracks: Vec::new(),
            search: ThresholdSearch::default(),
            frame: 0,
        }
    }

    pub fn config(&self) -> &DetectorConfig {
        &self.config
    }

    /// Forgets tracks and adapted tolerances.
    pub fn reset(&mut self) {
        *self = Detector {
            labels: std::mem::take(&mut self.labels),
            ..Detector::new(self.config.clone())
        };
    }

    /// Finds the markers in one frame. With tracking on, state carries over
    /// to the next call.
    pub fn detect(&mut self, image: &GrayImage) -> Vec<Detection> {
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
        if tracking {
            for index in 0..self.tracks.len() {
                if found.len() >= limit {
                    break;
                }
                if let Some(mut c) = self.follow(gray, index) {
                    c.track = Some(index);
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
                let map = ThresholdMap::adaptive_rows(gray.pixels, width, height, rows.clone());
                self.scan(gray, &map, rows, &mut found, limit);
            }
        } else {
            let map = ThresholdMap::adaptive(gray.pixels, width, height);
            self.scan(gray, &map, 0..height, &mut found, limit);
            if found.is_empty() {
                // The local map found nothing (noise above the markers'
                // contrast, say): a few levels of the reference's global
                // threshold walk. Under a light gradient no one level suits
                // the whole frame, so what each finds is pooled, and the
                // level that found most is tried first next time.
                let histogram = threshold::sampled_histogram(gray.pixels, width);
                let mut best = 0;
                for t in self.search.levels_after_miss(&histogram) {
                    self.labels.begin(width, height);
                    let mut level = Vec::new();
                    self.scan(
                        gray,
                        &ThresholdMap::constant(t),
                        0..height,
                        &mut level,
                        limit,
                    );
                    if level.len() > best {
                        best = level.len();
                        self.search.hit(t);
                    }
                    for c in level {
                        if found.len() < limit
                            && !found.iter().any(|o: &Candidate| {
                                (o.outer.u - c.outer.u).hypot(o.outer.v - c.outer.v) < o.outer.b
                            })
                        {
                            found.push(c);
                        }
                    }
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
                !old.iter()
                    .any(|o| (o.outer.u - c.outer.u).hypot(o.outer.v - c.outer.v) < o.outer.b)
            })
            .cloned()
            .collect();
        found.truncate(followed);
        found.extend(fresh);
        found.truncate(limit);
        let mut detections: Vec<Detection> = Vec::with_capacity(found.len());
        let mut settled_normals = Vec::with_capacity(found.len());
        for c in &found {
            let (d, settled) = self.describe(image, gray, c);
            detections.push(d);
            settled_normals.push(settled);
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
        detections
    }

    /// The detection of a candidate, and its normal when that was told
    /// apart from the other pose candidate with confidence (for the track).
    fn describe(
        &mut self,
        image: &GrayImage,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> (Detection, Option<Vector3<f64>>) {
        let quality = 1.0 - (c.area_error / self.area.tolerance()).min(1.0);
        let outer = pose::ImageEllipse {
            u: c.outer.u,
            v: c.outer.v,
            semi_major: c.outer.a,
            semi_minor: c.outer.b,
            angle: c.outer.angle,
        };
        let mut d = Detection {
            id: 0,
            code: None,
            u: c.outer.u,
            v: c.outer.v,
            yaw: None,
            axes: [c.outer.a, c.outer.b],
            angle: c.outer.angle,
            confidence: (0.5 + 0.5 * quality).clamp(0.0, 1.0),
            status: None,
            pose: None,
        };
        let mut axis_point = None;
        let mut centre_estimate = None;
        let mut settled_normal = None;
        // A marker followed from the last frames whose ID has been read
        // the same several times: its known code's edges give the yaw at a
        // fraction of a full read, and confirm the code on the way.
        let known = c
            .track
            .map(|i| self.tracks[i].clone())
            .filter(|t| t.id_streak >= 3);
        let followed_yaw = match (known, &self.config.family) {
            (Some(t), Some(family)) => match (t.code, t.yaw) {
                (Some(code), Some(yaw)) => {
                    rectify::follow_ring(gray, &c.outer, family.bits(), code, yaw).map(|y| (t, y))
                }
                _ => None,
            },
            _ => None,
        };
        if let Some((t, yaw)) = &followed_yaw {
            let (t, yaw) = (t, *yaw);
            d.id = t.id;
            d.code = t.code;
            d.status = t.status;
            d.yaw = Some(yaw);
            d.confidence = t.confidence;
        } else if let Some(reader) = &self.reader {
            let reading = reader.read(image, &outer, c.black, c.white);
            d.id = reading.id;
            d.code = reading.decoded.filter(|x| x.is_member()).map(|x| x.code);
            d.status = reading.decoded.map(|x| x.status);
            d.yaw = reading.yaw;
            d.confidence = reading.confidence;
            axis_point = reading.axis_point;
            centre_estimate = reading.centre_estimate;
        }
        if let Some(i) = c.track {
            self.filter_identity(gray, c, i, &mut d, followed_yaw.is_some());
        }
        if let (Some(camera), Some(diameter)) = (self.config.camera, self.config.diameter_m) {
            let hints = PoseHints {
                yaw: d.yaw,
                axis_point,
                centre_estimate,
                settled_normal: c.track.and_then(|i| self.tracks[i].normal),
            };
            let (pose, settled) = match self.pose(&camera, diameter / 2.0, gray, c, &outer, hints) {
                Some((pose, settled)) => (Some(pose), settled),
                None => (None, false),
            };
            d.pose = pose;
            settled_normal = d
                .pose
                .filter(|_| settled)
                .map(|p| p.rotation.column(2).into_owned());
            if let (Some(pose), Some(code), Some(family)) = (&d.pose, d.code, &self.config.family) {
                let bits = family.bits();
                if let Some(better) =
                    rectify::refine_rotation(gray, &camera, pose, diameter / 2.0, bits, code)
                {
                    d.pose = Some(better);
                }
            }
            // Under perspective the centre of the outer ellipse is not the
            // image of the marker's centre, nor is the ellipse-based yaw
            // the direction of +x at that centre: the pose knows both.
            if let Some(pose) = &d.pose {
                if let Some((u, v)) = camera.project(&pose.position) {
                    d.u = u;
                    d.v = v;
                }
                if d.yaw.is_some() {
                    d.yaw = pose.image_yaw(&camera).or(d.yaw);
                }
            }
        }
        (d, settled_normal)
    }

    /// Tracked markers report what the ID filter believes after this
    /// frame's reading, not the single reading: one misread (motion blur,
    /// a glint) does not change a marker's ID, and a marker whose readings
    /// disagree is "unknown" until they settle.
    fn filter_identity(
        &mut self,
        gray: Gray<'_>,
        c: &Candidate,
        index: usize,
        d: &mut Detection,
        followed: bool,
    ) {
        let Some(family) = &self.config.family else {
            return;
        };
        let track = &mut self.tracks[index];
        let previous_yaw = track.yaw;
        let estimate = track.observe_reading(family.len(), d);
        if followed || estimate.id == d.id {
            if estimate.id != 0 {
                d.confidence = estimate.probability;
            }
            return;
        }
        d.id = estimate.id;
        d.code = family.code(estimate.id);
        d.confidence = estimate.probability;
        // The reading's yaw belongs to the code it read; the believed code's
        // edges give the yaw instead.
        d.yaw = match (d.code, previous_yaw) {
            (Some(code), Some(yaw)) => {
                rectify::follow_ring(gray, &c.outer, family.bits(), code, yaw)
            }
            _ => None,
        };
    }

    /// Position and normal from the outer edge, the two-fold ambiguity
    /// decided by where the ring shows the marker's centre, else by the
    /// normal this marker's track settled on, else by the inner white
    /// edges; the rotation from the yaw. The flag says whether the normal
    /// was settled (not left to the inner edges).
    fn pose(
        &mut self,
        camera: &Camera,
        radius_m: f64,
        gray: Gray<'_>,
        c: &Candidate,
        outer: &pose::ImageEllipse,
        hints: PoseHints,
    ) -> Option<(Pose, bool)> {
        let PoseHints {
            yaw,
            axis_point,
            centre_estimate,
            settled_normal,
        } = hints;
        let candidates = pose::circle_poses_from_points(camera, &c.edge, radius_m)
            .or_else(|| pose::try_circle_poses(camera, outer, radius_m))?;
        // Both candidates cast the same outer ellipse, but each puts the
        // marker's centre at a different image point, and the ring's radial
        // edges all run through the real one. Under blur and noise this
        // is a far steadier witness than the inner edges' sub-pixel
        // positions, as long as the two points are apart by more than the
        // estimate's own scatter.
        let by_centre = centre_estimate.and_then(|measured| {
            let distance = |p: (f64, f64), q: (f64, f64)| (p.0 - q.0).hypot(p.1 - q.1);
            let first = camera.project(&candidates[0].center)?;
            let second = camera.project(&candidates[1].center)?;
            let apart = distance(first, second);
            let (m0, m1) = (distance(first, measured), distance(second, measured));
            (apart >= CENTRE_SEPARATION_PX && (m0 - m1).abs() >= CENTRE_MARGIN * apart)
                .then_some(usize::from(m1 < m0))
        });
        // A followed marker turns little between frames, while the two
        // candidates lie twice its tilt apart: the one nearer the normal
        // settled earlier is the same solution, and no edge needs sampling.
        let by_track = || {
            let previous = settled_normal?;
            let turn = |k: usize| candidates[k].normal.angle(&previous);
            let (t0, t1) = (turn(0), turn(1));
            ((t0 - t1).abs() >= SETTLED_NORMAL_MARGIN).then_some(usize::from(t1 < t0))
        };
        if let Some(k) = by_centre.or_else(by_track) {
            return Some((full_pose(camera, &candidates[k], yaw, axis_point), true));
        }
        let mid = (c.black + c.white) / 2.0;
        let whycode = self.config.family.is_some();
        let inner_ratios: &[f64] = if whycode {
            &[RING_INNER_RATIO, WHYCODE_WHITE_RATIO]
        } else {
            &[WHYCON_WHITE_RATIO]
        };
        let mut errors = [0.0f64; 2];
        for &ratio in inner_ratios {
            ellipse::inner_edge_points(gray, &c.outer, ratio, mid, &mut self.inner_scratch);
            for (k, candidate) in candidates.iter().enumerate() {
                let rms = pose::circle_point_rms(
                    camera,
                    candidate,
                    &self.inner_scratch,
                    ratio * radius_m,
                );
                errors[k] += rms.map_or(0.0, |r| r * r * self.inner_scratch.len() as f64);
            }
        }
        let circle: &CirclePose = if errors[1] < errors[0] {
            &candidates[1]
        } else {
            &candidates[0]
        };
        Some((full_pose(camera, circle, yaw, axis_point), false))
    }

    /// Marks the tiles that markers followed this frame cover, so that the
    /// scan does not flood-fill them again.
    fn mark_followed(&mut self, found: &[Candidate], width: usize, height: usize) {
        let cols = width.div_ceil(SCAN_CHUNK);
        let rows = height.div_ceil(SCAN_CHUNK);
        self.occupied.clear();
        if found.is_empty() {
            return;
        }
        self.occupied.resize(cols * rows, false);
        for c in found {
            let reach = c.outer.a + 2.0;
            let x0 = ((c.outer.u - reach).max(0.0) as usize) / SCAN_CHUNK;
            let x1 = ((c.outer.u + reach).max(0.0) as usize / SCAN_CHUNK).min(cols - 1);
            let y0 = ((c.outer.v - reach).max(0.0) as usize) / SCAN_CHUNK;
            let y1 = ((c.outer.v + reach).max(0.0) as usize / SCAN_CHUNK).min(rows - 1);
            for ty in y0..=y1 {
                self.occupied[ty * cols + x0.min(x1)..=ty * cols + x1].fill(true);
            }
        }
    }

    /// Scans the rows for dark pixels not yet visited and tests the
    /// segment each one starts.
    fn scan(
        &mut self,
        gray: Gray<'_>,
        map: &ThresholdMap,
        rows: std::ops::Range<usize>,
        found: &mut Vec<Candidate>,
        limit: usize,
    ) {
        const CHUNK: usize = SCAN_CHUNK;
        let shift = map.shift();
        let margin = map.seed_margin();
        let cols = gray.width.div_ceil(CHUNK);
        for y in rows {
            if found.len() >= limit {
                return;
            }
            let row_start = y * gray.width;
            let row = &gray.pixels[row_start..row_start + gray.width];
            let thresholds = map.row(y);
            for (k, chunk) in row.chunks(CHUNK).enumerate() {
                let x0 = k * CHUNK;
                if !self.occupied.is_empty() && self.occupied[(y / CHUNK) * cols + k] {
                    continue;
                }
                let t = thresholds[x0 >> shift].saturating_sub(margin);
                if chunk.iter().copied().min().unwrap_or(255) >= t || map.is_floor(x0, y) {
                    continue;
                }
                for (j, &p) in chunk.iter().enumerate() {
                    if p < t && !self.labels.is_dark_visited(row_start + x0 + j) {
                        if let Some(c) = self.evaluate(gray, map, ((x0 + j) as u32, y as u32)) {
                            found.push(c);
                            if found.len() >= limit {
                                return;
                            }
                        }
                    }
                }
            }
        }
    }

    /// Looks for a tracked marker where it should be now. First the cheap
    /// way: edge points around the predicted outline, a conic fit, and a
    /// check that the centre is white and the annulus black (a few hundred
    /// pixels). If that fails, the paper's way: from the predicted centre
    /// (inside the white centre) along the row to the first dark pixel,
    /// which starts the marker's dark segment and the full tests.
    fn follow(&mut self, gray: Gray<'_>, index: usize) -> Option<Candidate> {
        let track = self.tracks[index].clone();
        let (pu, pv) = track.predicted();
        if let Some(c) = self.follow_edges(gray, &track) {
            return Some(c);
        }
        let (x, y) = (pu.round(), pv.round());
        if !(x >= 0.0 && y >= 0.0 && (x as usize) < gray.width && (y as usize) < gray.height) {
            return None;
        }
        let (x, y) = (x as usize, y as usize);
        let reach = (1.5 * track.a + 2.0) as usize;
        let row = y * gray.width;
        let end = (x + reach).min(gray.width - 1);
        let seed = (x..=end).find(|&xx| gray.pixels[row + xx] < track.threshold)?;
        if self.labels.is_dark_visited(row + seed) {
            return None;
        }
        let map = ThresholdMap::constant(track.threshold);
        self.follow_filled = true;
        let c = self.evaluate(gray, &map, (seed as u32, y as u32))?;
        let moved = (c.outer.u - pu).hypot(c.outer.v - pv);
        let same_size = (c.outer.a / track.a - 1.0).abs() < 0.3;
        (moved < track.a.max(4.0) && same_size).then_some(c)
    }

    fn follow_edges(&mut self, gray: Gray<'_>, track: &Track) -> Option<Candidate> {
        let (pu, pv) = track.predicted();
        let guess = Ellipse {
            u: pu,
            v: pv,
            a: track.a,
            b: track.b,
            angle: track.angle,
        };
        let mid = (track.black + track.white) / 2.0;
        let window = (3.5 + 0.03 * track.a).min(23.0);
        let rays = ellipse::scanline_edge_points(
            gray,
            &guess,
            mid,
            track.white - track.black,
            window,
            &mut self.edge_scratch,
        );
        if self.edge_scratch.len() * 5 < rays * 4 {
            return None;
        }
        let fitted = ellipse::fit_conic(&self.edge_scratch, (pu, pv), track.a)?;
        let rms = (self
            .edge_scratch
            .iter()
            .map(|&(x, y)| ellipse::radial_distance(&fitted, x, y).powi(2))
            .sum::<f64>()
            / self.edge_scratch.len() as f64)
            .sqrt();
        let consistent = rms < 0.3 + 0.01 * track.a
            && (fitted.a / track.a - 1.0).abs() < 0.1
            && (fitted.b / track.b - 1.0).abs() < 0.1
            && (fitted.u - pu).hypot(fitted.v - pv) < window;
        if !consistent {
            return None;
        }
        // Inside: white at the centre, black across the annulus.
        let white_ratio = if self.config.family.is_some() {
            RING_INNER_RATIO
        } else {
            WHYCON_WHITE_RATIO
        };
        let (mut white_sum, mut black_sum) = (0.0, 0.0);
        const PROBES: usize = 8;
        for k in 0..PROBES {
            let t = std::f64::consts::TAU * k as f64 / PROBES as f64;
            let inner = fitted.scaled(0.6 * white_ratio).point(t);
            let annulus = fitted.scaled(0.8).point(t);
            let w = ellipse::sample(gray, inner.0, inner.1)?;
            let b = ellipse::sample(gray, annulus.0, annulus.1)?;
            if w < mid || b >= mid {
                return None;
            }
            white_sum += w;
            black_sum += b;
        }
        let (white, black) = (white_sum / PROBES as f64, black_sum / PROBES as f64);
        Some(Candidate {
            outer: fitted,
            edge: self.edge_scratch.clone(),
            black,
            white,
            ratio: self.ratio.expected,
            roundness: 0.0,
            area_error: 0.0,
            tested: false,
            track: None,
        })
    }

    fn update_tracks(
        &mut self,
        found: &[Candidate],
        detections: &[Detection],
        settled_normals: &[Option<Vector3<f64>>],
    ) {
        let mut next: Vec<Track> = Vec::with_capacity(found.len());
        let mut taken = vec![false; self.tracks.len()];
        for c in found {
            if let Some(i) = c.track {
                taken[i] = true;
            }
        }
        for ((c, d), settled) in found.iter().zip(detections).zip(settled_normals) {
            let threshold = ((c.black + c.white) / 2.0).round().clamp(1.0, 255.0) as u8;
            let (u, v, a, b) = (c.outer.u, c.outer.v, c.outer.a, c.outer.b);
            let index = c.track.or_else(|| {
                let i =
                    (0..self.tracks.len()).find(|&i| !taken[i] && self.tracks[i].matches(u, v))?;
                taken[i] = true;
                Some(i)
            });
            match index {
                Some(i) => {
                    let mut t = self.tracks[i].clone();
                    if c.track.is_none() {
                        // Found again by the scan rather than followed: its
                        // reading has not been filtered yet.
                        if let Some(family) = &self.config.family {
                            t.observe_reading(family.len(), d);
                        }
                    }
                    t.update(u, v, a, b, threshold);
                    t.observe_appearance(c.outer.angle, c.black, c.white);
                    t.observe_identity(d);
                    t.normal = settled.or(t.normal);
                    next.push(t);
                }
                None => {
                    let mut t = Track::new(u, v, a, b, threshold);
                    t.observe_appearance(c.outer.angle, c.black, c.white);
                    if let Some(family) = &self.config.family {
                        t.observe_reading(family.len(), d);
                    }
                    t.observe_identity(d);
                    t.normal = *settled;
                    next.push(t);
                }
            }
        }
        self.tracks = next;
    }

    /// Runs the tests on the dark segment that contains `seed`.
    fn evaluate(
        &mut self,
        gray: Gray<'_>,
        map: &ThresholdMap,
        seed: (u32, u32),
    ) -> Option<Candidate> {
        let whycode = self.config.family.is_some();
        let dark = self
            .filler
            .fill(gray, map, &mut self.labels, seed, Fill::Dark);
        if dark.escaped {
            return None;
        }
        let dark = dark.stats;
        let white_fraction = self.ratio.expected;
        let dark_fraction = 1.0 - white_fraction;
        let min_d = self.config.min_diameter_px;
        let n = dark.count as f64;
        if n < 0.5 * dark_fraction * PI / 4.0 * min_d * min_d {
            return None;
        }
        let (bw, bh) = (f64::from(dark.width()), f64::from(dark.height()));
        if bw < 4.0 || bh < 4.0 {
            return None;
        }
        // Eq. 1: the dark pixels fill the expected share of the bounding
        // box's inscribed ellipse.
        let roundness = n / (PI / 4.0 * bw * bh * dark_fraction) - 1.0;
        if roundness.abs() >= self.roundness.tolerance() {
            return None;
        }
        let (cu, cv) = dark.centroid();
        let bounds = [dark.min_u, dark.min_v, dark.max_u, dark.max_v];
        let max_count = (n * white_fraction / dark_fraction * 2.5) as u64 + 16;
        let white = self.fill_inside(gray, map, (cu, cv), bounds, max_count)?;
        let total = dark.merged(&white);
        let ratio = white.count as f64 / total.count as f64;
        let coarse = Ellipse::from_moments(&total);
        let accepted = self.ratio.accepts(ratio)
            && coarse.is_some_and(|e| {
                let (wu, wv) = white.centroid();
                let radius = (e.a * e.b).sqrt();
                (wu - e.u).hypot(wv - e.v) < concentricity_tolerance(whycode) * radius + 1.0
                    && 2.0 * e.b >= min_d
            });
        let coarse = match coarse {
            Some(e) if accepted => e,
            _ => {
                self.filler.undo_last(&mut self.labels, gray.width);
                return None;
            }
        };
        // Eq. 4 on the whole disc. Pixel counts of small discs carry a
        // boundary quantisation error of about 1/(2b) of the area.
        let area_error = coarse.area() / total.count as f64 - 1.0;
        if area_error.abs() >= self.area.tolerance() + 0.5 / coarse.b {
            return None;
        }
        let black = dark.mean_intensity();
        let white_level = white.mean_intensity();
        if white_level - black < map.min_contrast() {
            return None;
        }
        // The outline must be an ellipse along the whole edge: squares and
        // blobs pass the moment tests (a square's area is within 5 % of its
        // moment ellipse's) but not this.
        let refined = ellipse::refine(gray, &coarse, &mut self.edge_scratch)?;
        if refined.support < 0.75 || refined.rms > 0.35 + 0.015 * coarse.a {
            return None;
        }
        let outer = refined.ellipse;
        Some(Candidate {
            outer,
            edge: self.edge_scratch.clone(),
            black,
            white: white_level,
            ratio,
            roundness,
            area_error: area_error.abs(),
            tested: true,
            track: None,
        })
    }

    /// Fills the white region around the dark segment's centroid (or a
    /// neighbouring pixel when rounding lands on the ring); None when it is
    /// not enclosed by the segment.
    fn fill_inside(
        &mut self,
        gray: Gray<'_>,
        map: &ThresholdMap,
        centre: (f64, f64),
        bounds: [u32; 4],
        max_count: u64,
    ) -> Option<Stats> {
        let (cx, cy) = (centre.0.round() as i64, centre.1.round() as i64);
        for (dx, dy) in [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)] {
            let (x, y) = (cx + dx, cy + dy);
            if x <= i64::from(bounds[0]) || y <= i64::from(bounds[1]) {
                continue;
            }
            let result = self.filler.fill(
                gray,
                map,
                &mut self.labels,
                (x as u32, y as u32),
                Fill::White { bounds, max_count },
            );
            if result.escaped {
                self.filler.undo_last(&mut self.labels, gray.width);
                return None;
            }
            if result.stats.count > 0 {
                return Some(result.stats);
            }
        }
        None
    }
}

/// Least image distance between the two pose candidates' centres at which
/// the ring's centre estimate decides between them; closer, the estimate's
/// scatter under blur and noise could pick either.
const CENTRE_SEPARATION_PX: f64 = 0.3;

/// How much closer (as a fraction of the candidates' separation) the
/// estimate must lie to one candidate's centre. Measured on simulated 12-bit
/// markers at 8-60° tilt with blur and noise: the nearer candidate was right
/// in every case at any margin from 0 to 0.3; 0.5 sent some to the weaker
/// inner-edge test.
const CENTRE_MARGIN: f64 = 0.2;

/// How much nearer (radians) one pose candidate's normal must be to the
/// normal a track settled on than the other's, for the track to decide.
const SETTLED_NORMAL_MARGIN: f64 = 0.1;

/// What the ring reading and the marker's track tell the pose stage.
#[derive(Debug, Clone, Copy)]
struct PoseHints {
    yaw: Option<f64>,
    axis_point: Option<(f64, f64)>,
    centre_estimate: Option<(f64, f64)>,
    settled_normal: Option<Vector3<f64>>,
}

/// The full pose of a circle pose, its rotation about the normal from the
/// ring: the image of the +x axis point, else the yaw, else (legacy
/// markers) an arbitrary 0.
fn full_pose(
    camera: &Camera,
    circle: &CirclePose,
    yaw: Option<f64>,
    axis_point: Option<(f64, f64)>,
) -> Pose {
    match (axis_point, yaw) {
        (Some(p), _) => pose::full_pose(camera, circle, p),
        (None, Some(yaw)) => pose::full_pose_from_yaw(camera, circle, yaw),
        (None, None) => pose::full_pose_from_yaw(camera, circle, 0.0),
    }
}

/// Largest image side accepted by [`load_gray`].
pub const MAX_SIDE: u32 = 30_000;
/// Largest image area accepted by [`load_gray`], pixels.
pub const MAX_PIXELS: u64 = 400_000_000;

/// Reads an image file (PNG, JPEG, PGM/PPM, BMP; 8 or 16 bit; grey or
/// colour) as 8-bit grey. Refuses absurd dimensions before decoding.
pub fn load_gray(path: &Path) -> Result<GrayImage> {
    let name = || path.display().to_string();
    let open = || -> Result<image::ImageReader<std::io::BufReader<std::fs::File>>> {
        Ok(image::ImageReader::open(path)?.with_guessed_format()?)
    };
    let (width, height) = open()
        .and_then(|r| Ok(r.into_dimensions()?))
        .with_context(name)?;
    if width > MAX_SIDE || height > MAX_SIDE || u64::from(width) * u64::from(height) > MAX_PIXELS {
        anyhow::bail!(
            "{}: image of {width}x{height} pixels is larger than the supported {MAX_SIDE} px a side and {} megapixels",
            name(),
            MAX_PIXELS / 1_000_000
        );
    }
    let mut reader = open().with_context(name)?;
    let mut limits = image::Limits::no_limits();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    reader.limits(limits);
    let format = reader.format();
    let decoded = reader.decode().with_context(name)?;
    if format == Some(image::ImageFormat::Jpeg) {
        check_jpeg_complete(path).with_context(name)?;
    }
    Ok(match decoded {
        image::DynamicImage::ImageLuma8(g) => g,
        image::DynamicImage::ImageLuma16(_)
        | image::DynamicImage::ImageLumaA16(_)
        | image::DynamicImage::ImageRgb16(_)
        | image::DynamicImage::ImageRgba16(_) => stretched_to_8_bits(decoded.into_luma16()),
        other => other.into_luma8(),
    })
}

/// Many cameras write 10- or 12-bit data into 16-bit files, which a plain
/// division by 257 squeezes into a handful of grey levels. The brightest
/// value present becomes 255 instead (the detector's thresholds are local,
/// so a linear stretch changes nothing else).
fn stretched_to_8_bits(wide: image::ImageBuffer<image::Luma<u16>, Vec<u16>>) -> GrayImage {
    let brightest = wide.pixels().map(|p| p.0[0]).max().unwrap_or(0).max(1);
    let scale = 255.0 / f64::from(brightest);
    GrayImage::from_fn(wide.width(), wide.height(), |x, y| {
        image::Luma([(f64::from(wide.get_pixel(x, y).0[0]) * scale).round() as u8])
    })
}

/// The JPEG decoder fills a truncated file's missing part with grey and
/// reports no error, which would read as "no markers here". A complete
/// file has an end-of-image marker after its last scan (a thumbnail's EOI
/// comes before the main image's scans; entropy-coded data never holds FF D9).
fn check_jpeg_complete(path: &Path) -> Result<()> {
    let bytes = std::fs::read(path)?;
    let last_scan = bytes.windows(2).rposition(|w| w == [0xFF, 0xDA]);
    let ends = last_scan.is_some_and(|k| bytes[k..].windows(2).any(|w| w == [0xFF, 0xD9]));
    if !ends {
        anyhow::bail!("JPEG file is truncated (no end-of-image marker after its image data)");
    }
    Ok(())
}
