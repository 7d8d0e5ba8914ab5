//! Arena coordinates: four markers at the corners of a rectangle of known
//! size define a floor frame, and every marker found gets its position on
//! that floor in metres and its heading.
//!
//! The corners, in order: the origin, the corner along +x, the far corner
//! and the corner along +y; z is up (towards a camera above the floor).
//! Without IDs the four outermost markers in the image are the corners,
//! picked as the original WhyCon's autocalibration picks them (the marker
//! of largest −u+v is the origin, of largest u+v the +x corner, of largest
//! u−v the far corner, of largest −u−v the +y corner: with the camera
//! looking down, x runs right and y up the image).
//!
//! Two mappings, chosen by whether a calibrated camera is given:
//! - with a camera ([`Mapping::Floor`]): the floor plane's pose in the
//!   camera frame, fitted to the corners' projected centres through the
//!   lens. A marker's position is where the ray through its projected
//!   centre (the image of the circle's centre, not the ellipse's centre,
//!   which perspective moves) meets the plane at the markers' height;
//!   its heading is its pose's +x projected onto the floor.
//! - without one ([`Mapping::Homography`]): a plane-to-plane map from the
//!   image to the floor. It ignores the lens (a distorting lens bends the
//!   floor's straight lines, which no homography follows), and it maps
//!   the floor plane only, so markers must lie on the floor. It does
//!   remove the perspective bias of ellipse centres: a marker's outline is
//!   mapped back to the floor, where it is a circle whose centre is the
//!   marker's.

use std::path::Path;

use nalgebra::{DVector, Matrix2, Matrix3, Rotation3, Vector2, Vector3};

use crate::camera::Camera;
use crate::detect::Detection;
use crate::error::{FileKind, LoadError, LoadProblem};
use crate::family::MatchStatus;
use crate::limits;
use crate::math::homography::Homography;
use crate::math::least_squares::{levenberg_marquardt, numeric_jacobian};
use crate::math::Ellipse;

/// A floor frame and how the image maps to it.
#[derive(Debug, Clone, PartialEq)]
pub struct Arena {
    /// The corners' IDs: origin, +x corner, far corner, +y corner (0 for
    /// legacy circles, which carry none).
    pub ids: [u32; 4],
    /// The rectangle's sides along x and y, metres.
    pub size_m: [f64; 2],
    /// Height above the floor of the markers located (robots carry theirs
    /// above it), metres; 0 with a homography.
    pub marker_height_m: f64,
    /// How far the worst corner lay from the stated rectangle when the
    /// arena was measured, metres (0 with a homography: four points fix it
    /// exactly, so nothing is left to check).
    pub corner_error_m: f64,
    /// How image points map to the floor.
    pub mapping: Mapping,
}

/// How image points map to the arena's floor.
#[derive(Debug, Clone, PartialEq)]
pub enum Mapping {
    /// A calibrated camera and the floor's pose in its frame.
    Floor {
        /// The camera the arena was measured with (its resolution too).
        camera: Camera,
        /// Floor → camera rotation (columns: the floor's axes in the
        /// camera frame).
        rotation: Matrix3<f64>,
        /// The floor origin in the camera frame, metres.
        translation: Vector3<f64>,
    },
    /// Without a camera: the floor's map into an image of `width` x
    /// `height` pixels (floor metres → pixels). Lens distortion ignored.
    Homography {
        /// Image width it was measured at, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
        /// Floor (metres) → image (pixels).
        floor_to_image: Matrix3<f64>,
    },
}

/// A marker on the arena.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArenaPosition {
    /// Along the arena's x, metres.
    pub x: f64,
    /// Along the arena's y, metres.
    pub y: f64,
    /// Height of the plane it was located in, metres.
    pub z: f64,
    /// The marker's +x from the arena's +x, counter-clockwise about +z,
    /// radians in (−π, π]; `None` for markers without a heading (legacy
    /// circles).
    pub yaw: Option<f64>,
}

/// Which markers are the corners.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Corners {
    /// By ID: origin, +x corner, far corner, +y corner.
    Ids([u32; 4]),
    /// The four outermost markers (see the module's documentation).
    Outermost,
}

/// What measures an arena from a photo ([`crate::spec::ArenaSpec::build`]).
#[derive(Debug, Clone)]
pub struct ArenaOptions {
    /// The detector that finds the corners (with the camera, and a
    /// diameter so that their centres are projected centres).
    pub config: crate::detect::DetectorConfig,
    /// Which markers are the corners.
    pub corners: Corners,
    /// The rectangle's sides along x and y, metres.
    pub size_m: [f64; 2],
    /// Height of the markers to locate above the floor, metres.
    pub marker_height_m: f64,
}

