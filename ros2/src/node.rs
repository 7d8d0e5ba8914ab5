//! The node: DDS participant, parameters, subscriptions and publishers,
//! and the loop from a camera frame to its /tf and `~/markers`.
//!
//! One thread runs the loop below; ros2-client's spinner runs the
//! parameter services on another, and hands accepted changes to the loop
//! through the same channel as the stop request. Images are read best
//! effort with a history of one: when the detector is slower than the
//! camera, the newest frame waits and older ones are dropped, never queued.

use crate::args::{LogLevel, RosArgs};
use crate::image::{Converter, GrayView};
use crate::log::Logger;
use crate::msg::{
    CameraInfo, CompatMarker, CompatMarkerArray, CompressedImage, Header, Image, MarkerArray,
    RosType, TfMessage, TransformStamped, Vector3,
};
use crate::params::{self, Change, Settings, Transport};
use futures::channel::mpsc::{unbounded, UnboundedReceiver, UnboundedSender};
use futures::stream::{FusedStream, StreamExt};
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::qos::History;
use ros2_client::{
    Context, MessageInfo, Name, Node, NodeName, NodeOptions, ParameterValue, Publisher, QosProfile,
    Subscription,
};
use serde::de::DeserializeOwned;
use std::net::Ipv4Addr;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use whycode::detect::Detection;
use whycode::session::{
    Frame as SessionFrame, FrameError as SessionError, FrameReport, Session, SessionConfig,
};
use whycode::Camera;

/// What the loop is told from outside: a parameter change the parameter
/// services accepted, or to stop.
pub enum Control {
    /// New settings.
    Settings(Box<Update>),
    /// Finish the frame in hand and return.
    Stop,
}

/// An accepted parameter change.
pub struct Update {
    /// All the settings, with the change.
    pub settings: Settings,
    /// The detector configuration built for them, when the change concerns
    /// the detector.
    pub config: Option<SessionConfig>,
    /// What the change touches.
    pub change: Change,
}

/// Sends [`Control`]s to a running node.
#[derive(Clone)]
pub struct Controller(UnboundedSender<Control>);

impl Controller {
    /// Asks the node to stop.
    pub fn stop(&self) {
        // A node that already stopped has nothing to be told.
        let _ = self.0.unbounded_send(Control::Stop);
    }
}

/// A controller and the receiving end [`run`] takes.
pub fn control_channel() -> (Controller, UnboundedReceiver<Control>) {
    let (tx, rx) = unbounded();
    (Controller(tx), rx)
}

/// Per-frame timings, milliseconds.
#[derive(Debug, Clone, Default)]
pub struct Stats {
    /// Frames answered.
    pub frames: usize,
    /// Frames skipped as unreadable.
    pub skipped: usize,
    /// Frames the history of one dropped for a newer one before they were
    /// read (seen as gaps in the sequence numbers of one writer).
    pub dropped: usize,
    /// The detector's time on each frame.
    pub detect_ms: Vec<f64>,
    /// From taking the frame off the reader to /tf published.
    pub take_to_tf_ms: Vec<f64>,
    /// From the frame's arrival at the DDS reader (its last fragment) to
    /// /tf published.
    pub arrival_to_tf_ms: Vec<f64>,
}

/// The median of some values (0 for none).
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    if sorted.len().is_multiple_of(2) {
        0.5 * (sorted[mid - 1] + sorted[mid])
    } else {
        sorted[mid]
    }
}

impl Stats {
    /// The node's own time on each frame: from its arrival to /tf
    /// published, less the detector's time.
    pub fn own_ms(&self) -> Vec<f64> {
        self.arrival_to_tf_ms
            .iter()
            .zip(&self.detect_ms)
            .map(|(total, detect)| total - detect)
            .collect()
    }

    /// One line for the log at exit.
    pub fn summary(&self) -> String {
        let own = self.own_ms();
        format!(
            "{} frames answered, {} skipped, {} dropped for newer ones; medians: detector {:.3} ms, \
             arrival to /tf {:.3} ms, of which the node's own {:.3} ms",
            self.frames,
            self.skipped,
            self.dropped,
            median(&self.detect_ms),
            median(&self.arrival_to_tf_ms),
            median(&own)
        )
    }
}

/// The DDS domain from `ROS_DOMAIN_ID` (0 when unset).
fn domain_id() -> Result<u16, String> {
    match std::env::var("ROS_DOMAIN_ID") {
        Err(_) => Ok(0),
        Ok(text) if text.trim().is_empty() => Ok(0),
        Ok(text) => text
            .trim()
            .parse::<u16>()
            .ok()
            // The RTPS port formula runs out of ports above 232.
            .filter(|&d| d <= 232)
            .ok_or_else(|| format!("ROS_DOMAIN_ID '{text}' is not a domain, 0 to 232")),
    }
}

