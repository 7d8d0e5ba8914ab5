//! Tracking across frames (paper 4.1-4.2): each known marker is first
//! followed where it should be (last position plus velocity) by its edges
//! along a few dozen scan lines (`follow.rs`), and described at once,
//! while its pixels are in the cache; once its ID is settled, its yaw comes
//! from the known code's edges (on the rectified ring, once, when a pose is
//! wanted). Only if following fails does the flood fill run, and only if a
//! marker is lost inside the frame is the whole frame scanned (else one
//! band of rows per frame looks for newcomers, and for markers that left
//! through the edge and come back). IDs of tracked markers go through a
//! Bayesian filter ([`idfilter`], paper 5.1); the test tolerances adapt
//! slowly to what is measured (paper 4.2, `track.rs`).

mod follow;
pub mod idfilter;
pub(super) mod track;

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::identity::Reading;
use super::pose::Posed;
use super::ring::RingRead;
use super::scan::Passed;
#[cfg(feature = "parallel")]
use super::scan::{Rules, Walker};
use super::segment::Gray;
#[cfg(feature = "parallel")]
use super::segment::Marks;
use super::threshold::ThresholdMap;
use super::{
    in_runs, preload_disc, rectify, Candidate, Detection, Detector, Finds, Stage, Workspace,
    SCAN_CHUNK,
};
use crate::family::Family;
#[cfg(feature = "parallel")]
use follow::{fill_apart, FilledApart};
use track::{PoseMemory, Track};

/// A tracked frame looks for new markers in one of this many row bands.
const DISCOVERY_BANDS: u64 = 8;

/// Frames in a row a marker's ID must have been read the same before its
/// known code is followed instead of read.
const SETTLED_STREAK: u32 = 3;

/// A followed marker's identity from its track, its yaw from the known
/// code's edges.
#[derive(Debug, Clone, Copy)]
pub(super) struct FollowedCode {
    /// What the track read, the yaw measured this frame.
    pub(super) read: RingRead,
    /// The pose, its rotation measured on the code's edges, with a camera
    /// and a diameter.
    pub(super) posed: Option<Posed>,
}

impl Detector {
    /// Follows every tracked marker where it should be now, describing
    /// each as soon as it is found: while its pixels are still in the cache
    /// from following it (on a large frame they would have left it by the
    /// time every other marker is followed, and be fetched a second time).
    pub(super) fn follow_tracks<C: Deref<Target = [u8]>>(
        &mut self,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        finds: &mut Finds,
    ) {
        let threads = crate::parallel::frame_threads(gray.width * gray.height);
        // Past the most markers allowed, which tracks are followed depends
        // on how many were found before them: those frames stay on one
        // thread.
        if threads > 1 && self.tracks.len() > 1 && self.tracks.len() <= self.config.max_markers {
            self.follow_tracks_in_parallel(threads, image, gray, finds);
        } else {
            self.follow_tracks_in_turn(image, gray, finds);
        }
        if self.follow_filled {
            // A follow that fell back to the flood fill labelled the
            // pixels it reached with its own threshold, whether or not it
            // found its marker; the scan would skip a marker it missed as
            // already visited. Markers that were followed are kept out of
            // the scan by the occupied tiles (`Detector::mark_followed`)
            // and the duplicate test after it.
            self.walker.labels.begin(gray.width, gray.height);
        }
    }

    /// [`Detector::follow_tracks`] one track after another.
    fn follow_tracks_in_turn<C: Deref<Target = [u8]>>(
        &mut self,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        finds: &mut Finds,
    ) {
        for index in 0..self.tracks.len() {
            if finds.candidates.len() >= self.config.max_markers {
                break;
            }
            if let Some(next) = self.tracks.get(index + 1) {
                // The edge search reaches a window past the outline.
                let (u, v) = next.predicted();
                preload_disc(gray, u, v, next.a + follow::edge_window(next.a) + 1.0);
            }
            let followed = self.follow(gray, index);
            self.stopwatch.lap(Stage::Follow);
            if let Some(mut c) = followed {
                c.track = Some(index);
                let (d, memory) = self.describe(image, gray, &c);
                finds.detections.push(d);
                finds.memories.push(memory);
                finds.candidates.push(c);
            }
        }
    }