impl ArenaOptions {
    /// Finds the corners in `image` and measures the arena.
    pub fn measure<C: std::ops::Deref<Target = [u8]>>(
        &self,
        image: &image::ImageBuffer<image::Luma<u8>, C>,
    ) -> Result<Arena, ArenaError> {
        let mut detector = crate::detect::Detector::new(self.config.clone());
        detector
            .fit_camera(image.width(), image.height())
            .map_err(|e| ArenaError::OtherCamera(e.to_string()))?;
        let detections = detector.detect(image);
        Arena::measure(
            self.corners,
            self.size_m,
            self.marker_height_m,
            self.config.camera.as_ref(),
            &detections,
            (image.width(), image.height()),
        )
    }
}

/// Why an arena cannot be measured from an image.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArenaError {
    /// One ID named for two corners.
    #[error("ID {0} is given for two corners: each corner needs its own marker")]
    RepeatedId(u32),
    /// A corner's marker is not in the image.
    #[error("corner ID {id} is not among the markers found ({})", list(found))]
    NotSeen {
        /// The corner's ID.
        id: u32,
        /// The IDs that were found.
        found: Vec<u32>,
    },
    /// A corner's ID found on several markers.
    #[error(
        "corner ID {id} was found on {count} markers: a corner's ID must be on one marker only"
    )]
    SeenTwice {
        /// The corner's ID.
        id: u32,
        /// On how many markers.
        count: usize,
    },
    /// Fewer than four markers to take the outermost of.
    #[error("only {0} marker{plural} found: four corner markers are needed", plural = if *.0 == 1 { "" } else { "s" })]
    TooFew(usize),
    /// The outermost picks name one marker for two corners.
    #[error("the four outermost markers are not four different markers (one is outermost two ways): give the corners with --ids")]
    NotFourOutermost,
    /// The corners do not lie on the stated rectangle.
    #[error("the corners are not a {:.3} m x {:.3} m rectangle: corner ID {id} is {:.0} mm off it ({:.0} mm allowed); check the size, the order of the IDs (origin, +x, far corner, +y) and that the camera is the one calibrated", size_m[0], size_m[1], error_m * 1000.0, tolerance_m * 1000.0)]
    NotTheRectangle {
        /// The rectangle asked for, metres.
        size_m: [f64; 2],
        /// The corner furthest off.
        id: u32,
        /// How far off, metres.
        error_m: f64,
        /// What is allowed, metres.
        tolerance_m: f64,
    },
    /// The corners run the wrong way round: z would point into the floor.
    #[error("the corners run clockwise seen from above, so z would point down into the floor: give the +y corner second and the +x corner fourth (and swap the two sizes)")]
    Clockwise,
    /// The camera was calibrated for another aspect ratio.
    #[error("{0}")]
    OtherCamera(String),
    /// Three corners lie on one line in the image: no floor spans them.
    #[error("corner IDs {}, {} and {} lie on one line in the image, so they span no floor: lay the four markers out as the corners of the rectangle, all in view", ids[0], ids[1], ids[2])]
    Collinear {
        /// The three corners in a line.
        ids: [u32; 3],
    },
    /// The corners' image points are degenerate.
    #[error("the corners' centres fit no plane-to-image map (three in a line?)")]
    Degenerate,
}

