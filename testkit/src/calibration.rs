//! Calibration views: an A4 sheet of markers, and a chessboard of the same
//! printed footprint, seen by a 1280×960 camera with a strongly distorting
//! lens (k1 = −0.26) from 0.35–0.6 m, as the calibration round trip and
//! `examples/calibration_bar` measure them.

use image::GrayImage;
use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::family::Family;
use whycode::manifest::{FamilyRef, Manifest, PrintedMarker};
use whycode::math::Pcg32;
use whycode::simulate::{
    self, Background, Placement, PrintedSquare, Scene, SceneObject, SheetPage,
};

/// A4 portrait, millimetres.
pub const PAGE_MM: [f64; 2] = [210.0, 297.0];
/// Marker grid: columns, rows, pitch and diameter (mm).
pub const MARKER_COLUMNS: u32 = 5;
/// Rows of the marker grid.
pub const MARKER_ROWS: u32 = 7;
/// Distance between neighbouring markers' centres, mm.
pub const MARKER_PITCH_MM: f64 = 40.0;
/// Outer diameter of each marker's black disc, mm.
pub const MARKER_DIAMETER_MM: f64 = 30.0;
/// The chessboard: squares across and down (7 × 11 of 25 mm: 175 × 275 mm,
/// the marker grid's footprint), so 6 × 10 inner corners.
pub const CHESS_SQUARES: (u32, u32) = (7, 11);
/// Side of one chessboard square, mm.
pub const CHESS_SQUARE_MM: f64 = 25.0;

/// The true camera: 1280×960, 65° across, barrel distortion k1 = −0.26.
pub fn lens() -> Camera {
    Camera {
        fx: 1000.0,
        fy: 1001.5,
        cx: 643.2,
        cy: 476.9,
        distortion: [-0.26, 0.085, 0.0007, -0.0004, -0.012],
        width: 1280,
        height: 960,
    }
}

/// The sheet: 35 markers of 30 mm (IDs 1-35 of the 10-bit, distance-2
/// family) in 5 columns and 7 rows, 40 mm apart, centred on the page.
pub fn a4_sheet() -> Manifest {
    let family = Family::generate(10, 2).expect("10 bits, distance 2");
    let [w, h] = PAGE_MM;
    let x0 = w / 2.0 - MARKER_PITCH_MM * f64::from(MARKER_COLUMNS - 1) / 2.0;
    let y0 = h / 2.0 - MARKER_PITCH_MM * f64::from(MARKER_ROWS - 1) / 2.0;
    let markers = (0..MARKER_COLUMNS * MARKER_ROWS)
        .map(|k| PrintedMarker {
            id: k + 1,
            code: family.code(k + 1).expect("35 IDs"),
            page: 1,
            x_mm: x0 + MARKER_PITCH_MM * f64::from(k % MARKER_COLUMNS),
            y_mm: y0 + MARKER_PITCH_MM * f64::from(k / MARKER_COLUMNS),
            diameter_mm: MARKER_DIAMETER_MM,
        })
        .collect();
    Manifest {
        format: "whycode-sheet".into(),
        version: 1,
        tool: "whycode-testkit".into(),
        family: Some(FamilyRef {
            bits: 10,
            distance: 2,
        }),
        legacy: false,
        template: "a4".into(),
        page_size_mm: PAGE_MM,
        pages: 1,
        files: Vec::new(),
        markers,
    }
}

/// A page's point (mm from the top-left corner, y down) in the simulator's
/// page frame (mm from the centre, y up).
fn page_frame((x, y): (f64, f64)) -> (f64, f64) {
    (x - PAGE_MM[0] / 2.0, PAGE_MM[1] / 2.0 - y)
}

/// Where `camera` sees the centre of `marker` (printed on the sheet, mm
/// from the page's top-left corner) when the page's centre is at
/// `placement`: the truth a detected centre is held against.
pub fn projected_centre(
    camera: &Camera,
    placement: &Placement,
    marker: &PrintedMarker,
) -> Option<(f64, f64)> {
    let (x, y) = page_frame((marker.x_mm, marker.y_mm));
    camera.project(&placement.to_camera_mm(x, y))
}

