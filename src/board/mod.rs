//! Boards and bundles: one pose from many markers fixed to one rigid body.
//!
//! A board is given by a sheet's manifest (each page a plane; the board
//! frame is the page's top-left corner, x along the top edge, y down the
//! page, z into the page, metres) or by a bundle file listing each marker's
//! ID, diameter and pose (or only position) in the bundle's frame, as
//! apriltag_ros's tag bundles do, so 3D rigs (a cube of markers) work.
//!
//! The pose comes from every marker seen: each marker's projected centre,
//! plus (weakly) each marker's own orientation, which alone decides the
//! directions a single marker or a line of markers leaves open. Markers
//! that disagree with the rest (a wrong ID, a moved marker) are left out
//! and named.

mod smooth;
pub use smooth::BoardTracker;

use std::path::Path;

use nalgebra::{DVector, Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde::Deserialize;

use crate::camera::Camera;
use crate::detect::Detection;
use crate::error::{refuse, FileKind, LoadError, LoadProblem};
use crate::family::MatchStatus;
use crate::manifest::Manifest;
use crate::math::least_squares::{levenberg_marquardt, numeric_jacobian};
use crate::pose::{self, Pose};

/// One marker of a board.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardMarker {
    /// Family ID.
    pub id: u32,
    /// Outer diameter of the black disc, metres.
    pub diameter_m: f64,
    /// Centre in the board frame, metres.
    pub position: Vector3<f64>,
    /// Marker → board rotation; `None` when the bundle gave a position only.
    pub rotation: Option<Matrix3<f64>>,
    /// The ring printed, as bit count and code, where a sheet's manifest
    /// says it: a detector of another family reads other IDs there.
    pub ring: Option<(u32, u32)>,
}

/// A rigid set of markers.
#[derive(Debug, Clone, PartialEq)]
pub struct Board {
    /// Name reported with its pose.
    pub name: String,
    /// Its markers.
    pub markers: Vec<BoardMarker>,
}

/// Why `name` cannot be a board's name, if it cannot: the name becomes the
/// board's frame on /tf, beside the markers' `whycode_<ID>` frames and the
/// arena's `arena` (the node's and the detections bag's defaults), so it
/// must be a frame name of its own: not empty, not one of those, and of
/// letters, digits, `_`, `-` and `.` only (a slash would make it a path
/// in the frame tree, white space or a control character break the tools
/// that print it).
pub fn name_problem(name: &str) -> Option<String> {
    if name.is_empty() {
        return Some("a board's name is its /tf frame and cannot be empty".into());
    }
    if name.len() > 200 {
        return Some(format!(
            "name {:?}... is {} characters; a /tf frame name of at most 200 is wanted",
            name.chars().take(20).collect::<String>(),
            name.len()
        ));
    }
    if let Some(bad) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.')))
    {
        return Some(format!(
            "name {name:?} holds {bad:?}; a board's name is its /tf frame: use letters, digits, _, - and . only"
        ));
    }
    let marker_frame = name
        .strip_prefix("whycode_")
        .is_some_and(|id| !id.is_empty() && id.bytes().all(|b| b.is_ascii_digit()));
    if marker_frame || name == "arena" {
        return Some(format!(
            "name {name:?} is the /tf frame of {}: give the board another name",
            if marker_frame {
                "a marker"
            } else {
                "the arena"
            }
        ));
    }
    None
}

/// `stem` made a board name: characters a /tf frame cannot hold become `_`
/// (a sheet saved as `lab sheet.json` is board `lab_sheet`).
fn frame_safe(stem: &str) -> String {
    let safe: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if safe.is_empty() || name_problem(&safe).is_some() {
        format!("board_{safe}")
    } else {
        safe
    }
}

/// A marker printed unrotated on a page: its +x along the page's x, its +y
/// up the page (the board's −y), its face out of the page (the board's −z).
fn page_marker_rotation() -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))
}

#[derive(Deserialize)]
struct BundleFile {
    #[serde(alias = "tag_bundles")]
    bundles: Vec<BundleEntry>,
}

#[derive(Deserialize)]
struct BundleEntry {
    name: String,
    layout: Vec<BundleMarker>,
}