fn list(ids: &[u32]) -> String {
    if ids.is_empty() {
        return "none".into();
    }
    ids.iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Corner disagreement allowed when measuring with a camera: 1 % of the
/// rectangle's diagonal (25 mm on a 2 m x 1.5 m arena). The centres are
/// read to well under a millimetre and a taped-out rectangle is good to a
/// few millimetres, while the slips this catches are far larger: swapped
/// sides (0.5 m on that arena), a wrong unit, IDs out of order (a side or
/// a diagonal off).
pub const CORNER_TOLERANCE: f64 = 0.01;

/// The corners' floor points, in the corners' order.
fn corner_points([w, h]: [f64; 2]) -> [Vector2<f64>; 4] {
    [
        Vector2::new(0.0, 0.0),
        Vector2::new(w, 0.0),
        Vector2::new(w, h),
        Vector2::new(0.0, h),
    ]
}

/// The corners' detections among `detections`.
fn pick_corners(corners: Corners, detections: &[Detection]) -> Result<[&Detection; 4], ArenaError> {
    let read = |d: &&Detection| {
        d.status.is_none() || matches!(d.status, Some(MatchStatus::Exact | MatchStatus::Corrected))
    };
    match corners {
        Corners::Ids(ids) => {
            for (k, id) in ids.iter().enumerate() {
                if ids[..k].contains(id) {
                    return Err(ArenaError::RepeatedId(*id));
                }
            }
            let mut found: Vec<u32> = detections
                .iter()
                .filter(read)
                .map(|d| d.id)
                .filter(|&id| id != 0)
                .collect();
            found.sort_unstable();
            found.dedup();
            let mut out = Vec::with_capacity(4);
            for id in ids {
                let mut all = detections.iter().filter(read).filter(|d| d.id == id);
                let first = all.next().ok_or_else(|| ArenaError::NotSeen {
                    id,
                    found: found.clone(),
                })?;
                let more = all.count();
                if more > 0 {
                    return Err(ArenaError::SeenTwice {
                        id,
                        count: more + 1,
                    });
                }
                out.push(first);
            }
            Ok([out[0], out[1], out[2], out[3]])
        }
        Corners::Outermost => {
            let candidates: Vec<&Detection> = detections.iter().filter(read).collect();
            if candidates.len() < 4 {
                return Err(ArenaError::TooFew(candidates.len()));
            }
            // Origin, +x, far, +y: the extremes of −u+v, u+v, u−v, −u−v.
            let directions = [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)];
            let picks: Vec<&Detection> = directions
                .iter()
                .map(|&(su, sv)| {
                    *candidates
                        .iter()
                        .max_by(|a, b| (su * a.u + sv * a.v).total_cmp(&(su * b.u + sv * b.v)))
                        .expect("four or more")
                })
                .collect();
            for k in 0..4 {
                if picks[..k].iter().any(|p| std::ptr::eq(*p, picks[k])) {
                    return Err(ArenaError::NotFourOutermost);
                }
            }
            Ok([picks[0], picks[1], picks[2], picks[3]])
        }
    }
}

/// The image of the centre of the floor circle whose image outline is
/// `outline`, through `floor_to_image`: the outline mapped back to the
/// floor is that circle, and its centre maps forward to the point sought.
fn projected_centre(floor_to_image: &Matrix3<f64>, outline: &Ellipse) -> Option<Vector2<f64>> {
    let floor = floor_conic_centre(floor_to_image, outline)?;
    let p = floor_to_image * Vector3::new(floor.x, floor.y, 1.0);
    (p.z.abs() > 1e-12).then(|| Vector2::new(p.x / p.z, p.y / p.z))
}

/// The centre, on the floor, of the image conic `outline` mapped back
/// through `floor_to_image`.
fn floor_conic_centre(floor_to_image: &Matrix3<f64>, outline: &Ellipse) -> Option<Vector2<f64>> {
    conic_centre(&(floor_to_image.transpose() * outline.conic() * floor_to_image))
}

fn outline(d: &Detection) -> Ellipse {
    Ellipse {
        u: d.u,
        v: d.v,
        semi_major: d.axes[0],
        semi_minor: d.axes[1],
        angle: d.angle,
    }
}

fn fit_homography(floor: &[Vector2<f64>; 4], image: &[Vector2<f64>]) -> Option<Matrix3<f64>> {
    let pairs: Vec<_> = floor
        .iter()
        .zip(image)
        .map(|(f, i)| ((f.x, f.y), (i.x, i.y)))
        .collect();
    Homography::fit(&pairs).map(|h| h.matrix)
}

