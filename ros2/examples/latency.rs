//! What the node adds to the detector's own time, in one run: the same
//! 640x480 frames (a board of four markers moving past the camera) through
//! the detector alone, and through whycode_node's loop from an image
//! publisher to a /tf subscriber in this process (each its own DDS
//! participant, on loopback).
//!
//! ```text
//! # in a network namespace holding only loopback (ros2/test.sh runs it so):
//! cargo run --release -p whycode-ros2 --example latency [frames]
//! ```
//!
//! Prints medians: the detector alone; in the node, the detector, the time
//! from the frame's arrival at the node's DDS reader to its /tf published,
//! and the node's own share of that (arrival to /tf minus the detector);
//! and the whole trip from the publisher's call to the /tf sample read.

use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::qos::History;
use ros2_client::{Context, Node, NodeName, NodeOptions, QosProfile};
use std::net::Ipv4Addr;
use std::time::{Duration, Instant};
use whycode::simulate::{self, layout, Scene, SceneObject};
use whycode::{Camera, Detector, Marker};
use whycode_ros2::args::RosArgs;
use whycode_ros2::msg::{CameraInfo, Header, Image, TfMessage, Time};
use whycode_ros2::node::{self, median};
use whycode_ros2::params::{self, Settings};

const DOMAIN: &str = "77";
const IDS: [u32; 4] = [3, 17, 42, 77];

fn main() {
    let frames: usize = std::env::args()
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or(200);
    // Before any thread starts: the node reads these, as it would from a
    // launch file's environment.
    std::env::set_var("ROS_DOMAIN_ID", DOMAIN);
    std::env::set_var("ROS_LOCALHOST_ONLY", "1");

    let camera = Camera::ideal(640, 480, 60.0);
    let images = render(&camera, frames);
    let node_line = [
        "--ros-args",
        "-p",
        "bits:=12",
        "-p",
        "diameter:=0.05",
        "-r",
        "image:=/camera/image_raw",
        "--disable-stdout-logs",
    ];
    let args = RosArgs::parse(node_line).expect("node arguments");

    // The detector alone, configured as the node configures it.
    let settings = Settings::from_parameters(&args.parameters("/whycode", "whycode").unwrap())
        .expect("settings");
    let config = params::detector_config(&settings, Some(camera)).expect("config");
    let mut detector = Detector::new(config.detector);
    let mut alone = Vec::with_capacity(frames);
    for image in &images {
        let started = Instant::now();
        let found = detector.detect(image);
        alone.push(started.elapsed().as_secs_f64() * 1e3);
        assert_eq!(found.len(), IDS.len(), "the detector misses markers");
    }

    // The node, in a thread of this process.
    let (controller, control) = node::control_channel();
    let stopper = controller.clone();
    let running = std::thread::spawn(move || node::run(&args, controller, control));

    let peer = Peer::new();
    // Until discovery has matched both ends and the calibration is in.
    let warm_up = Instant::now() + Duration::from_secs(20);
    let mut stamp = 1;
    while peer
        .round_trip(
            &camera,
            &images[0],
            Time {
                sec: stamp,
                nanosec: 0,
            },
        )
        .0
        .is_none()
    {
        assert!(Instant::now() < warm_up, "the node does not answer");
        stamp += 1;
    }
    let mut trips = Vec::with_capacity(frames);
    let mut answered = 0;
    for (k, image) in images.iter().enumerate() {
        let stamp = Time {
            sec: 1000 + k as i32,
            nanosec: 0,
        };
        let (trip, transforms) = peer.round_trip(&camera, image, stamp);
        if let Some(trip) = trip {
            trips.push(trip);
            answered += 1;
            assert_eq!(transforms, IDS.len(), "frame {k}: not every marker on /tf");
        }
        // A camera's pace, roughly: the node is idle between frames.
        std::thread::sleep(Duration::from_millis(5));
    }
    stopper.stop();
    let stats = running.join().expect("node thread").expect("node ran");
    let own = stats.own_ms();
    println!(
        "whycode_node latency, {frames} frames of 640x480 with {} markers ({answered} answered on /tf):",
        IDS.len()
    );
    println!(
        "  detector alone                     {:.3} ms median",
        median(&alone)
    );
    println!(
        "  in the node: detector              {:.3} ms median",
        median(&stats.detect_ms)
    );
    println!(
        "  in the node: arrival -> /tf sent   {:.3} ms median",
        median(&stats.arrival_to_tf_ms)
    );
    println!(
        "  the node's own share               {:.3} ms median (arrival -> /tf minus the detector; p90 {:.3} ms)",
        median(&own),
        percentile(&own, 0.9)
    );
    println!(
        "  publish call -> /tf read (2 hops)  {:.3} ms median",
        median(&trips)
    );
}