    /// [`Detector::follow_tracks`] on the pool's threads, with the same
    /// results: each track is followed by its edges and its marker read
    /// on some thread; then, in the tracks' order on this one, the tracks
    /// whose edges were missed are flood-filled (each fill labels what the
    /// next may not take), and what the fills found is fitted and read on
    /// the threads; then every reading goes through its track's ID filter
    /// in the tracks' order (which changes that track only, and nothing
    /// the other steps read); then the poses are fitted on the threads.
    fn follow_tracks_in_parallel<C: Deref<Target = [u8]>>(
        &mut self,
        threads: usize,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        finds: &mut Finds,
    ) {
        let view = ImageBuffer::<Luma<u8>, &[u8]>::from_raw(
            image.width(),
            image.height(),
            &**image.as_raw(),
        )
        .expect("an image's buffer holds its pixels");
        let mut workspaces = std::mem::take(&mut self.workspaces);
        let timings = self.config.timings;
        let this = &*self;
        let tracks = &this.tracks;
        let (by_edges, spent) = in_runs(
            threads,
            &mut workspaces,
            timings,
            tracks,
            |ws, stopwatch, index, track| {
                if let Some(next) = tracks.get(index + 1) {
                    // The edge search reaches a window past the outline.
                    let (u, v) = next.predicted();
                    preload_disc(gray, u, v, next.a + follow::edge_window(next.a) + 1.0);
                }
                let followed = this.follow_edges(gray, track, &mut Vec::new());
                stopwatch.lap(Stage::Follow);
                let read = this.read_followed(ws, &view, gray, followed, index);
                stopwatch.lap(Stage::Describe);
                read
            },
        );
        self.stopwatch.lap_shared(&spent);
        // The markers whose edges were missed: their flood fills, then
        // their outlines and readings on the threads, as for those
        // followed by their edges.
        let missed: Vec<usize> = (0..by_edges.len())
            .filter(|&index| by_edges[index].is_none())
            .collect();
        let filled = self.fill_missed(threads, gray, &missed);
        self.stopwatch.lap(Stage::Follow);
        let this = &*self;
        let (by_fill, spent) = in_runs(
            threads,
            &mut workspaces,
            timings,
            &filled,
            |ws, stopwatch, _, (index, passed)| {
                let outline = Detector::outline(gray, passed, &mut Vec::new());
                let fitted = outline.is_some();
                let followed = outline.and_then(|c| this.where_expected(*index, c));
                stopwatch.lap(Stage::Follow);
                let read = this.read_followed(ws, &view, gray, followed, *index);
                stopwatch.lap(Stage::Describe);
                (fitted, read)
            },
        );
        self.stopwatch.lap_shared(&spent);
        let mut by_fill = filled.iter().zip(by_fill).peekable();
        let mut found = Vec::new();
        for (index, read) in by_edges.into_iter().enumerate() {
            let read = read.or_else(|| {
                let ((_, passed), (fitted, read)) = by_fill.next_if(|((i, _), _)| *i == index)?;
                self.walker.note_outline(passed, fitted);
                read
            });
            if let Some((c, reading)) = read {
                let (d, read, posed) = self.settle_identity(gray, &c, reading);
                found.push((c, d, read, posed));
            }
        }
        self.stopwatch.lap(Stage::Describe);
        let this = &*self;
        let (posed, spent) = in_runs(
            threads,
            &mut workspaces,
            timings,
            &found,
            |ws, stopwatch, _, (c, d, read, posed)| {
                let mut d = d.clone();
                let memory = this.measure_pose(ws, gray, c, &mut d, read, *posed);
                stopwatch.lap(Stage::Pose);
                (d, memory)
            },
        );
        self.stopwatch.lap_shared(&spent);
        self.workspaces = workspaces;
        for ((c, ..), (d, memory)) in found.into_iter().zip(posed) {
            finds.detections.push(d);
            finds.memories.push(memory);
            finds.candidates.push(c);
        }
    }