/// True when ROS's environment asks for discovery on this host only:
/// `ROS_LOCALHOST_ONLY=1` (up to Humble) or
/// `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST` (from Iron).
fn localhost_only() -> bool {
    std::env::var("ROS_LOCALHOST_ONLY").is_ok_and(|v| v.trim() == "1")
        || std::env::var("ROS_AUTOMATIC_DISCOVERY_RANGE")
            .is_ok_and(|v| v.trim().eq_ignore_ascii_case("LOCALHOST"))
}

/// The resolved topic names.
struct Topics {
    image: String,
    compressed: String,
    camera_info: String,
    tf: String,
    markers: String,
    markers_compat: String,
    arena_markers: String,
    debug_image: String,
    debug_compressed: String,
}

impl Topics {
    fn resolve(args: &RosArgs, base: &str, namespace: &str) -> Result<Topics, String> {
        let r = |name: &str| args.resolve(name, base, namespace);
        let image = r("image")?;
        // image_transport's rules: the compressed topic hangs below the
        // image topic, and camera_info sits beside it unless remapped.
        let camera_info = if args.remaps_name("camera_info", base, namespace) {
            r("camera_info")?
        } else {
            whycode::ros::camera_info_beside(&image)
        };
        let debug_image = r("~/debug_image")?;
        Ok(Topics {
            compressed: format!("{image}/compressed"),
            image,
            camera_info,
            tf: r("/tf")?,
            markers: r("~/markers")?,
            markers_compat: r("~/markers_compat")?,
            arena_markers: r("~/arena_markers")?,
            debug_compressed: format!("{debug_image}/compressed"),
            debug_image,
        })
    }
}

/// QoS of camera drivers: best effort, volatile, and a history of one, so
/// only the newest frame waits.
const SENSOR_QOS: QosProfile = QosProfile::subscription_default();
/// tf2's: reliable, volatile, keep last 100.
const TF_QOS: QosProfile =
    QosProfile::publisher_default().history(History::KeepLast { depth: 100 });
/// The detections: reliable, keep last 10.
const MARKERS_QOS: QosProfile =
    QosProfile::publisher_default().history(History::KeepLast { depth: 10 });
/// The debug image: reliable (a reliable writer serves best-effort readers
/// too), newest only.
const DEBUG_QOS: QosProfile = QosProfile::publisher_default();

/// Everything the loop changes from frame to frame.
struct Pipeline {
    node: Node,
    topics: Topics,
    settings: Settings,
    session: Session,
    converter: Converter,
    /// The newest valid calibration from camera_info, at its own size.
    camera_info: Option<Camera>,
    log: Arc<Logger>,
    tf: Publisher<TfMessage>,
    markers: Publisher<MarkerArray>,
    compat: Option<Publisher<CompatMarkerArray>>,
    /// `~/arena_markers`, while an arena is set.
    arena_markers: Option<Publisher<MarkerArray>>,
    debug: Option<(Publisher<Image>, Publisher<CompressedImage>)>,
    /// Last sequence number seen per writer, to count dropped frames.
    last_sequence: Option<(ros2_client::Gid, i64)>,
    stats: Stats,
}

/// One frame's output.
struct Described {
    markers: MarkerArray,
    /// Everything the frame puts on /tf, sent as one TFMessage: one
    /// transform per identified marker; the boards' poses and the arena's
    /// floor frame join them in the frame loop (`whycode::ros::describe`).
    transforms: Vec<TransformStamped>,
    /// Each marker's pose at its own diameter, in the markers' order.
    poses: Vec<Option<whycode::Pose>>,
}

/// A frame as it came off the reader.
enum Frame {
    Raw(Image),
    Compressed(CompressedImage),
}

impl Frame {
    fn header(&self) -> &Header {
        match self {
            Frame::Raw(m) => &m.header,
            Frame::Compressed(m) => &m.header,
        }
    }
}

type FrameStream<'a> =
    Pin<Box<dyn FusedStream<Item = ros2_client::ReadResult<(Frame, MessageInfo)>> + 'a>>;