fn percentile(values: &[f64], q: f64) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted
        .get(((sorted.len() as f64 - 1.0) * q).round() as usize)
        .copied()
        .unwrap_or(0.0)
}

/// Frames of a board of markers turning slowly in front of the camera.
fn render(camera: &Camera, frames: usize) -> Vec<image::GrayImage> {
    let family = whycode::Family::generate(12, 2).expect("family");
    let markers: Vec<(Marker, u32)> = IDS
        .iter()
        .map(|&id| {
            let code = family.code(id).expect("an ID of the family");
            (Marker::whycode(12, code, 50.0), id)
        })
        .collect();
    (0..frames)
        .map(|k| {
            let s = k as f64 / frames as f64;
            let board = layout::centred(
                0.8 - 0.2 * s,
                (10.0 + 20.0 * s).to_radians(),
                (-10.0 + 20.0 * s).to_radians(),
                (40.0 * s).to_radians(),
            );
            let mut scene = Scene::new(*camera);
            scene.objects = layout::marker_grid(&markers, &board)
                .into_iter()
                .map(SceneObject::Marker)
                .collect();
            scene.noise = 2.0;
            scene.seed = k as u64 + 1;
            simulate::render(&scene).0
        })
        .collect()
}

/// The other end: a camera publishing frames and a /tf listener, as their
/// own DDS participant.
struct Peer {
    _node: Node,
    images: ros2_client::Publisher<Image>,
    infos: ros2_client::Publisher<CameraInfo>,
    tf: ros2_client::Subscription<TfMessage>,
}

impl Peer {
    fn new() -> Peer {
        let domain = DOMAIN.parse().expect("a domain");
        let participant = DomainParticipantBuilder::new(domain)
            .with_only_networks([Ipv4Addr::LOCALHOST])
            .build()
            .expect("participant");
        let context = Context::from_domain_participant(participant).expect("context");
        let mut ros = context
            .new_node(
                NodeName::new("/", "latency_peer").expect("name"),
                NodeOptions::new().enable_rosout(false),
            )
            .expect("node");
        let sensor = QosProfile::subscription_default();
        let tf_qos = QosProfile::publisher_default().history(History::KeepLast { depth: 100 });
        Peer {
            images: node::create_publisher(&mut ros, "/camera/image_raw", sensor.clone())
                .expect("publisher"),
            infos: node::create_publisher(&mut ros, "/camera/camera_info", sensor)
                .expect("publisher"),
            tf: node::create_subscription(&mut ros, "/tf", tf_qos).expect("subscription"),
            _node: ros,
        }
    }

    /// Publishes a frame (and its camera_info) and waits for its /tf: the
    /// time from the publish call to the /tf sample read, and how many
    /// transforms it held; no time when none came within a second.
    fn round_trip(
        &self,
        camera: &Camera,
        image: &image::GrayImage,
        stamp: Time,
    ) -> (Option<f64>, usize) {
        let header = Header {
            stamp,
            frame_id: "camera_optical".into(),
        };
        let mut info = CameraInfo {
            header: header.clone(),
            width: camera.width,
            height: camera.height,
            distortion_model: "plumb_bob".into(),
            d: camera.distortion.to_vec(),
            k: [
                camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0,
            ],
            ..CameraInfo::default()
        };
        info.p[0] = camera.fx;
        info.p[5] = camera.fy;
        info.p[2] = camera.cx;
        info.p[6] = camera.cy;
        let _ = self.infos.publish(info);
        let message = Image {
            header,
            height: image.height(),
            width: image.width(),
            encoding: "mono8".into(),
            is_bigendian: 0,
            step: image.width(),
            data: image.as_raw().clone(),
        };
        let sent = Instant::now();
        if self.images.publish(message).is_err() {
            return (None, 0);
        }
        let deadline = sent + Duration::from_secs(1);
        while Instant::now() < deadline {
            while let Ok(Some((tf, _))) = self.tf.take() {
                if tf.transforms.first().map(|t| t.header.stamp) == Some(stamp) {
                    return (
                        Some(sent.elapsed().as_secs_f64() * 1e3),
                        tf.transforms.len(),
                    );
                }
            }
            std::thread::sleep(Duration::from_micros(50));
        }
        (None, 0)
    }
}
