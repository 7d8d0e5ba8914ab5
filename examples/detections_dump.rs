//! Every detection of a fixed set of frames, printed with `{:?}`: a change
//! to the detector that should leave its results as they were shows as a
//! diff of this output (`cargo run --release --example detections_dump >
//! before.txt`, change, run again, `diff before.txt after.txt`).
//!
//! The frames are the stored photos (tests/data, and the original project's
//! `many.png` when /work/shared/compat is there) and seeded simulated
//! scenes that take the detector down each of its paths: families of 4 to
//! 16 bits and auto bits, legacy WhyCon, tracked sequences with markers
//! moving, leaving and coming back, pose with and without lens distortion,
//! motion blur, a cast shadow's edge (the shaded second look), low
//! contrast under noise (the global threshold walk), clutter, rings too
//! small to sample, steep views and families of the wrong bit count; and
//! the detection bench's 5000x5000 swarm, which the detector splits
//! between the threads of the pool it runs in (`RAYON_NUM_THREADS=1` and
//! `2` must print the same).
//!
//! `detections_dump [group ...]` prints only the named groups (see
//! `GROUPS`), e.g. a short run under callgrind; with `--timings`, each
//! group's stage timings (summed over its frames) go to stderr.

use std::f64::consts::PI;
use std::path::Path;