/// Starts the node described by `args` and runs it until told to stop
/// through `control` (whose sender `controller` is handed to the
/// parameter services). An error is a one-line reason: a bad argument or
/// parameter, or a DDS participant that could not be made.
pub fn run(
    args: &RosArgs,
    controller: Controller,
    mut control: UnboundedReceiver<Control>,
) -> Result<Stats, String> {
    let (base, namespace) = args.node_name(params::DEFAULT_NODE_NAME)?;
    let node_name = NodeName::new(&namespace, &base)
        .map_err(|e| format!("node name {namespace}/{base}: {e:?}"))?;
    let fqn = node_name.fully_qualified_name();
    let log = Arc::new(Logger::new(
        &base,
        args.log_level.unwrap_or(LogLevel::Info),
        args.stdout_logs,
    ));

    let mut settings = Settings::default();
    let mut built_in = Vec::new();
    for (name, value) in args.parameters(&fqn, &base)? {
        if params::NAMES.contains(&name.as_str()) {
            settings = settings.with(&name, &value).map_err(|e| e.to_string())?;
        } else if params::BUILT_IN.contains(&name.as_str()) {
            built_in.push((name, value));
        } else {
            log.warn(&format!(
                "parameter {name} ignored: this node has {}",
                params::NAMES.join(", ")
            ));
        }
    }
    let config = params::detector_config(&settings, None).map_err(|e| e.to_string())?;
    let topics = Topics::resolve(args, &base, &namespace)?;

    let domain = domain_id()?;
    let mut participant = DomainParticipantBuilder::new(domain);
    if localhost_only() {
        participant = participant.with_only_networks([Ipv4Addr::LOCALHOST]);
    }
    let participant = participant
        .build()
        .map_err(|e| format!("cannot join DDS domain {domain}: {e}"))?;
    let context = Context::from_domain_participant(participant)
        .map_err(|e| format!("cannot start ROS 2 context: {e}"))?;

    let mut options = NodeOptions::new()
        .enable_rosout(args.rosout_logs)
        .start_parameter_services(true)
        // The node checks names and types itself (integers are taken
        // for doubles), and refuses names it does not have.
        .allow_undeclared_parameters(true);
    for name in params::NAMES {
        options = options.declare_parameter(name, settings.value(name).expect("a parameter"));
    }
    for (name, value) in built_in {
        options = options.declare_parameter(&name, value);
    }
    let shared = Arc::new(ParameterGate {
        current: Mutex::new(settings.clone()),
        pending: Mutex::new(None),
        log: Arc::clone(&log),
        controller,
    });
    let gate = Arc::clone(&shared);
    let options = options
        .parameter_validator(Box::new(move |name, value| gate.check(name, value)))
        .parameter_set_action(Box::new(move |name, value| shared.apply(name, value)));
    let mut node = context
        .new_node(node_name, options)
        .map_err(|e| format!("cannot create node {fqn}: {e:?}"))?;
    if args.rosout_logs {
        log.attach_rosout(node.logging_handle());
    }
    let spinner = node
        .spinner()
        .map_err(|e| format!("cannot start the parameter services: {e}"))?;
    let spin_log = Arc::clone(&log);
    let spinning = std::thread::Builder::new()
        .name("ros2 spinner".into())
        .spawn(move || {
            if let Err(e) = futures::executor::block_on(spinner.spin()) {
                spin_log.error(&format!("parameter services stopped: {e}"));
            }
        })
        .map_err(|e| format!("cannot start the spinner thread: {e}"))?;

    let tf = create_publisher(&mut node, &topics.tf, TF_QOS)?;
    let markers = create_publisher(&mut node, &topics.markers, MARKERS_QOS)?;
    let info_sub: Subscription<CameraInfo> =
        create_subscription(&mut node, &topics.camera_info, SENSOR_QOS)?;
    log.info(&format!(
        "{fqn} on DDS domain {domain}{}: images from {}, camera_info from {}, /tf to {}, \
         markers to {}",
        if localhost_only() {
            " (localhost only)"
        } else {
            ""
        },
        match settings.image_transport {
            Transport::Raw => &topics.image,
            Transport::Compressed => &topics.compressed,
        },
        topics.camera_info,
        topics.tf,
        topics.markers
    ));
    let mut pipeline = Pipeline {
        node,
        topics,
        session: Session::new(config),
        settings,
        converter: Converter::default(),
        camera_info: None,
        log,
        tf,
        markers,
        compat: None,
        arena_markers: None,
        debug: None,
        last_sequence: None,
        stats: Stats::default(),
    };
    pipeline.sync_publishers();
    pipeline.describe_setup();

    serve(&mut pipeline, &info_sub, &mut control)?;
    pipeline.log.info(&pipeline.stats.summary());

    // Leave the domain in order, so that other participants see every
    // reader and writer go at once (the participant's dispose) instead of
    // waiting for their leases to run out: the node's entities first, then
    // the parameter services (the node's drop stops their spinner), and the
    // participant last.
    let stats = std::mem::take(&mut pipeline.stats);
    let log = Arc::clone(&pipeline.log);
    log.detach_rosout();
    drop(info_sub);
    drop(pipeline);
    if spinning.join().is_err() {
        log.error("the parameter services' thread panicked");
    }
    drop(context);
    Ok(stats)
}