    /// The flood fills of the tracks `missed` (in the tracks' order) whose
    /// edges were missed, with the segments that passed their tests: the
    /// same as one thread filling them in turn, where each fill's labels
    /// keep the next from the pixels it took.
    #[cfg_attr(not(feature = "parallel"), allow(unused_variables))]
    fn fill_missed(
        &mut self,
        threads: usize,
        gray: Gray<'_>,
        missed: &[usize],
    ) -> Vec<(usize, Passed)> {
        #[cfg(feature = "parallel")]
        if !cfg!(feature = "trace") && threads > 1 && missed.len() > 1 {
            return self.fill_missed_apart(threads, gray, missed);
        }
        missed
            .iter()
            .filter_map(|&index| Some((index, self.fill_tracked(gray, index)?)))
            .collect()
    }

    /// [`Detector::fill_missed`] on the threads, each fill in labels of
    /// its own; then, in the tracks' order, a fill whose pixels (and the
    /// pixels round them) no earlier fill's reached is taken as it is, and
    /// any other is made again in the labels the earlier fills round it
    /// left, as one thread would have.
    #[cfg(feature = "parallel")]
    fn fill_missed_apart(
        &mut self,
        threads: usize,
        gray: Gray<'_>,
        missed: &[usize],
    ) -> Vec<(usize, Passed)> {
        use crate::parallel::prelude::*;
        let mut spare = std::mem::take(&mut self.spare_walkers);
        spare.resize_with(threads - 1, Walker::default);
        let chunk = missed.len().div_ceil(threads);
        let apart: Vec<Vec<(usize, Option<FilledApart>)>> = {
            let rules = Rules::new(&self.config, &self.tolerances, &self.occupied);
            let tracks = &self.tracks;
            let mut walkers: Vec<&mut Walker> = std::iter::once(&mut self.walker)
                .chain(spare.iter_mut())
                .collect();
            walkers
                .par_iter_mut()
                .zip(missed.par_chunks(chunk))
                .map(|(walker, indices)| {
                    walker.labels.begin(gray.width, gray.height);
                    indices
                        .iter()
                        .map(|&index| (index, fill_apart(&rules, walker, gray, &tracks[index])))
                        .collect()
                })
                .collect()
        };
        self.spare_walkers = spare;
        self.walker.labels.begin(gray.width, gray.height);
        let mut earlier = Reached::new(gray.width, gray.height);
        let mut filled = Vec::new();
        let mut before = Vec::new();
        for (index, fill) in apart.into_iter().flatten() {
            // No fill starts (which reads no labels): none on one thread.
            let Some(fill) = fill else { continue };
            let near = earlier.near(fill.reach);
            let (passed, marks) = if near.is_empty() {
                self.follow_filled = true;
                (fill.passed, fill.marks)
            } else {
                // The labels one thread would have round this fill.
                self.walker.labels.begin(gray.width, gray.height);
                for &k in &near {
                    self.walker.labels.put_marks(&earlier.marks[k]);
                }
                before.clear();
                self.walker.labels.marks_in(fill.reach, false, &mut before);
                let passed = self.fill_tracked(gray, index);
                let mut after = Vec::new();
                self.walker.labels.marks_in(fill.reach, true, &mut after);
                (passed, only_new(after, &before))
            };
            earlier.push(fill.reach, marks);
            if let Some(passed) = passed {
                filled.push((index, passed));
            }
        }
        filled
    }

    /// Candidate `followed`, found where track `index` expected its marker,
    /// as that track's, with what its pixels say of it.
    fn read_followed(
        &self,
        ws: &mut Workspace,
        image: &ImageBuffer<Luma<u8>, &[u8]>,
        gray: Gray<'_>,
        followed: Option<Candidate>,
        index: usize,
    ) -> Option<(Candidate, Reading)> {
        let mut c = followed?;
        c.track = Some(index);
        let reading = self.read_tracked(ws, image, gray, &c);
        Some((c, reading))
    }

    /// Per track, whether a candidate of `found` was followed as it.
    fn tracks_of(&self, found: &[Candidate]) -> Vec<bool> {
        let mut taken = vec![false; self.tracks.len()];
        for i in found.iter().filter_map(|c| c.track) {
            taken[i] = true;
        }
        taken
    }