#[derive(Deserialize)]
struct BundleMarker {
    id: u32,
    #[serde(alias = "size")]
    diameter: f64,
    x: f64,
    y: f64,
    z: f64,
    qw: Option<f64>,
    qx: Option<f64>,
    qy: Option<f64>,
    qz: Option<f64>,
}

impl Board {
    /// Page `page` of a sheet as a board, printed at `print_scale` about
    /// the page centre.
    pub fn from_manifest_page(
        manifest: &Manifest,
        page: u32,
        name: String,
        print_scale: f64,
    ) -> Board {
        let diameters: std::collections::HashMap<u32, f64> = manifest
            .markers
            .iter()
            .map(|m| (m.id, m.diameter_mm * print_scale / 1000.0))
            .collect();
        let codes: std::collections::HashMap<u32, u32> =
            manifest.markers.iter().map(|m| (m.id, m.code)).collect();
        Board {
            name,
            markers: crate::calibrate::board_points(manifest, page, print_scale)
                .into_iter()
                .map(|(id, [x, y])| BoardMarker {
                    id,
                    diameter_m: diameters[&id],
                    position: Vector3::new(x, y, 0.0),
                    rotation: Some(page_marker_rotation()),
                    ring: manifest
                        .family
                        .filter(|_| !manifest.legacy)
                        .map(|f| (f.bits, codes[&id])),
                })
                .collect(),
        }
    }

    /// The boards of a file: every page of a sheet manifest (JSON; named
    /// after the file, with `-pageN` on sheets of several pages) or every
    /// bundle of a bundle file (YAML: `bundles:` or apriltag_ros's
    /// `tag_bundles:`, each with `name` and a `layout` of markers with
    /// `id`, `diameter` (or `size`), `x`, `y`, `z` in metres and
    /// optionally `qw`, `qx`, `qy`, `qz`).
    pub fn load(path: &Path) -> Result<Vec<Board>, LoadError> {
        let text = crate::input::read_text(path, FileKind::Board)?;
        Board::from_text(path, &text)
    }

    /// The boards of a file already read (the page's uploads): `path` names
    /// the boards and the errors as [`Board::load`] does.
    pub fn from_text(path: &Path, text: &str) -> Result<Vec<Board>, LoadError> {
        if text.trim_start().starts_with('{') {
            let manifest = Manifest::from_json(&path.display().to_string(), text)
                .map_err(|e| LoadError::new(path, FileKind::Board, e.problem))?;
            let stem = path
                .file_stem()
                .map(|s| frame_safe(&s.to_string_lossy()))
                .unwrap_or_else(|| "board".into());
            return Ok((1..=manifest.pages)
                .map(|page| {
                    let name = if manifest.pages > 1 {
                        format!("{stem}-page{page}")
                    } else {
                        stem.clone()
                    };
                    Board::from_manifest_page(&manifest, page, name, 1.0)
                })
                .collect());
        }
        Board::parse_bundles(text).map_err(|err| err.in_file(path))
    }

    /// The bundles of a bundle file's text (see [`Board::load`], which
    /// adds the file's name to the error).
    pub fn parse_bundles(text: &str) -> Result<Vec<Board>, LoadError> {
        bundles(text).map_err(|problem| LoadError {
            path: None,
            kind: FileKind::Board,
            problem,
        })
    }
}