/// The loop: frames, calibrations and parameter changes until told to
/// stop. The image subscription is made afresh when the transport changes.
fn serve(
    pipeline: &mut Pipeline,
    info_sub: &Subscription<CameraInfo>,
    control: &mut UnboundedReceiver<Control>,
) -> Result<(), String> {
    let infos = info_sub.async_stream();
    futures::pin_mut!(infos);
    loop {
        // (Re)subscribe the image topic of the transport in use.
        let transport = pipeline.settings.image_transport;
        let (raw, compressed): (
            Option<Subscription<Image>>,
            Option<Subscription<CompressedImage>>,
        ) = match transport {
            Transport::Raw => (
                Some(create_subscription(
                    &mut pipeline.node,
                    &pipeline.topics.image,
                    SENSOR_QOS,
                )?),
                None,
            ),
            Transport::Compressed => (
                None,
                Some(create_subscription(
                    &mut pipeline.node,
                    &pipeline.topics.compressed,
                    SENSOR_QOS,
                )?),
            ),
        };
        let mut frames: FrameStream = match (&raw, &compressed) {
            (Some(sub), _) => Box::pin(
                sub.async_stream()
                    .map(|r| r.map(|(m, i)| (Frame::Raw(m), i))),
            ),
            (_, Some(sub)) => Box::pin(
                sub.async_stream()
                    .map(|r| r.map(|(m, i)| (Frame::Compressed(m), i))),
            ),
            _ => unreachable!("one subscription exists"),
        };
        let newest = || -> Option<(Frame, MessageInfo)> {
            match (&raw, &compressed) {
                (Some(sub), _) => sub.take().ok().flatten().map(|(m, i)| (Frame::Raw(m), i)),
                (_, Some(sub)) => sub
                    .take()
                    .ok()
                    .flatten()
                    .map(|(m, i)| (Frame::Compressed(m), i)),
                _ => None,
            }
        };
        let resubscribe = futures::executor::block_on(async {
            loop {
                // Biased, in this order: a parameter change the services
                // have answered applies to every frame that comes after the
                // answer, and a frame is read with the newest calibration.
                futures::select_biased! {
                    message = control.next() => match message {
                        Some(Control::Settings(update)) => {
                            let Update { settings, config, change } = *update;
                            pipeline.on_settings(settings, config);
                            if change == Change::Transport
                                && pipeline.settings.image_transport != transport
                            {
                                return true;
                            }
                        }
                        Some(Control::Stop) | None => return false,
                    },
                    info = infos.select_next_some() => match info {
                        Ok((info, _)) => pipeline.on_camera_info(&info),
                        Err(e) => {
                            pipeline.log.once(
                                LogLevel::Warn,
                                "camera_info read",
                                &format!("a camera_info message could not be read: {e}"),
                            );
                        }
                    },
                    frame = frames.select_next_some() => match frame {
                        Ok((mut frame, mut info)) => {
                            let taken = Instant::now();
                            // A newer frame that came in meanwhile wins.
                            while let Some((newer, newer_info)) = newest() {
                                pipeline.count_gap(&info);
                                pipeline.stats.dropped += 1;
                                frame = newer;
                                info = newer_info;
                            }
                            pipeline.on_frame(frame, &info, taken);
                        }
                        Err(e) => {
                            pipeline.log.once(
                                LogLevel::Warn,
                                "image read",
                                &format!("an image message could not be read: {e}"),
                            );
                        }
                    },
                }
            }
        });
        if !resubscribe {
            break;
        }
    }
    Ok(())
}

/// A topic of `M` by its fully qualified ROS name.
fn create_topic<M: RosType>(
    node: &mut Node,
    topic: &str,
    qos: QosProfile,
) -> Result<ros2_client::dds::rustdds::Topic, String> {
    let name = Name::parse(topic).map_err(|e| format!("topic {topic}: {e:?}"))?;
    node.create_topic(
        &name,
        ros2_client::MessageTypeName::new(M::PACKAGE, M::NAME),
        &qos,
    )
    .map_err(|e| format!("cannot create topic {topic}: {e}"))
}

/// A publisher of `M` on a fully qualified ROS topic name.
pub fn create_publisher<M: RosType + serde::Serialize>(
    node: &mut Node,
    topic: &str,
    qos: QosProfile,
) -> Result<Publisher<M>, String> {
    let t = create_topic::<M>(node, topic, qos.clone())?;
    node.create_publisher(&t, Some(qos))
        .map_err(|e| format!("cannot publish {topic}: {e}"))
}