use image::GrayImage;
use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::detect::{Detector, DetectorConfig, StageTimings, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::{self, Background, LooseMarker, MotionBlur, Placement, Scene, SceneObject};

const DEG: f64 = PI / 180.0;
const DIAMETER_M: f64 = 0.05;

const GROUPS: [&str; 13] = [
    "photos", "families", "auto", "legacy", "tracking", "blur", "shade", "dim", "clutter", "small",
    "steep", "wrong", "large",
];

thread_local! {
    /// With `--timings`: the stage timings of the group being run.
    static TIMINGS: std::cell::RefCell<Option<StageTimings>> = const { std::cell::RefCell::new(None) };
}

fn main() {
    let (flags, wanted): (Vec<String>, Vec<String>) =
        std::env::args().skip(1).partition(|a| a.starts_with("--"));
    let timings = flags.iter().any(|f| f == "--timings");
    let run = |group: &str| wanted.is_empty() || wanted.iter().any(|w| w == group);
    for group in GROUPS {
        if run(group) {
            if timings {
                TIMINGS.with(|t| *t.borrow_mut() = Some(StageTimings::default()));
            }
            println!("== {group}");
            match group {
                "photos" => photos(),
                "families" => families(),
                "auto" => auto(),
                "legacy" => legacy(),
                "tracking" => tracking(),
                "blur" => blur(),
                "shade" => shade(),
                "dim" => dim(),
                "clutter" => clutter(),
                "small" => small(),
                "steep" => steep(),
                "wrong" => wrong(),
                "large" => large(),
                _ => unreachable!(),
            }
            if let Some(sum) = TIMINGS.with(|t| t.borrow_mut().take()) {
                eprintln!("== {group}\n{sum}");
            }
        }
    }
}

fn family(bits: u32, distance: u32) -> Family {
    Family::generate(bits, distance).expect("family parameters valid")
}

fn config(target: Target) -> DetectorConfig {
    DetectorConfig {
        target,
        ..DetectorConfig::default()
    }
}

fn with_pose(config: DetectorConfig, camera: &Camera) -> DetectorConfig {
    DetectorConfig {
        camera: Some(*camera),
        diameter_m: Some(DIAMETER_M),
        ..config
    }
}

/// Runs a fresh detector over the frames in order and prints what it finds.
fn dump(name: &str, config: DetectorConfig, frames: &[GrayImage]) {
    let timings = TIMINGS.with(|t| t.borrow().is_some());
    let mut detector = Detector::new(DetectorConfig { timings, ..config });
    for (k, frame) in frames.iter().enumerate() {
        let found = detector.detect(frame);
        if let Some(laps) = detector.last_timings() {
            TIMINGS.with(|t| *t.borrow_mut().as_mut().expect("timed group") += &laps);
        }
        println!("{name} frame {k}: {} found", found.len());
        for d in &found {
            println!("  {d:?}");
        }
    }
    println!("{name} check: {:?}", detector.family_check());
}

fn photos() {
    let mut paths: Vec<_> = std::fs::read_dir("tests/data")
        .expect("run from the repository root")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    paths.sort();
    let many = Path::new("/work/shared/compat/many.png");
    if many.exists() {
        paths.push(many.to_path_buf());
    }
    for path in paths {
        let image = whycode::load_gray(&path).expect("stored image loads");
        let name = path.display().to_string();
        let frames = [image];
        dump(&format!("{name} whycon"), config(Target::WhyCon), &frames);
        dump(
            &format!("{name} whycon unreadable"),
            DetectorConfig {
                report_unreadable: true,
                max_markers: 100,
                ..config(Target::WhyCon)
            },
            &frames,
        );
        for (bits, distance) in [(8, 2), (12, 2), (8, 1)] {
            dump(
                &format!("{name} {bits}b d{distance}"),
                config(Target::WhyCode(family(bits, distance))),
                &frames,
            );
        }
        dump(
            &format!("{name} auto d2"),
            config(Target::AnyBits { distance: Some(2) }),
            &frames,
        );
        dump(
            &format!("{name} auto"),
            DetectorConfig {
                report_unreadable: true,
                ..config(Target::AnyBits { distance: None })
            },
            &frames,
        );
    }
}

/// A distortion-free camera with a 60° horizontal field of view.
fn camera(width: u32, height: u32) -> Camera {
    Camera::ideal(width, height, 60.0)
}

/// How markers are spread over a frame.
#[derive(Debug, Clone, Copy)]
struct Spread {
    count: usize,
    diameter_px: (f64, f64),
    max_tilt: f64,
}

fn spread(count: usize, diameter_px: (f64, f64), max_tilt_deg: f64) -> Spread {
    Spread {
        count,
        diameter_px,
        max_tilt: max_tilt_deg * DEG,
    }
}

/// A marker whose centre projects to (u, v), `diameter_px` across seen
/// face-on at that depth.
fn placement_at(
    camera: &Camera,
    (u, v): (f64, f64),
    diameter_px: f64,
    tilt: f64,
    pan: f64,
    roll: f64,
) -> Placement {
    let z = camera.fx * DIAMETER_M / diameter_px;
    let (x, y) = camera.undistort(u, v);
    Placement::viewed(Vector3::new(x * z, y * z, z), tilt, pan, roll)
}

/// Where one marker of a spread sits, so that a sequence can move it.
#[derive(Debug, Clone, Copy)]
struct Spot {
    u: f64,
    v: f64,
    diameter: f64,
    tilt: f64,
    pan: f64,
    roll: f64,
    /// Code bits and code (0 bits: legacy).
    bits: u32,
    code: u32,
    id: u32,
}

impl Spot {
    fn object(&self, camera: &Camera) -> SceneObject {
        let placement = placement_at(
            camera,
            (self.u, self.v),
            self.diameter,
            self.tilt,
            self.pan,
            self.roll,
        );
        let marker = if self.bits == 0 {
            Marker::whycon(DIAMETER_M * 1000.0)
        } else {
            Marker::whycode(self.bits, self.code, DIAMETER_M * 1000.0)
        };
        SceneObject::Marker(LooseMarker::new(marker, self.id, placement))
    }
}

/// Markers on a jittered grid, each a random member of one of `families`
/// (legacy markers for none).
fn spots(camera: &Camera, families: &[&Family], spread: Spread, rng: &mut Pcg32) -> Vec<Spot> {
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    let cols = ((spread.count as f64 * w / h).sqrt().ceil() as usize).max(1);
    let rows = spread.count.div_ceil(cols);
    let (cell_w, cell_h) = (w / cols as f64, h / rows as f64);
    let reach = 0.8 * spread.diameter_px.1 + 2.0;
    (0..spread.count)
        .map(|k| {
            let (col, row) = ((k % cols) as f64, (k / cols) as f64);
            let jitter_u = (cell_w / 2.0 - reach).max(0.0);
            let jitter_v = (cell_h / 2.0 - reach).max(0.0);
            let u = (col + 0.5) * cell_w + rng.range(-jitter_u, jitter_u.max(1e-9));
            let v = (row + 0.5) * cell_h + rng.range(-jitter_v, jitter_v.max(1e-9));
            let diameter = rng.range(
                spread.diameter_px.0,
                spread.diameter_px.1.max(spread.diameter_px.0 + 1e-9),
            );
            let roll = rng.range(0.0, 2.0 * PI);
            let tilt = rng.range(-spread.max_tilt, spread.max_tilt.max(1e-12));
            let pan = rng.range(-spread.max_tilt, spread.max_tilt.max(1e-12));
            let (bits, code, id) = if families.is_empty() {
                (0, 0, 0)
            } else {
                let f = families[k % families.len()];
                let id = 1 + rng.next_u32() % f.len() as u32;
                (f.bits(), f.code(id).expect("member"), id)
            };
            Spot {
                u,
                v,
                diameter,
                tilt,
                pan,
                roll,
                bits,
                code,
                id,
            }
        })
        .collect()
}

fn scene(camera: &Camera, spots: &[Spot], seed: u64) -> Scene {
    let mut s = Scene::new(*camera);
    s.objects = spots.iter().map(|p| p.object(camera)).collect();
    s.seed = seed;
    s.focus_blur_px = 0.6;
    s.noise = 2.0;
    s
}

fn render(scene: &Scene) -> GrayImage {
    simulate::render(scene).0
}

/// `frames` independent frames of markers of `families`.
fn frames_of(
    camera: &Camera,
    families: &[&Family],
    spread: Spread,
    frames: usize,
    seed0: u64,
    look: impl Fn(&mut Scene, usize),
) -> Vec<GrayImage> {
    (0..frames)
        .map(|f| {
            let seed = seed0 + f as u64;
            let mut rng = Pcg32::new(seed, 7);
            let spots = spots(camera, families, spread, &mut rng);
            let mut s = scene(camera, &spots, seed);
            look(&mut s, f);
            render(&s)
        })
        .collect()
}

fn families() {
    let cam = camera(640, 480);
    for (bits, distance) in [(4, 1), (8, 2), (12, 3), (16, 4)] {
        let f = family(bits, distance);
        let frames = frames_of(
            &cam,
            &[&f],
            spread(8, (40.0, 110.0), 45.0),
            4,
            100 + u64::from(bits),
            |_, _| {},
        );
        dump(
            &format!("{bits}b d{distance}"),
            config(Target::WhyCode(f.clone())),
            &frames,
        );
        dump(
            &format!("{bits}b d{distance} pose"),
            with_pose(config(Target::WhyCode(f.clone())), &cam),
            &frames,
        );
    }
    // Pose through a lens with distortion (the outline's points fitted
    // again in the camera's coordinates).
    let mut lens = camera(640, 480);
    lens.distortion = [-0.2, 0.05, 0.001, -0.001, 0.0];
    let f = family(8, 2);
    let frames = frames_of(
        &lens,
        &[&f],
        spread(6, (50.0, 100.0), 40.0),
        3,
        150,
        |_, _| {},
    );
    dump(
        "8b distorted pose",
        with_pose(config(Target::WhyCode(f)), &lens),
        &frames,
    );
}

fn auto() {
    let cam = camera(640, 480);
    let fams: Vec<Family> = [(4, 1), (6, 2), (8, 2), (12, 2), (16, 3)]
        .into_iter()
        .map(|(b, d)| family(b, d))
        .collect();
    let refs: Vec<&Family> = fams.iter().collect();
    let frames = frames_of(
        &cam,
        &refs,
        spread(10, (35.0, 110.0), 35.0),
        4,
        200,
        |_, _| {},
    );
    dump(
        "auto d2",
        config(Target::AnyBits { distance: Some(2) }),
        &frames,
    );
    dump("auto", config(Target::AnyBits { distance: None }), &frames);
    dump(
        "auto pose unreadable",
        DetectorConfig {
            report_unreadable: true,
            ..with_pose(config(Target::AnyBits { distance: None }), &cam)
        },
        &frames,
    );
    dump(
        "8b on mixed",
        config(Target::WhyCode(fams[2].clone())),
        &frames,
    );
}

fn legacy() {
    let cam = camera(640, 480);
    let frames = frames_of(&cam, &[], spread(9, (14.0, 100.0), 45.0), 4, 300, |_, _| {});
    dump("legacy", config(Target::WhyCon), &frames);
    dump(
        "legacy pose",
        with_pose(config(Target::WhyCon), &cam),
        &frames,
    );
    dump(
        "legacy unreadable",
        DetectorConfig {
            report_unreadable: true,
            ..config(Target::WhyCon)
        },
        &frames,
    );
    let f = family(8, 2);
    let whycode = frames_of(
        &cam,
        &[&f],
        spread(6, (40.0, 90.0), 30.0),
        2,
        310,
        |_, _| {},
    );
    dump("legacy on whycode", config(Target::WhyCon), &whycode);
}

/// A sequence: markers drift, one leaves the frame for a few frames and
/// comes back, one appears late; every few frames a motion blur.
fn sequence(cam: &Camera, families: &[&Family], frames: usize, seed: u64) -> Vec<GrayImage> {
    let mut rng = Pcg32::new(seed, 3);
    let mut base = spots(cam, families, spread(6, (40.0, 90.0), 35.0), &mut rng);
    let velocity: Vec<(f64, f64, f64)> = base
        .iter()
        .map(|_| {
            (
                rng.range(-4.0, 4.0),
                rng.range(-3.0, 3.0),
                rng.range(-0.05, 0.05),
            )
        })
        .collect();
    (0..frames)
        .map(|f| {
            let shown: Vec<Spot> = base
                .iter()
                .enumerate()
                // Marker 1 is gone for frames 4-6; marker 5 arrives at frame 3.
                .filter(|(k, _)| {
                    let away = *k == 1 && (4..7).contains(&f);
                    let not_yet = *k == 5 && f < 3;
                    !(away || not_yet)
                })
                .map(|(_, s)| *s)
                .collect();
            let mut s = scene(cam, &shown, seed + f as u64);
            if f % 5 == 4 {
                s.motion_blur = Some(MotionBlur {
                    length_px: 6.0,
                    angle: 0.4,
                });
            }
            for (spot, (du, dv, droll)) in base.iter_mut().zip(&velocity) {
                spot.u += du;
                spot.v += dv;
                spot.roll += droll;
            }
            render(&s)
        })
        .collect()
}

fn tracking() {
    let cam = camera(640, 480);
    let f = family(8, 2);
    let frames = sequence(&cam, &[&f], 12, 400);
    let tracked = |c: DetectorConfig| DetectorConfig {
        tracking: true,
        ..c
    };
    dump(
        "track 8b",
        tracked(config(Target::WhyCode(f.clone()))),
        &frames,
    );
    dump(
        "track 8b pose",
        tracked(with_pose(config(Target::WhyCode(f.clone())), &cam)),
        &frames,
    );
    dump(
        "track auto",
        tracked(config(Target::AnyBits { distance: Some(2) })),
        &frames,
    );
    dump(
        "track 12b on 8b",
        tracked(config(Target::WhyCode(family(12, 2)))),
        &frames,
    );
    let legacy = sequence(&cam, &[], 10, 410);
    dump("track legacy", tracked(config(Target::WhyCon)), &legacy);
    dump(
        "track legacy pose",
        tracked(with_pose(config(Target::WhyCon), &cam)),
        &legacy,
    );
    let f16 = family(16, 4);
    let long = sequence(&cam, &[&f16], 8, 420);
    dump(
        "track 16b pose",
        tracked(with_pose(config(Target::WhyCode(f16)), &cam)),
        &long,
    );
    dump(
        "track limited",
        DetectorConfig {
            max_markers: 3,
            ..tracked(config(Target::WhyCode(f)))
        },
        &frames,
    );
}

fn blur() {
    let cam = camera(640, 480);
    let f = family(8, 2);
    let frames = frames_of(
        &cam,
        &[&f],
        spread(6, (40.0, 90.0), 30.0),
        6,
        500,
        |s, k| {
            s.motion_blur = Some(MotionBlur {
                length_px: 6.0 + 4.0 * k as f64,
                angle: 0.3 * k as f64,
            });
        },
    );
    dump("blur 8b", config(Target::WhyCode(f.clone())), &frames);
    dump(
        "blur 8b pose",
        with_pose(config(Target::WhyCode(f)), &cam),
        &frames,
    );
    dump(
        "blur auto",
        config(Target::AnyBits { distance: Some(2) }),
        &frames,
    );
    let f12 = family(12, 2);
    let frames = frames_of(
        &cam,
        &[&f12],
        spread(5, (60.0, 110.0), 20.0),
        3,
        510,
        |s, k| {
            s.motion_blur = Some(MotionBlur {
                length_px: 10.0 + 5.0 * k as f64,
                angle: 1.0 + k as f64,
            });
        },
    );
    dump("blur 12b", config(Target::WhyCode(f12)), &frames);
}

/// Darkens the image beyond a straight soft-edged line.
fn cast_shadow(image: &mut GrayImage, (u0, v0): (f64, f64), angle: f64, factor: f64, soft: f64) {
    let (s, c) = angle.sin_cos();
    for (x, y, p) in image.enumerate_pixels_mut() {
        let d = -(f64::from(x) - u0) * s + (f64::from(y) - v0) * c;
        let t = (d / soft + 0.5).clamp(0.0, 1.0);
        let light = 1.0 - (1.0 - factor) * t;
        p.0[0] = (f64::from(p.0[0]) * light).round().clamp(0.0, 255.0) as u8;
    }
}

fn shade() {
    let cam = camera(640, 480);
    let f = family(8, 2);
    let mut frames = frames_of(
        &cam,
        &[&f],
        spread(12, (40.0, 80.0), 25.0),
        5,
        600,
        |s, k| {
            s.gradient = 1.0 + k as f64;
            s.gradient_angle = 0.7 * k as f64;
        },
    );
    for (k, frame) in frames.iter_mut().enumerate() {
        let angle = 0.5 + 0.9 * k as f64;
        cast_shadow(frame, (320.0 + 20.0 * k as f64, 240.0), angle, 0.35, 3.0);
    }
    dump("shade 8b", config(Target::WhyCode(f.clone())), &frames);
    dump(
        "shade 8b pose",
        with_pose(config(Target::WhyCode(f.clone())), &cam),
        &frames,
    );
    dump(
        "shade auto",
        config(Target::AnyBits { distance: Some(2) }),
        &frames,
    );
    dump("shade legacy", config(Target::WhyCon), &frames);
    // Sharper, lighter shadows across larger markers.
    let mut frames = frames_of(
        &cam,
        &[&f],
        spread(9, (60.0, 110.0), 20.0),
        8,
        610,
        |_, _| {},
    );
    for (k, frame) in frames.iter_mut().enumerate() {
        let angle = 0.3 + 0.7 * k as f64;
        cast_shadow(
            frame,
            (300.0 + 10.0 * k as f64, 250.0),
            angle,
            0.5 + 0.03 * k as f64,
            1.0 + 0.5 * k as f64,
        );
    }
    dump(
        "shade sharp 8b",
        config(Target::WhyCode(f.clone())),
        &frames,
    );
    dump(
        "shade sharp 8b track",
        DetectorConfig {
            tracking: true,
            ..config(Target::WhyCode(f.clone()))
        },
        &frames,
    );
    // Shadow edges of several softnesses and depths across the rings.
    for soft in [0.5, 1.0, 2.0, 4.0] {
        for factor in [0.3, 0.45, 0.6] {
            let mut frames = frames_of(
                &cam,
                &[&f],
                spread(12, (50.0, 120.0), 20.0),
                3,
                1300,
                |_, _| {},
            );
            for (k, frame) in frames.iter_mut().enumerate() {
                let at = (320.0 + 17.0 * k as f64, 240.0 - 9.0 * k as f64);
                cast_shadow(frame, at, 0.2 + 1.1 * k as f64, factor, soft);
            }
            dump(
                &format!("shade {soft} {factor}"),
                config(Target::WhyCode(f.clone())),
                &frames,
            );
        }
    }
}

fn dim() {
    let cam = camera(640, 480);
    let f = family(8, 2);
    let frames = frames_of(
        &cam,
        &[&f],
        spread(5, (50.0, 100.0), 30.0),
        6,
        700,
        |s, k| {
            s.exposure = 0.15 + 0.05 * k as f64;
            s.ink_reflectance = 0.35;
            s.noise = 6.0 + k as f64;
            s.gradient = 1.0 + 0.5 * k as f64;
        },
    );
    dump("dim 8b", config(Target::WhyCode(f.clone())), &frames);
    dump(
        "dim 8b track",
        DetectorConfig {
            tracking: true,
            ..config(Target::WhyCode(f))
        },
        &frames,
    );
    dump("dim legacy", config(Target::WhyCon), &frames);
}

fn clutter() {
    let cam = camera(640, 480);
    let f = family(8, 2);
    let frames = frames_of(
        &cam,
        &[&f],
        spread(4, (40.0, 80.0), 30.0),
        4,
        800,
        |s, k| {
            s.background = Background::Clutter {
                density: 1.0 + k as f64,
            };
        },
    );
    dump("clutter 8b", config(Target::WhyCode(f.clone())), &frames);
    dump(
        "clutter 8b unreadable",
        DetectorConfig {
            report_unreadable: true,
            ..config(Target::WhyCode(f))
        },
        &frames,
    );
    dump(
        "clutter auto",
        config(Target::AnyBits { distance: None }),
        &frames,
    );
    dump("clutter legacy", config(Target::WhyCon), &frames);
    let empty = frames_of(&cam, &[], spread(0, (40.0, 80.0), 0.0), 3, 810, |s, _| {
        s.background = Background::Clutter { density: 4.0 };
    });
    dump(
        "clutter only auto",
        config(Target::AnyBits { distance: Some(2) }),
        &empty,
    );
    dump("clutter only legacy", config(Target::WhyCon), &empty);
}

fn small() {
    let cam = camera(640, 480);
    for (bits, distance) in [(4, 1), (8, 2), (12, 2)] {
        let f = family(bits, distance);
        let frames = frames_of(
            &cam,
            &[&f],
            spread(30, (9.0, 18.0), 40.0),
            2,
            900 + u64::from(bits),
            |_, _| {},
        );
        dump(
            &format!("small {bits}b"),
            config(Target::WhyCode(f.clone())),
            &frames,
        );
        dump(
            &format!("small {bits}b unreadable"),
            DetectorConfig {
                report_unreadable: true,
                ..config(Target::WhyCode(f))
            },
            &frames,
        );
        dump(
            &format!("small {bits}b auto"),
            config(Target::AnyBits {
                distance: Some(distance),
            }),
            &frames,
        );
    }
    let f = family(8, 2);
    let frames = frames_of(
        &cam,
        &[&f],
        spread(20, (12.0, 24.0), 30.0),
        2,
        950,
        |s, k| {
            s.motion_blur = Some(MotionBlur {
                length_px: 3.0 + 2.0 * k as f64,
                angle: 0.5,
            });
        },
    );
    dump("small 8b blur", config(Target::WhyCode(f.clone())), &frames);
    let blurred = frames;
    // Small markers read with families one and two counts off.
    for (bits, distance, low, high) in [
        (12, 3, 14.0, 22.0),
        (11, 3, 13.0, 20.0),
        (18, 4, 28.0, 36.0),
    ] {
        let marker_family = if bits == 18 { family(16, 4) } else { f.clone() };
        let frames = frames_of(
            &cam,
            &[&marker_family],
            spread(20, (low, high), 35.0),
            2,
            960 + u64::from(bits),
            |_, _| {},
        );
        dump(
            &format!("small read as {bits}b d{distance}"),
            config(Target::WhyCode(family(bits, distance))),
            &frames,
        );
    }
    for bits in [6, 7, 9, 10] {
        dump(
            &format!("small 8b read as {bits}b"),
            config(Target::WhyCode(family(bits, 2))),
            &blurred,
        );
    }
}

fn steep() {
    let cam = camera(640, 480);
    let f = family(8, 2);
    let frames = frames_of(
        &cam,
        &[&f],
        spread(6, (60.0, 120.0), 72.0),
        4,
        1000,
        |_, _| {},
    );
    dump(
        "steep 8b pose",
        with_pose(config(Target::WhyCode(f.clone())), &cam),
        &frames,
    );
    dump("steep 8b", config(Target::WhyCode(f)), &frames);
    let f16 = family(16, 3);
    let frames = frames_of(
        &cam,
        &[&f16],
        spread(4, (80.0, 140.0), 65.0),
        3,
        1010,
        |_, _| {},
    );
    dump("steep 16b", config(Target::WhyCode(f16)), &frames);
    dump(
        "steep 16b auto",
        config(Target::AnyBits { distance: None }),
        &frames,
    );
}

fn wrong() {
    let cam = camera(640, 480);
    let f16 = family(16, 3);
    let f8 = family(8, 2);
    let frames = frames_of(
        &cam,
        &[&f16, &f8],
        spread(8, (30.0, 90.0), 40.0),
        3,
        1100,
        |_, _| {},
    );
    dump("wrong 8b", config(Target::WhyCode(f8)), &frames);
    dump("wrong 12b", config(Target::WhyCode(family(12, 2))), &frames);
    dump("wrong 18b", config(Target::WhyCode(family(18, 3))), &frames);
    dump("wrong 4b", config(Target::WhyCode(family(4, 1))), &frames);
    // A 16-bit ring too fine to test for 18 bits that shows its own count.
    let sixteen = family(16, 2);
    let mut scene = Scene::new(cam);
    let code = sixteen.code(4).expect("member");
    let placement = placement_at(&cam, (80.0, 240.0), 40.0, 34.455 * DEG, 0.0, 1.057);
    scene.objects.push(SceneObject::Marker(LooseMarker::new(
        Marker::whycode(16, code, DIAMETER_M * 1000.0),
        4,
        placement,
    )));
    scene.noise = 2.0;
    scene.seed = 2;
    let frames = [render(&scene)];
    dump(
        "wrong 16b as 18b",
        config(Target::WhyCode(family(18, 2))),
        &frames,
    );
    dump(
        "wrong 16b as 16b",
        config(Target::WhyCode(sixteen)),
        &frames,
    );
}

/// The detection bench's frame (`benches/detect.rs`): 5000x5000, 550
/// markers of 60-120 px, light falling 2:1, mild blur and noise; seen
/// once with pose, and twice tracked.
fn large() {
    use whycode_testkit::scenes::{self, Look};
    let family = family(8, 2);
    let codes = family.codes().to_vec();
    let camera = scenes::camera(5000, 5000, 5000.0);
    let mut rng = Pcg32::new(5000, 0);
    let markers = scenes::scatter(&mut rng, &camera, 550, (60.0, 120.0), &mut |k| {
        let id = k % codes.len();
        (Marker::whycode(8, codes[id], 100.0), id as u32 + 1)
    });
    let look = Look {
        gradient_right: 0.5,
        blur: 1,
        noise: 2.0,
        ..Look::default()
    };
    let frame = scenes::render(&camera, &markers, look).0;
    let config = DetectorConfig {
        camera: Some(camera),
        diameter_m: Some(0.1),
        ..config(Target::WhyCode(family))
    };
    dump("large", config.clone(), std::slice::from_ref(&frame));
    dump(
        "large tracked",
        DetectorConfig {
            tracking: true,
            ..config
        },
        &[frame.clone(), frame],
    );
}