/// The checks behind [`Board::parse_bundles`].
fn bundles(text: &str) -> Result<Vec<Board>, LoadProblem> {
    let file: BundleFile = serde_yaml::from_str(text).map_err(|e| {
        LoadProblem::Invalid(format!(
            "neither a sheet manifest nor a marker bundle: {}",
            crate::error::one_line(&e)
        ))
    })?;
    if file.bundles.is_empty() {
        refuse!("lists no bundles");
    }
    file.bundles
        .into_iter()
        .map(|bundle| {
            if let Some(problem) = name_problem(&bundle.name) {
                refuse!("bundle {problem}");
            }
            if bundle.layout.is_empty() {
                refuse!("bundle {} lists no markers", bundle.name);
            }
            let mut ids = std::collections::HashSet::new();
            let markers = bundle
                .layout
                .iter()
                .map(|m| {
                    if !ids.insert(m.id) {
                        refuse!("bundle {}: ID {} listed twice", bundle.name, m.id);
                    }
                    let mm = m.diameter * 1000.0;
                    crate::limits::MARKER_DIAMETER_MM.check(mm).map_err(|e| {
                        LoadProblem::Invalid(format!(
                            "bundle {} ID {}: diameter {e}",
                            bundle.name, m.id
                        ))
                    })?;
                    if ![m.x, m.y, m.z].iter().all(|v| v.is_finite()) {
                        refuse!(
                            "bundle {} ID {}: position is not a number",
                            bundle.name,
                            m.id
                        );
                    }
                    let rotation = match (m.qw, m.qx, m.qy, m.qz) {
                        (None, None, None, None) => None,
                        (Some(w), Some(x), Some(y), Some(z)) => {
                            let q = nalgebra::Quaternion::new(w, x, y, z);
                            if !(q.norm() > 1e-6 && q.norm().is_finite()) {
                                refuse!(
                                    "bundle {} ID {}: orientation is not a rotation",
                                    bundle.name,
                                    m.id
                                );
                            }
                            Some(
                                *UnitQuaternion::from_quaternion(q)
                                    .to_rotation_matrix()
                                    .matrix(),
                            )
                        }
                        _ => {
                            refuse!(
                                "bundle {} ID {}: give all of qw, qx, qy, qz or none",
                                bundle.name,
                                m.id
                            )
                        }
                    };
                    Ok(BoardMarker {
                        id: m.id,
                        diameter_m: m.diameter,
                        position: Vector3::new(m.x, m.y, m.z),
                        rotation,
                        ring: None,
                    })
                })
                .collect::<Result<Vec<_>, LoadProblem>>()?;
            Ok(Board {
                name: bundle.name,
                markers,
            })
        })
        .collect()
}

/// A board's pose in one image.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardPose {
    /// The board's name.
    pub name: String,
    /// Board origin in the camera frame, metres.
    pub position: Vector3<f64>,
    /// Board → camera rotation.
    pub rotation: Matrix3<f64>,
    /// The same rotation as a unit quaternion [x, y, z, w], w ≥ 0.
    pub quaternion: [f64; 4],
    /// IDs of the markers the pose rests on.
    pub used: Vec<u32>,
    /// IDs of the board's markers seen in the image.
    pub seen: Vec<u32>,
    /// IDs seen but left out: they disagree with the rest.
    pub rejected: Vec<u32>,
    /// Reprojection RMS of the used markers' centres, pixels.
    pub rms_px: f64,
}

/// How many pixels of centre residual one radian of a marker's own
/// orientation weighs: little, so that several markers' centres decide
/// the pose and a marker's orientation only fills the directions they
/// leave open (a single marker, a line of markers).
const ORIENTATION_PX_PER_RAD: f64 = 2.0;
/// A marker whose centre is further than this from where the rest put it
/// (pixels, and at least six times the median) disagrees.
const DISAGREE_PX: f64 = 1.0;

/// One marker's sighting: its board entry, and the projected centre
/// (pixels) and pose the detection gave, or those of the pose's twin once
/// the board's own plane showed the detector picked the wrong one.
struct Sighting<'a> {
    marker: &'a BoardMarker,
    centre: (f64, f64),
    pose: Option<Pose>,
}