/// A subscription of `M` to a fully qualified ROS topic name.
pub fn create_subscription<M: RosType + DeserializeOwned + 'static>(
    node: &mut Node,
    topic: &str,
    qos: QosProfile,
) -> Result<Subscription<M>, String> {
    let t = create_topic::<M>(node, topic, qos.clone())?;
    node.create_subscription(&t, Some(qos))
        .map_err(|e| format!("cannot subscribe {topic}: {e}"))
}

/// Checks parameter changes for the parameter services and passes the
/// accepted ones to the loop. Runs on the spinner's thread.
struct ParameterGate {
    current: Mutex<Settings>,
    /// The last change checked, with what was built for it, so that the
    /// family is made once per change.
    pending: Mutex<Option<Checked>>,
    log: Arc<Logger>,
    controller: Controller,
}

struct Checked {
    name: String,
    value: ParameterValue,
    settings: Settings,
    config: Option<SessionConfig>,
}

impl ParameterGate {
    /// The validator: the whole settings with this change must hold. The
    /// refusal is text because ros2-client sends it as the reason of the
    /// SetParameters response (its `SetParametersResult`).
    fn check(&self, name: &str, value: &ParameterValue) -> Result<(), String> {
        let current = self.current.lock().expect("settings lock").clone();
        let refuse = |reason: String| {
            self.log.warn(&format!(
                "refused: {reason}; {name} stays {}",
                current
                    .value(name)
                    .map_or_else(|| "undeclared".into(), |v| format!("{v:?}"))
            ));
            Err(reason)
        };
        let next = match current.with(name, value) {
            Ok(next) => next,
            Err(e) => return refuse(e.to_string()),
        };
        if next == current {
            return Ok(());
        }
        let config = if Settings::change_of(name) == Change::Detector {
            match params::detector_config(&next, None) {
                Ok(config) => Some(config),
                Err(e) => return refuse(e.to_string()),
            }
        } else {
            None
        };
        *self.pending.lock().expect("pending lock") = Some(Checked {
            name: name.to_string(),
            value: value.clone(),
            settings: next,
            config,
        });
        Ok(())
    }

    /// The set action: the change was accepted (by [`Self::check`]).
    fn apply(&self, name: &str, value: &ParameterValue) -> Result<(), String> {
        let mut current = self.current.lock().expect("settings lock");
        let checked = self
            .pending
            .lock()
            .expect("pending lock")
            .take()
            .filter(|c| c.name == name && c.value == *value);
        let (next, config) = match checked {
            Some(c) => (c.settings, c.config),
            None => {
                let next = current.with(name, value).map_err(|e| e.to_string())?;
                if next == *current {
                    return Ok(());
                }
                let config = (Settings::change_of(name) == Change::Detector)
                    .then(|| params::detector_config(&next, None))
                    .transpose()
                    .map_err(|e| e.to_string())?;
                (next, config)
            }
        };
        *current = next.clone();
        self.log.info(&format!("parameter {name} set to {value:?}"));
        self.controller
            .0
            .unbounded_send(Control::Settings(Box::new(Update {
                settings: next,
                config,
                change: Settings::change_of(name),
            })))
            .map_err(|_| "the node is stopping".to_string())
    }
}

/// A frame's grey pixels: the message's own bytes when they are grey
/// already, a decoded image otherwise.
enum Grey<'a> {
    Borrowed(GrayView<'a>),
    Owned(image::GrayImage),
}

impl Grey<'_> {
    fn as_view(&self) -> GrayView<'_> {
        match self {
            Grey::Borrowed(view) => view.clone(),
            Grey::Owned(image) => {
                GrayView::from_raw(image.width(), image.height(), image.as_raw().as_slice())
                    .expect("a whole image")
            }
        }
    }
}

impl Pipeline {
    /// Logs what the settings mean for the output, once at start and after
    /// each change.
    fn describe_setup(&self) {
        let s = &self.settings;
        let target = match &self.session.detector_config().target {
            whycode::Target::WhyCon => "legacy WhyCon circles (no IDs, so no /tf)".to_string(),
            whycode::Target::WhyCode(f) => format!(
                "WhyCode {}-bit distance-{} family ({} IDs)",
                f.bits(),
                f.distance(),
                f.len()
            ),
            whycode::Target::AnyBits { distance } => format!(
                "WhyCode markers of any bit count, IDs at distance {}",
                distance.unwrap_or(0)
            ),
        };
        self.log.info(&format!(
            "looking for {target}; marker diameter {}",
            match s.detector_diameter() {
                Some(d) if s.diameter > 0.0 => format!("{d} m"),
                Some(_) => "per tag.sizes only".into(),
                None => "not set (-p diameter:=<metres>): no poses, no /tf".into(),
            }
        ));
    }