    /// How many tracks were lost inside the frame: not followed this
    /// frame (`followed` holds no candidate of theirs), their outline as
    /// predicted wholly within the frame. A track lost where that outline
    /// reaches past the frame's edge left the view, or is leaving it.
    pub(super) fn lost_inside(&self, followed: &[Candidate], width: usize, height: usize) -> usize {
        let seen = self.tracks_of(followed);
        let inside = |track: &Track| {
            let (u, v) = track.predicted();
            let reach = track.a + follow::edge_window(track.a);
            let within = |x: f64, size: usize| x - reach >= 0.0 && x + reach < size as f64;
            within(u, width) && within(v, height)
        };
        self.tracks
            .iter()
            .zip(seen)
            .filter(|&(track, seen)| !seen && inside(track))
            .count()
    }

    /// Looks for markers new to a frame that lost no marker inside it
    /// (every known marker is back, or left through the frame's edge):
    /// in one band of rows per frame, so a tracked frame stays cheap and a
    /// newcomer is found within [`DISCOVERY_BANDS`] frames.
    pub(super) fn scan_band(&mut self, gray: Gray<'_>, found: &mut Vec<Candidate>) {
        if found.len() >= self.config.max_markers {
            return;
        }
        let (width, height) = (gray.width, gray.height);
        let band = (self.frame % DISCOVERY_BANDS) as usize;
        let rows = height * band / DISCOVERY_BANDS as usize
            ..height * (band + 1) / DISCOVERY_BANDS as usize;
        // The map reaches past the band by the largest marker's diameter,
        // so a newcomer straddling the band's edge lies wholly within it (a
        // dark fill stops where the map does).
        let reach = self.tracks.iter().map(|t| 2.0 * t.a).fold(0.0, f64::max) as usize + SCAN_CHUNK;
        let map_rows = rows.start.saturating_sub(reach)..(rows.end + reach).min(height);
        let map = ThresholdMap::adaptive_rows(gray.pixels, width, height, map_rows);
        self.stopwatch.lap(Stage::Threshold);
        self.scan(Stage::Scan, gray, &map, rows, &[], found);
    }

    /// A followed marker whose ID its track has read the same several
    /// times: its known code's edges give the yaw at a fraction of a full
    /// read, and confirm the code on the way. With a pose to give, the
    /// code's edges are measured once, on the rectified ring that gives
    /// the rotation; without, along the image ellipse. None when the track
    /// has not settled, or the code's edges do not show (then the ring is
    /// read).
    pub(super) fn follow_code(
        &self,
        ws: &mut Workspace,
        gray: Gray<'_>,
        c: &Candidate,
        index: usize,
    ) -> Option<FollowedCode> {
        let track = &self.tracks[index];
        if track.id_streak < SETTLED_STREAK {
            return None;
        }
        let bits = self.config.target.family().map(Family::bits)?;
        let (code, previous_yaw) = (track.code?, track.yaw?);
        let followed = self.follow_pose(ws, gray, c, index);
        let yaw = match &followed {
            Some(followed) => followed.yaw,
            None => rectify::follow_ring(gray, &c.outer, bits, code, previous_yaw)?,
        };
        let track = &self.tracks[index];
        Some(FollowedCode {
            read: RingRead {
                id: track.id,
                code: track.code,
                status: track.status,
                yaw: Some(yaw),
                confidence: track.confidence,
                // The count its ring showed when it was read: following the
                // code's edges confirms it.
                bits: track.bits,
                ..RingRead::nothing(0.0)
            },
            posed: followed.map(|f| f.posed),
        })
    }

    /// Whether track `index` has settled on an ID: a marker whose ring
    /// blurs is still the marker.
    pub(super) fn settled(&self, index: usize) -> bool {
        let track = &self.tracks[index];
        track.id != 0 && track.id_streak >= SETTLED_STREAK
    }