/// The board's pose from the image's detections, made with `camera` (the
/// markers' centres are then their projected centres). The detections'
/// own poses were computed for a disc of `detector_diameter_m`; each is
/// rescaled to its marker's diameter. `None` when none of the board's
/// markers was seen with a pose.
pub fn locate(
    board: &Board,
    detections: &[Detection],
    camera: &Camera,
    detector_diameter_m: f64,
) -> Option<BoardPose> {
    let read =
        |d: &&Detection| matches!(d.status, Some(MatchStatus::Exact | MatchStatus::Corrected));
    let mut sightings: Vec<Sighting> = Vec::new();
    for marker in &board.markers {
        let mut found = detections.iter().filter(read).filter(|d| d.id == marker.id);
        if let (Some(detection), None) = (found.next(), found.next()) {
            sightings.push(Sighting {
                marker,
                centre: (detection.u, detection.v),
                pose: detection.pose,
            });
        }
    }
    let seen: Vec<u32> = sightings.iter().map(|s| s.marker.id).collect();
    // Every marker's own pose gives a board pose; the fit starts from the
    // one most others agree with.
    let starts: Vec<(Matrix3<f64>, Vector3<f64>)> = sightings
        .iter()
        .filter_map(|s| {
            let pose = s.pose.as_ref()?;
            let to_board = s.marker.rotation?;
            let position = pose.position * (s.marker.diameter_m / detector_diameter_m);
            let rotation = pose.rotation * to_board.transpose();
            Some((rotation, position - rotation * s.marker.position))
        })
        .collect();
    // Markers given by position only (a bundle may): the board's pose that
    // carries their positions onto where their own poses put them.
    let starts = if starts.is_empty() {
        positions_start(&sightings, detector_diameter_m)
            .into_iter()
            .collect()
    } else {
        starts
    };
    let mut active: Vec<bool> = vec![true; sightings.len()];
    let mut best: Option<(f64, DVector<f64>)> = None;
    for (rotation, translation) in &starts {
        let x0 = params(rotation, translation);
        let Some(x) = fit(&sightings, &active, camera, detector_diameter_m, x0) else {
            continue;
        };
        let score = median_residual(&sightings, camera, &x);
        if best.as_ref().is_none_or(|(s, _)| score < *s) {
            best = Some((score, x));
        }
    }
    let (_, mut x) = best?;
    if face_the_board(&mut sightings, camera, detector_diameter_m, &x) {
        x = fit(&sightings, &active, camera, detector_diameter_m, x)?;
    }
    let mut rejected = Vec::new();
    for _ in 0..3 {
        let residuals: Vec<f64> = sightings
            .iter()
            .map(|s| centre_residual(s, camera, &x).map_or(f64::INFINITY, |r| r.norm()))
            .collect();
        let mut sorted: Vec<f64> = residuals.clone();
        sorted.sort_by(f64::total_cmp);
        let limit = (6.0 * sorted[sorted.len() / 2]).max(DISAGREE_PX);
        let mut changed = false;
        for (k, r) in residuals.iter().enumerate() {
            if active[k] && *r > limit && active.iter().filter(|&&a| a).count() > 1 {
                active[k] = false;
                rejected.push(sightings[k].marker.id);
                changed = true;
            }
        }
        if !changed {
            break;
        }
        x = fit(&sightings, &active, camera, detector_diameter_m, x)?;
    }
    let (rotation, position) = from_params(&x);
    let used: Vec<u32> = sightings
        .iter()
        .zip(&active)
        .filter(|(_, &a)| a)
        .map(|(s, _)| s.marker.id)
        .collect();
    let squares: Vec<f64> = sightings
        .iter()
        .zip(&active)
        .filter(|(_, &a)| a)
        .filter_map(|(s, _)| centre_residual(s, camera, &x).map(|r| r.norm_squared()))
        .collect();
    let rms_px = (squares.iter().sum::<f64>() / squares.len().max(1) as f64).sqrt();
    let pose = Pose::new(position, rotation);
    rejected.sort_unstable();
    Some(BoardPose {
        name: board.name.clone(),
        position,
        rotation: pose.rotation,
        quaternion: pose.quaternion,
        used,
        seen,
        rejected,
        rms_px,
    })
}

/// The rigid motion (Kabsch) that best carries the board positions of the
/// sightings with poses onto the camera-frame centres those poses give,
/// rescaled to each marker's diameter; `None` for fewer than three, or
/// three in a line.
fn positions_start(
    sightings: &[Sighting],
    detector_diameter_m: f64,
) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = sightings
        .iter()
        .filter_map(|s| {
            let pose = s.pose.as_ref()?;
            Some((
                s.marker.position,
                pose.position * (s.marker.diameter_m / detector_diameter_m),
            ))
        })
        .collect();
    if pairs.len() < 3 {
        return None;
    }
    let n = pairs.len() as f64;
    let board_mean = pairs.iter().map(|(p, _)| p).sum::<Vector3<f64>>() / n;
    let camera_mean = pairs.iter().map(|(_, q)| q).sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (p, q) in &pairs {
        h += (p - board_mean) * (q - camera_mean).transpose();
    }
    let svd = h.svd(true, true);
    // Three points in a line leave a rotation about it open.
    let mut singular: Vec<f64> = svd.singular_values.iter().copied().collect();
    singular.sort_by(f64::total_cmp);
    if singular[1].is_nan() || singular[1] <= 1e-9 * singular[2].max(1e-12) {
        return None;
    }
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut correction = Matrix3::identity();
    correction[(2, 2)] = (v_t.transpose() * u.transpose()).determinant().signum();
    let rotation = v_t.transpose() * correction * u.transpose();
    Some((rotation, camera_mean - rotation * board_mean))
}

