//! Arena coordinates against the naive way, on the same simulated views in
//! one run: a 2 m × 1.5 m arena seen from 2.5 m by a 1920×1080 camera
//! with k1 = −0.26 (`whycode_testkit::arena`), 12 robots' markers per view.
//!
//! Rows, all on the same images:
//! - ours with the camera: the floor's pose fitted to the corners through
//!   the lens, each marker's projected centre's ray met with the floor,
//!   heading from its pose (`whycode arena --camera`, `detect --arena`);
//! - ours without a camera: a floor-to-image homography of the corners,
//!   each marker's outline mapped back to the floor (no perspective bias,
//!   lens ignored);
//! - naive: today's ellipse centres mapped through a homography of the
//!   four corners' ellipse centres (what a user would do by hand);
//! - ours with the camera, markers 12 cm above the floor (on robots).
//!
//! Printed: position error median and worst (mm), heading error median
//! and worst (degrees), over every robot of every view.
//!
//! ```text
//! cargo run --release --example arena_bar [-- VIEWS [SEED]]
//! ```

use whycode::arena::{Arena, Corners};
use whycode::detect::{Detection, Detector, DetectorConfig, Target};
use whycode::math::Homography;
use whycode_testkit::arena::{self, Robot};

/// Position (m) and heading (radians, if any) of one robot by one method.
type Located = Option<(f64, f64, Option<f64>)>;

#[derive(Default)]
struct Row {
    position_mm: Vec<f64>,
    yaw_deg: Vec<f64>,
    missed: usize,
}

impl Row {
    fn add(&mut self, robot: &Robot, at: Located) {
        let Some((x, y, yaw)) = at else {
            self.missed += 1;
            return;
        };
        self.position_mm
            .push(1000.0 * (x - robot.position.x).hypot(y - robot.position.y));
        if let Some(yaw) = yaw {
            let turn = (yaw - robot.yaw + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            self.yaw_deg.push(turn.abs().to_degrees());
        }
    }

    fn print(&self, name: &str) {
        let stats = |v: &[f64]| {
            let mut s = v.to_vec();
            s.sort_by(f64::total_cmp);
            if s.is_empty() {
                return "       -        -".to_string();
            }
            format!("{:>8.3} {:>8.3}", s[s.len() / 2], s[s.len() - 1])
        };
        println!(
            "{name:<34} {:>5} {:>6} {}  {}",
            self.position_mm.len(),
            self.missed,
            stats(&self.position_mm),
            stats(&self.yaw_deg)
        );
    }
}

fn detect(camera: Option<whycode::camera::Camera>, image: &image::GrayImage) -> Vec<Detection> {
    Detector::new(DetectorConfig {
        target: Target::WhyCode(arena::family()),
        camera,
        diameter_m: camera.map(|_| arena::ROBOT_DIAMETER_MM / 1000.0),
        ..DetectorConfig::default()
    })
    .detect(image)
}

/// Ours: the arena measured from this image's corners, then every robot
/// located through it.
fn ours(
    found: &[Detection],
    camera: Option<&whycode::camera::Camera>,
    height: f64,
    robots: &[Robot],
    size: (u32, u32),
    row: &mut Row,
) {
    let arena = match Arena::measure(
        Corners::Ids(arena::CORNER_IDS),
        arena::SIZE_M,
        height,
        camera,
        found,
        size,
    ) {
        Ok(arena) => arena,
        Err(err) => {
            eprintln!("arena not measured: {err}");
            row.missed += robots.len();
            return;
        }
    };
    for r in robots {
        let at = found
            .iter()
            .find(|d| d.id == r.id)
            .and_then(|d| arena.locate(d, camera, size))
            .map(|a| (a.x, a.y, a.yaw));
        row.add(r, at);
    }
}

/// The naive way: ellipse centres through the corners' ellipse centres'
/// homography.
fn naive(found: &[Detection], robots: &[Robot], row: &mut Row) {
    let [w, h] = arena::SIZE_M;
    let floor = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)];
    let pairs: Option<Vec<_>> = arena::CORNER_IDS
        .iter()
        .zip(floor)
        .map(|(id, f)| found.iter().find(|d| d.id == *id).map(|d| (f, (d.u, d.v))))
        .collect();
    let Some(back) = pairs
        .and_then(|p| Homography::fit(&p))
        .and_then(|h| h.inverse())
    else {
        row.missed += robots.len();
        return;
    };
    for r in robots {
        let at = found.iter().find(|d| d.id == r.id).and_then(|d| {
            let (x, y) = back.apply(d.u, d.v)?;
            let yaw = d.yaw.and_then(|t| {
                let (ax, ay) = back.apply(d.u + 0.5 * t.cos(), d.v + 0.5 * t.sin())?;
                Some((ay - y).atan2(ax - x))
            });
            Some((x, y, yaw))
        });
        row.add(r, at);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let views: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(5);
    let seed: u64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(1);
    let lens = arena::lens();
    let mut with_camera = Row::default();
    let mut without_camera = Row::default();
    let mut by_hand = Row::default();
    let mut raised = Row::default();
    for view in seed..seed + views {
        let robots = arena::robots(12, 0.0, view);
        let image = arena::view(&lens, &robots, view);
        let size = (image.width(), image.height());
        let posed = detect(Some(lens), &image);
        ours(&posed, Some(&lens), 0.0, &robots, size, &mut with_camera);
        let plain = detect(None, &image);
        ours(&plain, None, 0.0, &robots, size, &mut without_camera);
        naive(&plain, &robots, &mut by_hand);

        let up = arena::robots(12, 0.12, view + 1000);
        let image = arena::view(&lens, &up, view + 1000);
        let posed = detect(Some(lens), &image);
        ours(&posed, Some(&lens), 0.12, &up, size, &mut raised);
    }
    println!(
        "arena {} m x {} m from 2.5 m, 1920x1080, k1 {}; {views} views of 12 robots (seeds {seed}..{})",
        arena::SIZE_M[0],
        arena::SIZE_M[1],
        lens.distortion[0],
        seed + views - 1
    );
    println!(
        "{:<34} {:>5} {:>6} {:>8} {:>8}  {:>8} {:>8}",
        "", "found", "missed", "pos_med", "pos_max", "yaw_med", "yaw_max"
    );
    println!(
        "{:<34} {:>5} {:>6} {:>8} {:>8}  {:>8} {:>8}",
        "", "", "", "mm", "mm", "deg", "deg"
    );
    with_camera.print("ours, camera (lens removed)");
    without_camera.print("ours, no camera (plane map)");
    by_hand.print("naive: ellipse centres, homography");
    raised.print("ours, camera, markers 12 cm up");
    println!("target (camera): position median < 0.5 mm, worst < 2 mm; yaw median < 0.2 deg");
}