    /// Counts frames the reader's history dropped: a gap in one writer's
    /// sequence numbers.
    fn count_gap(&mut self, info: &MessageInfo) {
        let (writer, sequence) = (info.publisher_gid(), info.sequence_number());
        if let Some((last_writer, last)) = self.last_sequence {
            if last_writer == writer && sequence > last + 1 {
                self.stats.dropped += (sequence - last - 1) as usize;
            }
        }
        self.last_sequence = Some((writer, sequence));
    }

    fn on_settings(&mut self, settings: Settings, config: Option<SessionConfig>) {
        let old = std::mem::replace(&mut self.settings, settings);
        if old.rectified != self.settings.rectified {
            // camera_info reads otherwise now: wait for the next one.
            self.camera_info = None;
        }
        if let Some(config) = config {
            // The session starts over (its tracks were made with the old
            // settings); camera_info stays and fits the next frame.
            self.session.restart(config);
        }
        self.sync_publishers();
        self.describe_setup();
    }

    /// The optional publishers exist while their parameter is on, so that
    /// subscribers match before the first frame.
    fn sync_publishers(&mut self) {
        if self.settings.arena_file.is_empty() {
            self.arena_markers = None;
        } else if self.arena_markers.is_none() {
            match create_publisher(&mut self.node, &self.topics.arena_markers, MARKERS_QOS) {
                Ok(p) => self.arena_markers = Some(p),
                Err(e) => self.log.error(&e),
            }
        }
        if !self.settings.compat_markers {
            self.compat = None;
        } else if self.compat.is_none() {
            match create_publisher(&mut self.node, &self.topics.markers_compat, MARKERS_QOS) {
                Ok(p) => self.compat = Some(p),
                Err(e) => self.log.error(&e),
            }
        }
        if !self.settings.debug_image {
            self.debug = None;
        } else if self.debug.is_none() {
            let made = create_publisher(&mut self.node, &self.topics.debug_image, DEBUG_QOS)
                .and_then(|raw| {
                    create_publisher(&mut self.node, &self.topics.debug_compressed, DEBUG_QOS)
                        .map(|compressed| (raw, compressed))
                });
            match made {
                Ok(p) => self.debug = Some(p),
                Err(e) => self.log.error(&e),
            }
        }
    }

    fn on_camera_info(&mut self, info: &CameraInfo) {
        match info.camera(self.settings.rectified) {
            Ok(camera) => {
                if self.camera_info != Some(camera) {
                    self.log.info(&format!(
                        "calibration from {}: {}x{}, fx {:.2} fy {:.2} cx {:.2} cy {:.2}{}",
                        self.topics.camera_info,
                        camera.width,
                        camera.height,
                        camera.fx,
                        camera.fy,
                        camera.cx,
                        camera.cy,
                        if camera.has_distortion() {
                            ", with distortion"
                        } else {
                            ""
                        }
                    ));
                    self.camera_info = Some(camera);
                }
            }
            Err(reason) => {
                let keeping = if self.camera_info.is_some() {
                    "the previous calibration stays"
                } else {
                    "no poses until a valid one arrives"
                };
                self.log.once(
                    LogLevel::Warn,
                    &format!("camera_info {reason}"),
                    &format!("{} skipped: {reason}; {keeping}", self.topics.camera_info),
                );
            }
        }
    }

    fn skip(&mut self, cause: &str, message: &str) {
        self.stats.skipped += 1;
        self.log.once(LogLevel::Warn, cause, message);
    }

    fn on_frame(&mut self, frame: Frame, info: &MessageInfo, taken: Instant) {
        self.count_gap(info);
        let mut converter = std::mem::take(&mut self.converter);
        if let Some(gray) = self.grey_frame(&mut converter, &frame) {
            let gray = gray.as_view();
            if let Some(report) = self.process(&gray) {
                self.publish(&report, &gray, frame.header(), info, taken);
            }
        }
        self.converter = converter;
    }