impl Arena {
    /// Measures the arena from one image's detections (`width` x `height`
    /// pixels). With `camera` the detections must have been made with it
    /// (and a diameter), so their centres are projected centres; without,
    /// their centres are the ellipses'.
    pub fn measure(
        corners: Corners,
        size_m: [f64; 2],
        marker_height_m: f64,
        camera: Option<&Camera>,
        detections: &[Detection],
        (width, height): (u32, u32),
    ) -> Result<Arena, ArenaError> {
        let picked = pick_corners(corners, detections)?;
        let ids = picked.map(|d| d.id);
        check_spread(&picked)?;
        let floor = corner_points(size_m);
        match camera {
            Some(camera) => {
                let camera = camera.for_image(width, height).unwrap_or(*camera);
                let rays: Vec<Vector3<f64>> = picked
                    .iter()
                    .map(|d| match &d.pose {
                        Some(pose) => pose.position / pose.position.z,
                        None => camera.ray(d.u, d.v),
                    })
                    .collect();
                let (rotation, translation) =
                    fit_floor(&camera, &floor, &rays).ok_or(ArenaError::Degenerate)?;
                // The camera must see the floor from above.
                let eye = -(rotation.transpose() * translation);
                if eye.z <= 0.0 {
                    return Err(ArenaError::Clockwise);
                }
                let mut worst = (0.0, ids[0]);
                for ((ray, point), id) in rays.iter().zip(&floor).zip(ids) {
                    let hit = intersect(&rotation, &translation, ray, 0.0)
                        .map_or(f64::INFINITY, |p| (p.xy() - point).norm());
                    if hit.is_nan() || hit > worst.0 {
                        worst = (hit, id);
                    }
                }
                let tolerance_m = CORNER_TOLERANCE * size_m[0].hypot(size_m[1]);
                if worst.0.is_nan() || worst.0 > tolerance_m {
                    return Err(ArenaError::NotTheRectangle {
                        size_m,
                        id: worst.1,
                        error_m: worst.0,
                        tolerance_m,
                    });
                }
                Ok(Arena {
                    ids,
                    size_m,
                    marker_height_m,
                    corner_error_m: worst.0,
                    mapping: Mapping::Floor {
                        camera,
                        rotation,
                        translation,
                    },
                })
            }
            None => {
                let mut image: Vec<Vector2<f64>> =
                    picked.iter().map(|d| Vector2::new(d.u, d.v)).collect();
                // Detections with poses have projected centres already;
                // the ellipses' centres are off the circles' images, and
                // each pass maps the outlines through the last map.
                if !picked.iter().any(|d| d.pose.is_some()) {
                    for _ in 0..4 {
                        let h = fit_homography(&floor, &image).ok_or(ArenaError::Degenerate)?;
                        image = picked
                            .iter()
                            .zip(&image)
                            .map(|(d, old)| projected_centre(&h, &outline(d)).unwrap_or(*old))
                            .collect();
                    }
                }
                let floor_to_image =
                    fit_homography(&floor, &image).ok_or(ArenaError::Degenerate)?;
                check_winding(&floor_to_image, size_m)?;
                Ok(Arena {
                    ids,
                    size_m,
                    marker_height_m: 0.0,
                    corner_error_m: 0.0,
                    mapping: Mapping::Homography {
                        width,
                        height,
                        floor_to_image: floor_to_image / floor_to_image.norm(),
                    },
                })
            }
        }
    }

    /// Where `d` lies on the arena, in a frame of `width` x `height`
    /// pixels; `camera` is the detector's camera fitted to that frame
    /// (needed with [`Mapping::Floor`]). `None` where the mapping gives
    /// none (a ray parallel to the floor, another aspect ratio).
    pub fn locate(
        &self,
        d: &Detection,
        camera: Option<&Camera>,
        (width, height): (u32, u32),
    ) -> Option<ArenaPosition> {
        match &self.mapping {
            Mapping::Floor {
                rotation,
                translation,
                ..
            } => {
                let camera = camera?;
                let h = self.marker_height_m;
                // The pose's centre is the projected centre fitted to the
                // marker's edge points, unless the pose stage picked the
                // wrong one of the outline's two normals (seen on markers
                // near the image's edges through a strong lens): then the
                // outline is read on the plane the arena knows instead.
                let floor_normal = rotation.column(2).into_owned();
                let p = match &d.pose {
                    Some(pose) if pose.rotation.column(2).angle(&floor_normal) < MAX_NORMAL_OFF => {
                        intersect(rotation, translation, &pose.position, h)?
                    }
                    _ => centre_on_plane(camera, &outline(d), rotation, translation, h)
                        .or_else(|| intersect(rotation, translation, &camera.ray(d.u, d.v), h))?,
                };
                // The heading from the image direction of the marker's +x
                // at its centre, carried onto the plane: it needs only the
                // plane, not the marker's own normal.
                let yaw = match d.yaw {
                    None => None,
                    Some(image_yaw) => {
                        let step = 0.5;
                        let here = intersect(rotation, translation, &camera.ray(d.u, d.v), h)?;
                        let ahead =
                            camera.ray(d.u + step * image_yaw.cos(), d.v + step * image_yaw.sin());
                        let q = intersect(rotation, translation, &ahead, h)?;
                        Some((q.y - here.y).atan2(q.x - here.x))
                    }
                };
                Some(ArenaPosition {
                    x: p.x,
                    y: p.y,
                    z: h,
                    yaw,
                })
            }
            Mapping::Homography {
                width: w0,
                height: h0,
                floor_to_image,
            } => {
                let scale = f64::from(*w0) / f64::from(width);
                if (f64::from(*h0) / f64::from(height) / scale - 1.0).abs() > 0.01 {
                    return None;
                }
                let to_image = Matrix3::from_diagonal(&Vector3::new(1.0 / scale, 1.0 / scale, 1.0))
                    * floor_to_image;
                let floor = if d.pose.is_some() {
                    apply(&to_image.try_inverse()?, d.u, d.v)?
                } else {
                    floor_conic_centre(&to_image, &outline(d))?
                };
                let yaw = d.yaw.and_then(|image_yaw| {
                    let image = apply(&to_image, floor.x, floor.y)?;
                    let back = to_image.try_inverse()?;
                    let step = 0.5;
                    let ahead = apply(
                        &back,
                        image.x + step * image_yaw.cos(),
                        image.y + step * image_yaw.sin(),
                    )?;
                    let here = apply(&back, image.x, image.y)?;
                    Some((ahead.y - here.y).atan2(ahead.x - here.x))
                });
                Some(ArenaPosition {
                    x: floor.x,
                    y: floor.y,
                    z: 0.0,
                    yaw,
                })
            }
        }
    }

