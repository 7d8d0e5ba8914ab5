//! Finding markers in grey images (paper section 4, spec section 4).
//!
//! Pipeline per candidate: flood fill of a dark segment from any dark pixel
//! (thresholds from a local map, so uneven light does not matter), the
//! roundness test (eq. 1), flood fill of the white inside from the dark
//! segment's centre, the area-ratio and concentricity tests, the ellipse
//! area test (eq. 4) on the whole disc, then a sub-pixel outer ellipse from
//! edge points. With tracking on, the search of a frame starts where each
//! marker is predicted to be, so a frame in which every marker is found
//! again only touches the markers' own pixels.

pub mod ellipse;
pub mod idfilter;
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
    /// Centre in pixels, origin at the centre of the top-left pixel.
    pub u: f64,
    pub v: f64,
    /// Direction of the marker's +x axis in the image, atan2(dv, du).
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
    track: Option<usize>,
}

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
        if !(tracking && all_followed && found.len() >= limit) {
            let map = ThresholdMap::adaptive(gray.pixels, width, height);
            self.scan(gray, &map, &mut found, limit);
            if found.is_empty() {
                // The local map found nothing; the reference's global
                // threshold walk gets one try per frame.
                let t = self.search.next_after_miss();
                self.labels.begin(width, height);
                self.scan(gray, &ThresholdMap::constant(t), &mut found, limit);
            } else {
                self.search.reset();
            }
        }
        if tracking {
            self.update_tracks(&found);
            for c in &found {
                self.ratio.learn(c.ratio);
                self.roundness.learn(c.roundness);
                self.area.learn(c.area_error);
            }
        }
        let mut detections: Vec<Detection> = Vec::with_capacity(found.len());
        for c in &found {
            let d = self.describe(image, gray, c);
            detections.push(d);
        }
        detections.sort_by(|a, b| a.v.total_cmp(&b.v).then(a.u.total_cmp(&b.u)));
        detections
    }

    fn describe(&mut self, image: &GrayImage, gray: Gray<'_>, c: &Candidate) -> Detection {
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
        if let Some(reader) = &self.reader {
            let ring_outer = ring::ImageEllipse {
                u: outer.u,
                v: outer.v,
                semi_major: outer.semi_major,
                semi_minor: outer.semi_minor,
                angle: outer.angle,
            };
            let reading = reader.read(image, &ring_outer, c.black, c.white);
            d.id = reading.id;
            d.code = reading.decoded.filter(|x| x.is_member()).map(|x| x.code);
            d.status = reading.decoded.map(|x| x.status);
            d.yaw = reading.yaw;
            d.confidence = reading.confidence;
            axis_point = reading.axis_point;
        }
        if let (Some(camera), Some(diameter)) = (self.config.camera, self.config.diameter_m) {
            d.pose = self.pose(&camera, diameter / 2.0, gray, c, &outer, d.yaw, axis_point);
        }
        d
    }

    /// Position and normal from the outer edge, the two-fold ambiguity
    /// decided by the inner white edges, the rotation from the yaw.
    #[allow(clippy::too_many_arguments)]
    fn pose(
        &mut self,
        camera: &Camera,
        radius_m: f64,
        gray: Gray<'_>,
        c: &Candidate,
        outer: &pose::ImageEllipse,
        yaw: Option<f64>,
        axis_point: Option<(f64, f64)>,
    ) -> Option<Pose> {
        let candidates = pose::circle_poses_from_points(camera, &c.edge, radius_m)
            .or_else(|| pose::try_circle_poses(camera, outer, radius_m))?;
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
        Some(match (axis_point, yaw) {
            (Some(p), _) => pose::full_pose(camera, circle, p),
            (None, Some(yaw)) => pose::full_pose_from_yaw(camera, circle, yaw),
            (None, None) => pose::full_pose_from_yaw(camera, circle, 0.0),
        })
    }

    /// Scans every row for dark pixels not yet visited and tests the
    /// segment each one starts.
    fn scan(
        &mut self,
        gray: Gray<'_>,
        map: &ThresholdMap,
        found: &mut Vec<Candidate>,
        limit: usize,
    ) {
        const CHUNK: usize = 16;
        let shift = map.shift();
        for y in 0..gray.height {
            if found.len() >= limit {
                return;
            }
            let row_start = y * gray.width;
            let row = &gray.pixels[row_start..row_start + gray.width];
            let thresholds = map.row(y);
            for (k, chunk) in row.chunks(CHUNK).enumerate() {
                let x0 = k * CHUNK;
                let t = thresholds[x0 >> shift];
                if chunk.iter().copied().min().unwrap_or(255) >= t {
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

    /// Looks for a tracked marker where it should be now: from the
    /// predicted centre (inside the white centre) along the row to the
    /// first dark pixel, which starts the marker's dark segment.
    fn follow(&mut self, gray: Gray<'_>, index: usize) -> Option<Candidate> {
        let track = self.tracks[index];
        let (pu, pv) = track.predicted();
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
        let c = self.evaluate(gray, &map, (seed as u32, y as u32))?;
        let moved = (c.outer.u - pu).hypot(c.outer.v - pv);
        let same_size = (c.outer.a / track.a - 1.0).abs() < 0.3;
        (moved < track.a.max(4.0) && same_size).then_some(c)
    }

    fn update_tracks(&mut self, found: &[Candidate]) {
        let mut next: Vec<Track> = Vec::with_capacity(found.len());
        let mut taken = vec![false; self.tracks.len()];
        for c in found {
            if let Some(i) = c.track {
                taken[i] = true;
            }
        }
        for c in found {
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
                    let mut t = self.tracks[i];
                    t.update(u, v, a, b, threshold);
                    next.push(t);
                }
                None => next.push(Track::new(u, v, a, b, threshold)),
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
            .fill(gray, map, &mut self.labels, seed, Fill::Dark)
            .stats;
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
    let decoded = reader.decode().with_context(name)?;
    Ok(match decoded {
        image::DynamicImage::ImageLuma8(g) => g,
        other => other.into_luma8(),
    })
}
