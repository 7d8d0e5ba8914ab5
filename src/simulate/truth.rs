//! The ground truth of a simulated view: where every marker really is.

use super::square::{true_square, TrueSquare};
use super::{Blot, Placement, Scene, SceneObject, SheetPage};
use crate::camera::Camera;
use crate::geometry::{Marker, MarkerKind};
use crate::math::{Ellipse, Homography};
use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
/// What a synthetic image really shows, to score a detector against.
pub struct GroundTruth {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The camera the image was made with.
    pub camera: CameraTruth,
    /// Every marker in the scene, visible or not.
    pub markers: Vec<TrueMarker>,
    /// Every sheet page in the scene.
    pub pages: Vec<TruePage>,
    /// Every printed square (other fiducials) in the scene; left out of
    /// the JSON when there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub squares: Vec<TrueSquare>,
    /// The image written with this truth and its digest (`fileset`), so
    /// an image and a truth from different runs are told apart; empty for
    /// a truth not written beside an image.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<crate::fileset::FileDigest>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CameraTruth {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    /// k1, k2, p1, p2, k3.
    pub distortion: [f64; 5],
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
/// One marker's true identity, place and pose.
pub struct TrueMarker {
    /// Family ID (0 for none / legacy).
    pub id: u32,
    /// Code printed in the ring (0 for a legacy WhyCon circle).
    pub code: u32,
    /// Bits of the code (0 for a legacy WhyCon circle).
    pub bits: u32,
    /// The sheet page it is printed on, if any.
    pub page: Option<u32>,
    /// Projected true centre, pixels (origin at the top-left pixel centre).
    pub u: f64,
    /// Row of the projected true centre, pixels.
    pub v: f64,
    /// Image direction of the marker's +x axis, atan2(dv, du), radians.
    pub yaw: f64,
    /// Longest projected diameter of the black disc, pixels.
    pub diameter_px: f64,
    /// The projected outline of the black disc (exact for a camera without
    /// distortion; with distortion, the ellipse of the undistorted view moved
    /// to the distorted centre). Its centre is where a detector's ellipse
    /// fit lands, which under perspective is not (u, v).
    pub ellipse: Option<Ellipse>,
    /// Diameter of the black disc as printed, mm.
    pub diameter_mm: f64,
    /// Facing the camera, wholly inside the frame and seen at more than a
    /// grazing angle (its outline at least a pixel wide).
    pub visible: bool,
    /// Some blot covers part of it.
    pub blotted: bool,
    /// Marker centre in the camera frame, metres.
    pub position: [f64; 3],
    /// Rotation marker → camera, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Unit normal of the printed face (marker +z) in the camera frame.
    pub normal: [f64; 3],
    /// The rotation as a quaternion x, y, z, w.
    pub quaternion: [f64; 4],
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
/// Where a sheet page lies in the image, to check page location against.
pub struct TruePage {
    /// Page number, from 1.
    pub page: u32,
    /// Scale the printer applied to the page's content.
    pub print_scale: f64,
    /// Paper corners in pixels: top-left, top-right, bottom-right, bottom-left.
    pub corners: [[f64; 2]; 4],
}

impl GroundTruth {
    /// The truth of `scene` without rendering it (what [`super::render`]
    /// returns beside the image): cheap, for choosing or checking a scene's
    /// markers before drawing it.
    pub fn of(scene: &Scene) -> GroundTruth {
        ground_truth(scene)
    }

    /// The truth as pretty-printed JSON, as `whycode simulate` writes it.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("ground truth serialises");
        s.push('\n');
        s
    }