    /// The camera's height above the floor, metres, for an arena measured
    /// with one.
    pub fn camera_height_m(&self) -> Option<f64> {
        match &self.mapping {
            Mapping::Floor {
                rotation,
                translation,
                ..
            } => Some(-(rotation.transpose() * translation).z),
            Mapping::Homography { .. } => None,
        }
    }

    /// Why markers `height_m` above the floor cannot be placed, if they
    /// cannot: at or above the camera, every ray misses their plane.
    pub fn height_problem(&self, height_m: f64) -> Option<String> {
        let camera = self.camera_height_m()?;
        (height_m >= camera).then(|| {
            format!(
                "{height_m} m is at or above the camera, which is {camera:.3} m above the arena's floor: no marker there can be placed"
            )
        })
    }

    /// Why a frame of `width` x `height` pixels cannot be placed on this
    /// arena, if it cannot: one measured without a camera maps frames of
    /// its own aspect ratio only (one measured with a camera is fitted to
    /// the frame as the camera is, and refused with it).
    pub fn frame_problem(&self, width: u32, height: u32) -> Option<String> {
        let Mapping::Homography {
            width: w0,
            height: h0,
            ..
        } = &self.mapping
        else {
            return None;
        };
        let scale = f64::from(*w0) / f64::from(width);
        ((f64::from(*h0) / f64::from(height) / scale - 1.0).abs() > 0.01).then(|| {
            format!(
                "the arena was measured without a camera on {w0}x{h0} frames and cannot map a {width}x{height} frame (another aspect ratio): measure it on a frame of this camera"
            )
        })
    }

    /// The camera an arena measured with one needs at detection.
    pub fn camera(&self) -> Option<&Camera> {
        match &self.mapping {
            Mapping::Floor { camera, .. } => Some(camera),
            Mapping::Homography { .. } => None,
        }
    }
}

/// How far a marker's pose normal may lie from the arena's before its
/// pose is taken for the wrong candidate (markers lie flat on the floor
/// or on robots' tops; the poses' normals agree with the floor's to a
/// fraction of a degree when right, and are off by several when wrong).
const MAX_NORMAL_OFF: f64 = 3.0 * std::f64::consts::PI / 180.0;

/// The centre, in floor coordinates, of the circle whose image outline is
/// `outline`, on the floor-frame plane z = `height`: the outline's points
/// taken through the lens to the ideal image plane, their conic mapped
/// onto the plane (where it is the circle itself).
fn centre_on_plane(
    camera: &Camera,
    outline: &Ellipse,
    rotation: &Matrix3<f64>,
    translation: &Vector3<f64>,
    height: f64,
) -> Option<Vector3<f64>> {
    let points: Vec<(f64, f64)> = outline
        .boundary_points(32)
        .into_iter()
        .map(|(u, v)| camera.undistort(u, v))
        .collect();
    let conic = crate::math::ellipse::fit_conic(&points)?;
    let plane_to_image = Matrix3::from_columns(&[
        rotation.column(0).into_owned(),
        rotation.column(1).into_owned(),
        rotation.column(2) * height + translation,
    ]);
    let centre = conic_centre(&(plane_to_image.transpose() * conic * plane_to_image))?;
    Some(Vector3::new(centre.x, centre.y, height))
}

fn conic_centre(conic: &Matrix3<f64>) -> Option<Vector2<f64>> {
    let quadratic = Matrix2::new(conic[(0, 0)], conic[(0, 1)], conic[(1, 0)], conic[(1, 1)]);
    let linear = Vector2::new(conic[(0, 2)], conic[(1, 2)]);
    let centre = -quadratic.try_inverse()? * linear;
    (centre.x.is_finite() && centre.y.is_finite()).then_some(centre)
}