    pub(super) fn update_tracks(
        &mut self,
        found: &[Candidate],
        detections: &mut [Detection],
        poses: &[PoseMemory],
    ) {
        let mut next: Vec<Track> = Vec::with_capacity(found.len());
        let mut taken = self.tracks_of(found);
        for ((c, d), pose) in found.iter().zip(detections.iter_mut()).zip(poses) {
            let threshold = ((c.black + c.white) / 2.0).round().clamp(1.0, 255.0) as u8;
            let (u, v, a, b) = (c.outer.u, c.outer.v, c.outer.semi_major, c.outer.semi_minor);
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
                        if let Some(family) = self.config.target.family() {
                            t.observe_reading(family.len(), d);
                        }
                    }
                    t.update(u, v, a, b, threshold);
                    t.observe_appearance(c.outer.angle, c.black, c.white);
                    t.observe_identity(d);
                    t.normal = pose.settled_normal.or(t.normal);
                    t.fitted = pose.fitted;
                    d.track = Some(t.number);
                    next.push(t);
                }
                None => {
                    let mut t = Track::new(u, v, a, b, threshold);
                    t.number = self.next_track;
                    self.next_track += 1;
                    d.track = Some(t.number);
                    t.observe_appearance(c.outer.angle, c.black, c.white);
                    if let Some(family) = self.config.target.family() {
                        t.observe_reading(family.len(), d);
                    }
                    t.observe_identity(d);
                    t.normal = pose.settled_normal;
                    t.fitted = pose.fitted;
                    next.push(t);
                }
            }
        }
        self.tracks = next;
    }

    /// The test tolerances follow what the candidates that passed the
    /// tests measured (not those followed by their edges).
    pub(super) fn learn_tolerances(&mut self, found: &[Candidate]) {
        for c in found.iter().filter(|c| c.tested) {
            self.tolerances.ratio.learn(c.ratio);
            self.tolerances.roundness.learn(c.roundness);
            self.tolerances.area.learn(c.area_error);
        }
    }
}

/// The boxes of the fills taken so far in a frame and the labels each
/// left, found by the grid cells the boxes cover.
#[cfg(feature = "parallel")]
struct Reached {
    boxes: Vec<[u32; 4]>,
    marks: Vec<Vec<Marks>>,
    cells: Vec<Vec<usize>>,
    columns: usize,
}

/// Pixels on a side of a cell of [`Reached`]'s grid.
#[cfg(feature = "parallel")]
const REACHED_CELL: u32 = 128;

#[cfg(feature = "parallel")]
impl Reached {
    fn new(width: usize, height: usize) -> Reached {
        let columns = width.div_ceil(REACHED_CELL as usize);
        let rows = height.div_ceil(REACHED_CELL as usize);
        Reached {
            boxes: Vec::new(),
            marks: Vec::new(),
            cells: vec![Vec::new(); columns * rows],
            columns,
        }
    }

    /// The cells `area` covers.
    fn cells_of(&self, area: [u32; 4]) -> impl Iterator<Item = usize> + '_ {
        let rows = self.cells.len() / self.columns;
        let [c0, r0, c1, r1] = area.map(|x| x / REACHED_CELL);
        let (c1, r1) = (c1.min(self.columns as u32 - 1), r1.min(rows as u32 - 1));
        (r0..=r1).flat_map(move |r| (c0..=c1).map(move |c| r as usize * self.columns + c as usize))
    }

    /// The fills so far whose boxes meet `area` grown by a pixel each way,
    /// in the order taken.
    fn near(&self, area: [u32; 4]) -> Vec<usize> {
        let grown = [
            area[0].saturating_sub(1),
            area[1].saturating_sub(1),
            area[2] + 1,
            area[3] + 1,
        ];
        let mut near: Vec<usize> = self
            .cells_of(grown)
            .flat_map(|cell| self.cells[cell].iter().copied())
            .filter(|&k| {
                let b = self.boxes[k];
                b[0] <= grown[2] && grown[0] <= b[2] && b[1] <= grown[3] && grown[1] <= b[3]
            })
            .collect();
        near.sort_unstable();
        near.dedup();
        near
    }

    fn push(&mut self, area: [u32; 4], marks: Vec<Marks>) {
        let k = self.boxes.len();
        let cells: Vec<usize> = self.cells_of(area).collect();
        for cell in cells {
            self.cells[cell].push(k);
        }
        self.boxes.push(area);
        self.marks.push(marks);
    }
}