    /// The visible marker with this ID, if exactly one.
    pub fn marker(&self, id: u32) -> Option<&TrueMarker> {
        let mut it = self.markers.iter().filter(|m| m.id == id);
        let first = it.next()?;
        it.next().is_none().then_some(first)
    }
}

pub(super) fn ground_truth(scene: &Scene) -> GroundTruth {
    let camera = &scene.camera;
    let mut markers = Vec::new();
    let mut pages = Vec::new();
    let mut squares = Vec::new();
    for object in &scene.objects {
        match object {
            SceneObject::Square(sq) => squares.push(true_square(camera, sq)),
            SceneObject::Marker(m) => markers.push(true_marker(
                camera,
                &m.marker,
                m.id,
                None,
                &m.placement,
                (0.0, 0.0),
                1.0,
                blots_touch(&m.blots, 0.0, 0.0, m.marker.outer_radius()),
            )),
            SceneObject::Page(p) => {
                let [w, h] = p.manifest.page_size_mm;
                let s = p.print_scale;
                for entry in p.manifest.markers.iter().filter(|e| e.page == p.page) {
                    let marker = SheetPage::marker_of(&p.manifest, entry);
                    let centre = ((entry.x_mm - w / 2.0) * s, -(entry.y_mm - h / 2.0) * s);
                    let blotted =
                        blots_touch(&p.blots, entry.x_mm, entry.y_mm, marker.outer_radius());
                    markers.push(true_marker(
                        camera,
                        &marker,
                        entry.id,
                        Some(p.page),
                        &p.placement,
                        centre,
                        s,
                        blotted,
                    ));
                }
                let corner = |x: f64, y: f64| {
                    camera
                        .project(&p.placement.to_camera_mm(x, y))
                        .map_or([f64::NAN, f64::NAN], |(u, v)| [u, v])
                };
                pages.push(TruePage {
                    page: p.page,
                    print_scale: s,
                    corners: [
                        corner(-w / 2.0, h / 2.0),
                        corner(w / 2.0, h / 2.0),
                        corner(w / 2.0, -h / 2.0),
                        corner(-w / 2.0, -h / 2.0),
                    ],
                });
            }
        }
    }
    GroundTruth {
        width: camera.width,
        height: camera.height,
        camera: CameraTruth {
            fx: camera.fx,
            fy: camera.fy,
            cx: camera.cx,
            cy: camera.cy,
            distortion: camera.distortion,
        },
        markers,
        pages,
        squares,
        files: Vec::new(),
    }
}

fn blots_touch(blots: &[Blot], x: f64, y: f64, radius: f64) -> bool {
    blots
        .iter()
        .any(|b| (b.x_mm - x).hypot(b.y_mm - y) < b.radius_mm + radius)
}

/// Truth of one marker whose centre is at `centre` (mm) in the frame of
/// `placement`, unrotated in that frame, printed at `scale`.
#[allow(clippy::too_many_arguments)]
fn true_marker(
    camera: &Camera,
    marker: &Marker,
    id: u32,
    page: Option<u32>,
    placement: &Placement,
    centre: (f64, f64),
    scale: f64,
    blotted: bool,
) -> TrueMarker {
    let (code, bits) = match marker.kind {
        MarkerKind::WhyCode { bits, code } => (code, bits),
        MarkerKind::WhyCon => (0, 0),
    };
    let r = marker.outer_radius() * scale;
    let position = placement.to_camera_mm(centre.0, centre.1);
    let (u, v) = camera.project(&position).unwrap_or((f64::NAN, f64::NAN));
    let step = r * 1e-3;
    let yaw = match camera.project(&placement.to_camera_mm(centre.0 + step, centre.1)) {
        Some((ux, vx)) => (vx - v).atan2(ux - u),
        None => f64::NAN,
    };
    const STEPS: usize = 72;
    let rim: Vec<Option<(f64, f64)>> = (0..STEPS)
        .map(|k| {
            let a = k as f64 / STEPS as f64 * std::f64::consts::TAU;
            camera.project(&placement.to_camera_mm(centre.0 + r * a.cos(), centre.1 + r * a.sin()))
        })
        .collect();
    let diameter_px = (0..STEPS / 2)
        .filter_map(|k| match (rim[k], rim[k + STEPS / 2]) {
            (Some(a), Some(b)) => Some((a.0 - b.0).hypot(a.1 - b.1)),
            _ => None,
        })
        .fold(0.0, f64::max);
    let normal = placement.normal();
    // An edge-on marker (tilt 90°) faces the camera only by rounding error:
    // the plane must be seen at more than a grazing angle.
    let facing = -normal.dot(&position) > 1e-9 * position.norm();
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    let inside = rim.iter().all(|p| {
        p.is_some_and(|(pu, pv)| pu >= -0.5 && pv >= -0.5 && pu <= w - 0.5 && pv <= h - 0.5)
    });
    let ellipse = outline_ellipse(camera, placement, centre, r, facing);
    let rot = placement.rotation;
    let quaternion =
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot)).into_inner();
    TrueMarker {
        id,
        code,
        bits,
        page,
        u,
        v,
        yaw,
        diameter_px,
        ellipse,
        diameter_mm: 2.0 * r,
        // Nothing is drawn of a marker whose image is thinner than a pixel.
        visible: facing && inside && ellipse.is_some_and(|e| e.semi_minor >= 0.5),
        blotted,
        position: vec3(position),
        rotation: [
            [rot[(0, 0)], rot[(0, 1)], rot[(0, 2)]],
            [rot[(1, 0)], rot[(1, 1)], rot[(1, 2)]],
            [rot[(2, 0)], rot[(2, 1)], rot[(2, 2)]],
        ],
        normal: vec3(normal),
        quaternion: [quaternion.i, quaternion.j, quaternion.k, quaternion.w],
    }
}

/// The image of the marker's outer circle through the plane's homography
/// K·[r1 r2 t] (mm in the plane → ideal pixels).
fn outline_ellipse(
    camera: &Camera,
    placement: &Placement,
    centre: (f64, f64),
    r: f64,
    facing: bool,
) -> Option<Ellipse> {
    if !facing || placement.position.z <= 0.0 {
        return None;
    }
    let k = nalgebra::Matrix3::new(
        camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0,
    );
    let rot = placement.rotation;
    let mut plane = nalgebra::Matrix3::zeros();
    plane.set_column(0, &(rot.column(0) / 1000.0));
    plane.set_column(1, &(rot.column(1) / 1000.0));
    plane.set_column(2, &placement.position);
    let h = Homography { matrix: k * plane };
    let e = h.circle_image(centre.0, centre.1, r)?;
    let (u, v) =
        camera.distort_normalized((e.u - camera.cx) / camera.fx, (e.v - camera.cy) / camera.fy);
    Some(Ellipse { u, v, ..e })
}

fn vec3(v: Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}