fn apply(m: &Matrix3<f64>, x: f64, y: f64) -> Option<Vector2<f64>> {
    let p = m * Vector3::new(x, y, 1.0);
    (p.z.abs() > 1e-12 && p.x.is_finite() && p.y.is_finite())
        .then(|| Vector2::new(p.x / p.z, p.y / p.z))
}

/// Where the camera-frame ray `ray` (from the camera centre) meets the
/// floor-frame plane z = `height`, in floor coordinates; `None` behind
/// the camera or parallel to the plane.
fn intersect(
    rotation: &Matrix3<f64>,
    translation: &Vector3<f64>,
    ray: &Vector3<f64>,
    height: f64,
) -> Option<Vector3<f64>> {
    let eye = -(rotation.transpose() * translation);
    let direction = rotation.transpose() * ray;
    if direction.z.abs() < 1e-12 {
        return None;
    }
    let s = (height - eye.z) / direction.z;
    (s > 0.0 && s.is_finite()).then(|| eye + direction * s)
}

/// Three corners in one line map every marker to that line: without a
/// camera the floor's map collapses, and with one the floor's fit can
/// only fail for the wrong reason (a floor seen from below). A triangle
/// of the corners under 0.5 % of the square of their spread is a line:
/// a real rectangle seen that edge-on could not be measured anyway.
fn check_spread(picked: &[&Detection; 4]) -> Result<(), ArenaError> {
    let points: Vec<Vector2<f64>> = picked.iter().map(|d| Vector2::new(d.u, d.v)).collect();
    let mut spread: f64 = 0.0;
    for a in &points {
        for b in &points {
            spread = spread.max((a - b).norm_squared());
        }
    }
    for (i, j, k) in [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)] {
        let (ab, ac) = (points[j] - points[i], points[k] - points[i]);
        let area = (ab.x * ac.y - ab.y * ac.x).abs();
        // NaN (a corner at no finite pixel) counts as a line too.
        if area.is_nan() || area <= 0.005 * spread {
            return Err(ArenaError::Collinear {
                ids: [picked[i].id, picked[j].id, picked[k].id],
            });
        }
    }
    Ok(())
}

/// Without a camera the floor's map must keep the corners' turning
/// direction as seen from above: y up the image when x runs right (the
/// image's v points down, so the floor's orientation flips in the image).
fn check_winding(floor_to_image: &Matrix3<f64>, size_m: [f64; 2]) -> Result<(), ArenaError> {
    let centre = Homography {
        matrix: *floor_to_image,
    };
    let jacobian = centre.jacobian(size_m[0] / 2.0, size_m[1] / 2.0);
    if jacobian.determinant() >= 0.0 {
        return Err(ArenaError::Clockwise);
    }
    Ok(())
}

/// The floor's pose fitting the corners' rays: a first guess from the
/// homography between the floor and the normalised image plane, then
/// least squares over the corners' pixels.
fn fit_floor(
    camera: &Camera,
    floor: &[Vector2<f64>; 4],
    rays: &[Vector3<f64>],
) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    let normalised: Vec<Vector2<f64>> = rays.iter().map(|r| r.xy() / r.z).collect();
    let h = fit_homography(floor, &normalised)?;
    let (c1, c2, c3) = (
        h.column(0).into_owned(),
        h.column(1).into_owned(),
        h.column(2).into_owned(),
    );
    let mut lambda = 2.0 / (c1.norm() + c2.norm());
    if c3.z * lambda < 0.0 {
        lambda = -lambda;
    }
    let r1 = c1 * lambda;
    let r2 = c2 * lambda;
    let guess = Matrix3::from_columns(&[r1, r2, r1.cross(&r2)]);
    let svd = guess.svd(true, true);
    let mut rotation = svd.u? * svd.v_t?;
    if rotation.determinant() < 0.0 {
        rotation = -rotation;
    }
    let translation = c3 * lambda;
    let start = Rotation3::from_matrix(&rotation).scaled_axis();
    let x0 = DVector::from_vec(vec![
        start.x,
        start.y,
        start.z,
        translation.x,
        translation.y,
        translation.z,
    ]);
    let pixels: Vec<(f64, f64)> = normalised
        .iter()
        .map(|p| camera.distort_normalized(p.x, p.y))
        .collect();
    let residuals = |x: &DVector<f64>| -> Option<DVector<f64>> {
        let r = Rotation3::new(Vector3::new(x[0], x[1], x[2]));
        let t = Vector3::new(x[3], x[4], x[5]);
        let mut out = Vec::with_capacity(8);
        for (p, (u, v)) in floor.iter().zip(&pixels) {
            let (pu, pv) = camera.project(&(r * Vector3::new(p.x, p.y, 0.0) + t))?;
            out.extend([pu - u, pv - v]);
        }
        Some(DVector::from_vec(out))
    };
    let jacobian = |x: &DVector<f64>| numeric_jacobian(x, residuals, &[1e-7; 6]);
    let x = levenberg_marquardt(x0, residuals, jacobian, 100)?.x;
    Some((
        *Rotation3::new(Vector3::new(x[0], x[1], x[2])).matrix(),
        Vector3::new(x[3], x[4], x[5]),
    ))
}