/// Each marker whose own pose faces away from where the board's pose `x`
/// turns it takes the other solution of its two-fold ambiguity, when that
/// one faces nearer: on a small or nearly face-on marker the detector's
/// pick is close to a coin toss, and the wrong one's centre is off by a
/// few tenths of a pixel. True when any marker changed.
fn face_the_board(
    sightings: &mut [Sighting],
    camera: &Camera,
    detector_diameter_m: f64,
    x: &DVector<f64>,
) -> bool {
    let (rotation, _) = from_params(x);
    let mut changed = false;
    for s in sightings.iter_mut() {
        let (Some(pose), Some(to_board)) = (s.pose, s.marker.rotation) else {
            continue;
        };
        let normal = (rotation * to_board).column(2).into_owned();
        let Some((twin, true)) = pose::facing_plane(&pose, detector_diameter_m / 2.0, &normal)
        else {
            continue;
        };
        let (Some(centre), Some(yaw)) = (camera.project(&twin.center), pose.image_yaw(camera))
        else {
            continue;
        };
        s.centre = centre;
        s.pose = Some(pose::full_pose_from_yaw(camera, &twin, yaw));
        changed = true;
    }
    changed
}

fn params(rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> DVector<f64> {
    let r = Rotation3::from_matrix(rotation).scaled_axis();
    DVector::from_vec(vec![
        r.x,
        r.y,
        r.z,
        translation.x,
        translation.y,
        translation.z,
    ])
}

fn from_params(x: &DVector<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    (
        *Rotation3::new(Vector3::new(x[0], x[1], x[2])).matrix(),
        Vector3::new(x[3], x[4], x[5]),
    )
}

fn centre_residual(
    s: &Sighting,
    camera: &Camera,
    x: &DVector<f64>,
) -> Option<nalgebra::Vector2<f64>> {
    let (rotation, translation) = from_params(x);
    let (u, v) = camera.project(&(rotation * s.marker.position + translation))?;
    Some(nalgebra::Vector2::new(s.centre.0 - u, s.centre.1 - v))
}

fn median_residual(sightings: &[Sighting], camera: &Camera, x: &DVector<f64>) -> f64 {
    let mut r: Vec<f64> = sightings
        .iter()
        .map(|s| centre_residual(s, camera, x).map_or(f64::INFINITY, |r| r.norm()))
        .collect();
    r.sort_by(f64::total_cmp);
    r[r.len() / 2]
}

/// Least squares over the active sightings' centres and (weakly) their
/// orientations.
fn fit(
    sightings: &[Sighting],
    active: &[bool],
    camera: &Camera,
    _detector_diameter_m: f64,
    x0: DVector<f64>,
) -> Option<DVector<f64>> {
    let residuals = |x: &DVector<f64>| -> Option<DVector<f64>> {
        let (rotation, _) = from_params(x);
        let mut out = Vec::new();
        for (s, _) in sightings.iter().zip(active).filter(|(_, &a)| a) {
            let r = centre_residual(s, camera, x)?;
            out.extend([r.x, r.y]);
            if let (Some(pose), Some(to_board)) = (&s.pose, s.marker.rotation) {
                let predicted = rotation * to_board;
                let error =
                    Rotation3::from_matrix(&(predicted.transpose() * pose.rotation)).scaled_axis();
                out.extend((error * ORIENTATION_PX_PER_RAD).iter().copied());
            }
        }
        Some(DVector::from_vec(out))
    };
    let jacobian = |x: &DVector<f64>| numeric_jacobian(x, residuals, &[1e-7; 6]);
    levenberg_marquardt(x0, residuals, jacobian, 100).map(|m| m.x)
}