    /// The frame's grey pixels, or `None` (skipped, and said why) when the
    /// message cannot be read as an image.
    fn grey_frame<'a>(
        &mut self,
        converter: &'a mut Converter,
        frame: &'a Frame,
    ) -> Option<Grey<'a>> {
        let result = match frame {
            Frame::Raw(msg) => converter.gray(msg).map(Grey::Borrowed),
            Frame::Compressed(msg) => converter
                .gray_compressed(msg, &self.topics.compressed)
                .map(Grey::Owned),
        };
        match result {
            Ok(gray) => Some(gray),
            Err(e) => {
                let topic = match frame {
                    Frame::Raw(_) => &self.topics.image,
                    Frame::Compressed(_) => &self.topics.compressed,
                };
                let message = format!("{topic}: frame skipped: {e}");
                self.skip(&e.cause(), &message);
                None
            }
        }
    }

    /// The session's report of one frame, or `None` (skipped, and said why)
    /// when the camera or arena does not fit it.
    fn process(&mut self, gray: &GrayView) -> Option<FrameReport> {
        let (width, height) = gray.dimensions();
        let processed = self.session.process(SessionFrame {
            image: gray,
            name: String::new(),
            stream: None,
            camera: self.camera_info,
        });
        let problem = match processed {
            Ok(report) => return Some(report),
            Err(problem) => problem,
        };
        let reason = match problem {
            SessionError::Camera {
                from_stream: true,
                problem,
            } => format!(
                "the calibration from {} does not fit this image: {problem}",
                self.topics.camera_info
            ),
            SessionError::Camera { problem, .. } => {
                format!("the arena file's calibration does not fit this image: {problem}")
            }
            SessionError::Arena(problem) => problem,
        };
        self.skip(
            &format!("fit {width}x{height}"),
            &format!("frame skipped: {reason}"),
        );
        None
    }

    /// Publishes one frame's results: /tf, the marker arrays (ours, the
    /// original's, the arena's) and the debug image, and counts its times.
    fn publish(
        &mut self,
        report: &FrameReport,
        gray: &GrayView,
        header: &Header,
        info: &MessageInfo,
        taken: Instant,
    ) {
        let parent = if self.settings.camera_frame.is_empty() {
            header.frame_id.clone()
        } else {
            self.settings.camera_frame.clone()
        };
        let stamped = Header {
            stamp: header.stamp,
            frame_id: parent.clone(),
        };
        let Described {
            markers,
            transforms,
            poses,
        } = self.describe(report, &stamped);
        if self.settings.publish_tf && !transforms.is_empty() {
            self.publish_tf(&parent, transforms);
        }
        self.count_times(report.elapsed_ms, info, taken);
        if self.settings.compat_markers {
            self.publish_compat(&markers, &poses);
        }
        if let Some(publisher) = &self.arena_markers {
            let placed = whycode::ros::describe::arena_markers(
                &markers,
                &report.places,
                &self.settings.arena_frame,
            );
            if let Err(e) = publisher.publish(placed) {
                self.log.once(
                    LogLevel::Warn,
                    "arena markers publish",
                    &format!("{}: publish failed: {e}", self.topics.arena_markers),
                );
            }
        }
        if let Err(e) = self.markers.publish(markers) {
            self.log.once(
                LogLevel::Warn,
                "markers publish",
                &format!("{}: publish failed: {e}", self.topics.markers),
            );
        }
        if self.settings.debug_image {
            self.publish_debug(gray, &report.markers, &stamped);
        }
    }

    fn publish_tf(&self, parent: &str, transforms: Vec<TransformStamped>) {
        if parent.is_empty() {
            self.log.once(
                LogLevel::Warn,
                "no frame_id",
                "the images carry no frame_id and camera_frame is not set: no /tf",
            );
        } else if let Err(e) = self.tf.publish(TfMessage { transforms }) {
            self.log.once(
                LogLevel::Warn,
                "tf publish",
                &format!("{}: publish failed: {e}", self.topics.tf),
            );
        }
    }

    /// The frame's detection time, and the times from taking it off the
    /// topic (and from its arrival) to publishing /tf.
    fn count_times(&mut self, detect_ms: f64, info: &MessageInfo, taken: Instant) {
        let published = Instant::now();
        let arrival_ms = info
            .received_timestamp()
            .map(|t| (wall_clock_nanos() - t.to_nanos()) as f64 * 1e-6);
        self.stats.frames += 1;
        self.stats.detect_ms.push(detect_ms);
        self.stats
            .take_to_tf_ms
            .push((published - taken).as_secs_f64() * 1e3);
        if let Some(ms) = arrival_ms {
            self.stats.arrival_to_tf_ms.push(ms);
        }
    }

    /// The detections as a marker array and as transforms: one per
    /// identified marker with a pose, to its frame (the most confident
    /// marker when two read as the same ID), by the library's conversion
    /// that bags written by `whycode detect --output` share.
    fn describe(&self, report: &FrameReport, header: &Header) -> Described {
        let detections = &report.markers;
        let detector_diameter = self.session.detector_config().diameter_m;
        let described = whycode::ros::describe::describe_frame(
            report,
            header,
            detector_diameter,
            |id| {
                if id == 0 {
                    (
                        None,
                        (self.settings.diameter > 0.0).then_some(self.settings.diameter),
                    )
                } else {
                    let (frame, size) = self.settings.tag(id);
                    (Some(frame.into_owned()), size)
                }
            },
            self.session
                .arena()
                .map(|arena| (arena, self.settings.arena_frame.as_str())),
        );
        for frame in &described.duplicate_frames {
            self.log.once(
                LogLevel::Warn,
                &format!("duplicate {frame}"),
                &format!(
                    "two markers read as {frame} in one frame: /tf gets the more confident one"
                ),
            );
        }
        if detections.iter().any(|d| d.id != 0) && detector_diameter.is_none() {
            self.log.once(
                LogLevel::Warn,
                "no diameter",
                "markers found, but no diameter is set (-p diameter:=<metres>, or tag.sizes): \
                 no poses, no /tf",
            );
        } else if detections.iter().any(|d| d.id != 0)
            && self.session.detector_config().camera.is_none()
        {
            self.log.once(
                LogLevel::Warn,
                "no camera_info",
                &format!(
                    "markers found, but no calibration has come on {} yet: no poses, no /tf",
                    self.topics.camera_info
                ),
            );
        }
        Described {
            markers: described.markers,
            transforms: described.transforms,
            poses: described.poses,
        }
    }

    /// The original whycode-ros2 node's message; IDs above 127 do not fit
    /// its `int8 id` and are left out rather than wrapped to another ID.
    fn publish_compat(&self, markers: &MarkerArray, poses: &[Option<whycode::Pose>]) {
        let Some(publisher) = &self.compat else {
            return;
        };
        let mut compat = Vec::with_capacity(markers.markers.len());
        for (m, pose) in markers.markers.iter().zip(poses) {
            let Ok(id) = i8::try_from(m.id) else {
                self.log.once(
                    LogLevel::Warn,
                    "compat id",
                    &format!(
                        "{}: ID {} does not fit whycode_interfaces' int8 id: left out there \
                         (it is on {})",
                        self.topics.markers_compat, m.id, self.topics.markers
                    ),
                );
                continue;
            };
            let rotation = pose.map_or_else(Vector3::default, |pose| {
                let (roll, pitch, yaw) = pose.roll_pitch_yaw();
                Vector3 {
                    x: roll,
                    y: pitch,
                    z: yaw,
                }
            });
            compat.push(CompatMarker {
                id,
                size: (std::f64::consts::PI * m.semi_major * m.semi_minor).round() as i32,
                u: m.u as f32,
                v: m.v as f32,
                angle: m.yaw as f32,
                position: m.pose,
                rotation,
            });
        }
        let message = CompatMarkerArray {
            header: markers.header.clone(),
            markers: compat,
        };
        if let Err(e) = publisher.publish(message) {
            self.log.once(
                LogLevel::Warn,
                "compat publish",
                &format!("{}: publish failed: {e}", self.topics.markers_compat),
            );
        }
    }

    /// The image with the detections drawn: PNG on
    /// `~/debug_image/compressed` as drawn, and rgb8 on `~/debug_image`.
    fn publish_debug(&self, gray: &GrayView, detections: &[Detection], header: &Header) {
        let Some((raw, compressed)) = &self.debug else {
            return;
        };
        let owned = image::GrayImage::from_raw(gray.width(), gray.height(), gray.as_raw().to_vec())
            .expect("a whole image");
        // Drawn once; the PNG is encoded from the same pixels, not decoded back.
        let drawn = whycode::session::annotate::annotated_rgb(&owned, detections)
            .map_err(|e| e.to_string())
            .and_then(|rgb| {
                let png = whycode::image_io::encode_rgb_png(&rgb).map_err(|e| e.to_string())?;
                Ok((png, rgb))
            });
        let (png, rgb) = match drawn {
            Ok(drawn) => drawn,
            Err(e) => {
                self.log.once(
                    LogLevel::Warn,
                    "debug draw",
                    &format!("debug image not drawn: {e}"),
                );
                return;
            }
        };
        let (width, height) = rgb.dimensions();
        let image = Image {
            header: header.clone(),
            height,
            width,
            encoding: "rgb8".into(),
            is_bigendian: 0,
            step: width * 3,
            data: rgb.into_raw(),
        };
        let sent = raw
            .publish(image)
            .map_err(|e| e.to_string())
            .and_then(|()| {
                compressed
                    .publish(CompressedImage {
                        header: header.clone(),
                        format: "png".into(),
                        data: png,
                    })
                    .map_err(|e| e.to_string())
            });
        if let Err(e) = sent {
            self.log.once(
                LogLevel::Warn,
                "debug publish",
                &format!("{}: publish failed: {e}", self.topics.debug_image),
            );
        }
    }
}

fn wall_clock_nanos() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or(Duration::ZERO)
        .as_nanos() as i64
}