/// The arena file: YAML, as `whycode arena` writes it.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ArenaFile {
    format: String,
    version: u32,
    /// Origin, +x corner, far corner, +y corner.
    ids: [u32; 4],
    /// Metres along x and y.
    size: [f64; 2],
    /// Metres above the floor.
    marker_height: f64,
    /// Metres: the worst corner's disagreement with the rectangle.
    corner_error: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    camera: Option<Camera>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    floor: Option<FloorRecord>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    image_to_floor: Option<HomographyRecord>,
}

#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FloorRecord {
    /// Floor → camera, row by row.
    rotation: [[f64; 3]; 3],
    /// The floor origin in the camera frame, metres.
    translation: [f64; 3],
}

#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct HomographyRecord {
    width: u32,
    height: u32,
    /// Floor metres → image pixels, row by row.
    floor_to_image: [[f64; 3]; 3],
}

const FORMAT: &str = "whycode-arena";

fn rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

fn from_rows(rows: &[[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| rows[r][c])
}

impl Arena {
    /// The arena file's text (YAML): what `detect --arena` reads.
    pub fn to_yaml(&self) -> String {
        let (camera, floor, image_to_floor) = match &self.mapping {
            Mapping::Floor {
                camera,
                rotation,
                translation,
            } => (
                Some(*camera),
                Some(FloorRecord {
                    rotation: rows(rotation),
                    translation: [translation.x, translation.y, translation.z],
                }),
                None,
            ),
            Mapping::Homography {
                width,
                height,
                floor_to_image,
            } => (
                None,
                None,
                Some(HomographyRecord {
                    width: *width,
                    height: *height,
                    floor_to_image: rows(floor_to_image),
                }),
            ),
        };
        let file = ArenaFile {
            format: FORMAT.into(),
            version: 1,
            ids: self.ids,
            size: self.size_m,
            marker_height: self.marker_height_m,
            corner_error: self.corner_error_m,
            camera,
            floor,
            image_to_floor,
        };
        let header = match &self.mapping {
            Mapping::Floor { .. } => {
                "# whycode arena: corners origin, +x, far, +y; metres; the floor's pose\n\
                 # in the frame of the calibrated camera below (p_camera = rotation p_floor + translation)\n"
            }
            Mapping::Homography { .. } => {
                "# whycode arena: corners origin, +x, far, +y; metres; made without a camera:\n\
                 # a plane-to-image map of the floor that ignores the lens\n"
            }
        };
        format!(
            "{header}{}",
            serde_yaml::to_string(&file).expect("plain records serialise")
        )
    }

    /// Reads an arena file (see [`Arena::to_yaml`]).
    pub fn load(path: &Path) -> Result<Arena, LoadError> {
        let text = crate::input::read_text(path, FileKind::Arena)?;
        Arena::parse(&text).map_err(|err| err.in_file(path))
    }

    /// An arena file's text, checked: every number in its plausible range,
    /// the rotation a rotation, the map invertible. [`Arena::load`] adds
    /// the file's name to the error.
    pub fn parse(text: &str) -> Result<Arena, LoadError> {
        parse_arena(text).map_err(|problem| LoadError {
            path: None,
            kind: FileKind::Arena,
            problem,
        })
    }
}

/// The checks behind [`Arena::parse`].
fn parse_arena(text: &str) -> Result<Arena, LoadProblem> {
    let file: ArenaFile = serde_yaml::from_str(text)
        .map_err(|e| invalid(format!("not an arena file: {}", crate::error::one_line(&e))))?;
    if file.format != FORMAT || file.version != 1 {
        return Err(invalid(format!(
            "format {} version {} is not {FORMAT} version 1",
            file.format, file.version
        )));
    }
    for side in file.size {
        limits::ARENA_SIDE_M
            .check(side)
            .map_err(|e| invalid(format!("size: {e}")))?;
    }
    limits::MARKER_HEIGHT_M
        .check(file.marker_height)
        .map_err(|e| invalid(format!("marker_height: {e}")))?;
    if !(file.corner_error >= 0.0 && file.corner_error.is_finite()) {
        return Err(invalid("corner_error is not a length"));
    }
    let mapping = match (file.camera, file.floor, file.image_to_floor) {
        (Some(camera), Some(floor), None) => {
            check_camera(&camera)?;
            let rotation = from_rows(&floor.rotation);
            let orthonormal = (rotation.transpose() * rotation - Matrix3::identity()).norm();
            if !(orthonormal < 1e-6 && rotation.determinant() > 0.0) {
                return Err(invalid("floor rotation is not a rotation"));
            }
            let translation = Vector3::from(floor.translation);
            if !translation.iter().all(|v| v.is_finite())
                || !limits::CAMERA_DISTANCE_M.contains(translation.norm())
            {
                return Err(invalid(format!(
                    "floor translation is not a plausible distance ({} to {} m)",
                    limits::CAMERA_DISTANCE_M.min,
                    limits::CAMERA_DISTANCE_M.max
                )));
            }
            Mapping::Floor {
                camera,
                rotation,
                translation,
            }
        }
        (None, None, Some(map)) => {
            for side in [map.width, map.height] {
                limits::IMAGE_SIDE_PX
                    .check(f64::from(side))
                    .map_err(|e| invalid(format!("image_to_floor size: {e}")))?;
            }
            let floor_to_image = from_rows(&map.floor_to_image);
            if !floor_to_image.iter().all(|v| v.is_finite())
                || floor_to_image.try_inverse().is_none()
            {
                return Err(invalid("image_to_floor is not an invertible map"));
            }
            if file.marker_height != 0.0 {
                return Err(invalid(
                    "marker_height: an arena made without a camera maps the floor only",
                ));
            }
            Mapping::Homography {
                width: map.width,
                height: map.height,
                floor_to_image,
            }
        }
        _ => {
            return Err(invalid(
                "give either camera and floor (made with a camera) or image_to_floor",
            ))
        }
    };
    let arena = Arena {
        ids: file.ids,
        size_m: file.size,
        marker_height_m: file.marker_height,
        corner_error_m: file.corner_error,
        mapping,
    };
    if let Some(problem) = arena.height_problem(arena.marker_height_m) {
        return Err(invalid(format!("marker_height: {problem}")));
    }
    Ok(arena)
}

/// What is wrong with an arena file, in words.
fn invalid(problem: impl Into<String>) -> LoadProblem {
    LoadProblem::Invalid(problem.into())
}

fn check_camera(camera: &Camera) -> Result<(), LoadProblem> {
    for side in [camera.width, camera.height] {
        limits::IMAGE_SIDE_PX
            .check(f64::from(side))
            .map_err(|e| invalid(format!("camera size: {e}")))?;
    }
    let finite = [camera.fx, camera.fy, camera.cx, camera.cy]
        .iter()
        .chain(&camera.distortion)
        .all(|v| v.is_finite());
    if !(finite && camera.fx > 0.0 && camera.fy > 0.0) {
        return Err(invalid("camera: focal lengths must be positive numbers"));
    }
    // The checks a --camera file gets: an arena's camera is used the same way.
    camera
        .check_plausible()
        .map_err(|e| invalid(format!("camera: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn homography_arena() -> Arena {
        Arena {
            ids: [1, 2, 3, 4],
            size_m: [2.0, 1.5],
            marker_height_m: 0.0,
            corner_error_m: 0.0,
            mapping: Mapping::Homography {
                width: 640,
                height: 480,
                floor_to_image: Matrix3::new(300.0, 0.0, 20.0, 0.0, -300.0, 460.0, 0.0, 0.0, 1.0),
            },
        }
    }

    #[test]
    fn the_file_reads_back_what_was_written() {
        let arena = homography_arena();
        assert_eq!(Arena::parse(&arena.to_yaml()).unwrap(), arena);
    }

    #[test]
    fn nonsense_files_are_refused_in_one_line() {
        let text = homography_arena().to_yaml();
        let bad_size = text.replace("- 2.0\n", "- 2000.0\n");
        let message = |text: &str| Arena::parse(text).unwrap_err().to_string();
        let err = message(&bad_size);
        assert!(err.starts_with("size: 2000 m is outside"), "{err}");
        let singular = text.replace("- 300.0", "- 0.0");
        assert!(message(&singular).contains("invertible"));
        let other = text.replace("whycode-arena", "whycode-sheet");
        assert!(message(&other).contains("version"));
        assert!(message("ids: [1]").starts_with("not an arena file"));
    }
}