/// The marks of `after` not in `before` (both in the order
/// [`Labels::marks_in`] lists a box's words).
#[cfg(feature = "parallel")]
fn only_new(after: Vec<Marks>, before: &[Marks]) -> Vec<Marks> {
    let mut before = before.iter().peekable();
    after
        .into_iter()
        .filter_map(|mut m| {
            while before
                .next_if(|b| (b.row, b.word) < (m.row, m.word))
                .is_some()
            {}
            if let Some(b) = before.next_if(|b| (b.row, b.word) == (m.row, m.word)) {
                m.dark &= !b.dark;
                m.white &= !b.white;
            }
            (m.dark | m.white != 0).then_some(m)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::detect::{Detector, DetectorConfig, Target};
    use crate::family::Family;
    use crate::geometry::Marker;
    use crate::simulate::{self, LooseMarker, Placement, Scene, SceneObject};

    #[test]
    fn a_followed_marker_keeps_reporting_the_count_its_ring_showed() {
        let family = Family::generate(8, 2).unwrap();
        let mut scene = Scene::new(crate::camera::Camera::ideal(320, 240, 60.0));
        let marker = Marker::whycode(8, family.code(5).unwrap(), 50.0);
        let placement = Placement::viewed(nalgebra::Vector3::new(0.02, 0.0, 0.4), 0.3, 0.0, 1.0);
        scene.objects = vec![SceneObject::Marker(LooseMarker::new(marker, 5, placement))];
        let (image, _) = simulate::render(&scene);
        let mut detector = Detector::new(DetectorConfig {
            target: Target::WhyCode(family),
            tracking: true,
            ..DetectorConfig::default()
        });
        // From the fourth frame on its code is followed, not read.
        for frame in 0..6 {
            let found = detector.detect(&image);
            let seen: Vec<_> = found.iter().map(|d| (d.id, d.bits)).collect();
            assert_eq!(seen, [(5, Some(8))], "frame {frame}");
        }
    }

    /// A marker 70 px across moving 20 px a frame that turns back, then
    /// stops. Where it turns its track predicted it 40 px off, past its
    /// radius: the flood fill from where it was finds it, and its track
    /// goes on (a fill from the prediction found nothing, the track was
    /// lost and the marker taken for a new one). The frames after that
    /// find it by its edges again, where the smoothed velocity alone would
    /// have missed them for three more frames; one that stops is found by
    /// its edges at once.
    #[test]
    fn a_marker_that_turns_back_or_stops_keeps_its_track_and_is_found_by_its_edges() {
        let family = Family::generate(8, 2).unwrap();
        let camera = crate::camera::Camera::ideal(640, 480, 60.0);
        let marker = Marker::whycode(8, family.code(3).unwrap(), 50.0);
        let mut detector = Detector::new(DetectorConfig {
            target: Target::WhyCode(family),
            tracking: true,
            ..DetectorConfig::default()
        });
        // Twenty pixels a frame to the right, back for five frames, then
        // standing still.
        let path = [0, 1, 2, 3, 4, 5, 4, 3, 2, 1, 0, 0, 0, 0];
        let (mut filled, mut tracks) = (Vec::new(), Vec::new());
        for (frame, &step) in path.iter().enumerate() {
            let u = 220.0 + 20.0 * f64::from(step);
            let placement = Placement::at_pixel(&camera, &marker, (u, 240.0), 70.0, 0.0, 0.0, 0.4);
            let mut scene = Scene::new(camera);
            scene.objects = vec![SceneObject::Marker(LooseMarker::new(marker, 3, placement))];
            let (image, _) = simulate::render(&scene);
            let found = detector.detect(&image);
            assert_eq!(found.len(), 1, "frame {frame}");
            assert_eq!(found[0].id, 3, "frame {frame}");
            let off = (found[0].u - u).hypot(found[0].v - 240.0);
            assert!(off < 0.5, "frame {frame}: {off} px off");
            if detector.follow_filled {
                filled.push(frame);
            }
            tracks.push(found[0].track);
        }
        assert!(tracks.iter().all(|&t| t == tracks[0]), "{tracks:?}");
        // Frame 1 is the track's second (no velocity yet), frame 6 turns
        // back, frame 11 stops.
        assert_eq!(filled, [1, 6]);
    }
}