/// `count` poses of the page's centre, seeded: 0.35-0.6 m away, tilted up
/// to 45° about varied axes, placed so the whole page (and so the whole
/// chessboard) is inside the image, spread over the image so that its
/// corners are covered. The first views face the camera least.
pub fn views(camera: &Camera, count: usize, seed: u64) -> Vec<Placement> {
    let mut rng = Pcg32::new(seed, 20);
    let mut out = Vec::with_capacity(count);
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    let mut attempts = 0;
    while out.len() < count && attempts < 100_000 {
        attempts += 1;
        let k = out.len();
        let distance = rng.range(0.35, 0.6);
        // Aim at a corner, an edge or the middle in turn.
        let aims = [
            (0.12, 0.12),
            (0.88, 0.88),
            (0.88, 0.12),
            (0.12, 0.88),
            (0.5, 0.5),
            (0.5, 0.25),
            (0.25, 0.5),
            (0.75, 0.5),
            (0.5, 0.75),
        ];
        let (au, av) = aims[k % aims.len()];
        let (u, v) = (
            w * (au + rng.range(-0.12, 0.12)),
            h * (av + rng.range(-0.12, 0.12)),
        );
        let (x, y) = camera.undistort(u, v);
        let tilt = rng.range(-40.0f64, 40.0).to_radians();
        let pan = rng.range(-40.0f64, 40.0).to_radians();
        let roll = rng.range(-30.0f64, 30.0).to_radians()
            + if k % 2 == 1 {
                std::f64::consts::FRAC_PI_2
            } else {
                0.0
            };
        let placement = Placement::viewed(
            Vector3::new(x * distance, y * distance, distance),
            tilt,
            pan,
            roll,
        );
        let tilt_total = placement.normal().angle(&-Vector3::z());
        if !(0.25..=0.8).contains(&tilt_total) {
            continue;
        }
        let inside = [
            (0.0, 0.0),
            (PAGE_MM[0], 0.0),
            (0.0, PAGE_MM[1]),
            PAGE_MM.into(),
        ]
        .into_iter()
        .all(|corner| {
            let (px, py) = page_frame(corner);
            camera
                .project(&placement.to_camera_mm(px, py))
                .is_some_and(|(u, v)| u > 8.0 && v > 8.0 && u < w - 9.0 && v < h - 9.0)
        });
        if inside {
            out.push(placement);
        }
    }
    out
}

/// The look shared by both targets' scenes: a mid-grey table, light
/// falling off 1.5:1, a slightly soft lens, sensor noise.
pub fn scene(camera: &Camera, object: SceneObject, seed: u64) -> Scene {
    let mut scene = Scene::new(*camera);
    scene.objects.push(object);
    scene.background = Background::Uniform(0.3);
    scene.gradient = 1.5;
    scene.gradient_angle = 0.7;
    scene.focus_blur_px = 0.6;
    scene.noise = 1.5;
    scene.seed = seed;
    // These views measure centres to thousandths of a pixel. With 4×4
    // samples a pixel the rendered edges alone moved noise-free marker
    // centres by 0.0069 px rms, more than the detector's own error (8×8:
    // 0.0043, 16×16: 0.0036; docs/calibration.md); a camera integrates
    // its pixels exactly.
    scene.supersampling = 8;
    scene
}

/// The sheet seen from `placement` (the page centre's pose).
pub fn sheet_view(
    camera: &Camera,
    manifest: &Manifest,
    placement: Placement,
    seed: u64,
) -> GrayImage {
    let page = SheetPage::new(manifest.clone(), 1, placement);
    simulate::render(&scene(camera, SceneObject::Page(page), seed)).0
}

/// The chessboard printed where the sheet's markers were, seen from the
/// same pose.
pub fn chessboard_view(camera: &Camera, placement: Placement, seed: u64) -> GrayImage {
    // One bitmap pixel per square, 13 × 13 of them so the board sits
    // centred with white around it.
    let (cols, rows) = CHESS_SQUARES;
    let side = 13;
    let (c0, r0) = ((side - cols) / 2, (side - rows) / 2);
    let bitmap = GrayImage::from_fn(side, side, |x, y| {
        let inside = (c0..c0 + cols).contains(&x) && (r0..r0 + rows).contains(&y);
        let black = inside && (x - c0 + y - r0) % 2 == 0;
        image::Luma([if black { 0 } else { 255 }])
    });
    let square = PrintedSquare::new(bitmap, f64::from(side) * CHESS_SQUARE_MM, 0, placement);
    simulate::render(&scene(camera, SceneObject::Square(square), seed)).0
}

/// The chessboard's inner corners in the page's board frame (mm from the
/// top-left corner, y down), row by row from the top-left.
pub fn chessboard_corners_mm() -> Vec<[f64; 2]> {
    let (cols, rows) = CHESS_SQUARES;
    let x0 = PAGE_MM[0] / 2.0 - CHESS_SQUARE_MM * f64::from(cols) / 2.0;
    let y0 = PAGE_MM[1] / 2.0 - CHESS_SQUARE_MM * f64::from(rows) / 2.0;
    (1..rows)
        .flat_map(|j| {
            (1..cols).map(move |i| {
                [
                    x0 + CHESS_SQUARE_MM * f64::from(i),
                    y0 + CHESS_SQUARE_MM * f64::from(j),
                ]
            })
        })
        .collect()
}
