"""whycode_node against an independent ROS 2 peer (CycloneDDS): simulated
camera frames with ground truth in, /tf and ~/markers checked against the
truth. Run by ros2/test.sh inside a network namespace that holds only
loopback; the node is started with ROS_LOCALHOST_ONLY=1 and the peer bound
to `lo`."""

from __future__ import annotations

import math
import re
import statistics
import subprocess
import time

import numpy as np
import pytest

import peer as P
import ros2_types as t
from conftest import DIAMETER_M, IDS, SEQUENCE_FRAMES, node_args


def percentile(values, q):
    return float(np.percentile(np.array(values), q)) if values else float("nan")


def angle_between(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2 * math.pi))


def check_answer(answer: P.Answer, scene: P.Scene, frame_id: str = "camera_optical"):
    """Markers and transforms against the truth; (right, wrong, position
    errors in metres, rotation errors in degrees)."""
    truth = scene.markers()
    assert answer.markers is not None, "no ~/markers for the frame"
    assert answer.markers.header.frame_id == frame_id
    right = wrong = 0
    position_errors, rotation_errors = [], []
    for m in answer.markers.markers:
        if m.id == 0:
            continue
        if m.id not in truth:
            wrong += 1
            continue
        right += 1
        true = truth[m.id]
        assert m.code == true["code"] and m.has_code
        assert abs(m.u - true["u"]) < 1.0 and abs(m.v - true["v"]) < 1.0, (m, true)
        ellipse = true["ellipse"]
        assert abs(m.semi_major - ellipse["semi_major"]) < 1.0
        assert abs(m.semi_minor - ellipse["semi_minor"]) < 1.0
        assert m.has_yaw and angle_between(m.yaw, true["yaw"]) < math.radians(3)
        assert 0.0 < m.confidence <= 1.0
        assert m.status in ("exact", "corrected")
        assert m.has_pose and m.diameter == DIAMETER_M
        assert m.frame_id == f"whycode_{m.id}"
    for x in answer.transforms:
        marker_id = int(x.child_frame_id.removeprefix("whycode_"))
        assert x.header.frame_id == frame_id
        assert marker_id in truth, f"/tf for ID {marker_id}, which is not in view"
        position_errors.append(P.position_error(x.transform, truth[marker_id]))
        rotation_errors.append(P.rotation_error_deg(x.transform.rotation, truth[marker_id]))
    return right, wrong, position_errors, rotation_errors


@pytest.mark.figures
def test_a_moving_camera_gets_every_marker_with_its_pose(start_node, peer, sequence, figures):
    node = start_node(*node_args())
    rig = P.Rig(peer).ready(sequence[0])
    answered = right = wrong = visible = tf_count = 0
    position_errors, rotation_errors, latencies = [], [], []
    for k, scene in enumerate(sequence):
        answer = rig.send(scene, (1000 + k, 0))
        if answer.markers is None:
            continue
        answered += 1
        visible += len(scene.markers())
        r, w, pe, re = check_answer(answer, scene)
        right += r
        wrong += w
        tf_count += len(answer.transforms)
        position_errors += pe
        rotation_errors += re
        if answer.latency_ms is not None:
            latencies.append(answer.latency_ms)
    node.stop()
    summary = node.log().strip().splitlines()[-1]
    distance = statistics.median(
        np.linalg.norm(m["position"]) for s in sequence for m in s.markers().values()
    )
    figures.append(
        f"moving camera, 640x480, {SEQUENCE_FRAMES} frames of {len(IDS)} markers "
        f"(50 mm at {distance:.2f} m median): {answered}/{SEQUENCE_FRAMES} frames answered, "
        f"{right}/{visible} markers identified, {wrong} wrong IDs, {tf_count} transforms"
    )
    figures.append(
        f"  position error {1e3 * statistics.median(position_errors):.2f} mm median, "
        f"{1e3 * max(position_errors):.2f} mm max; rotation error "
        f"{statistics.median(rotation_errors):.2f} deg median, {max(rotation_errors):.2f} max"
    )
    figures.append(
        f"  write returned -> /tf read: {statistics.median(latencies):.2f} ms median, "
        f"{percentile(latencies, 90):.2f} ms p90"
    )
    figures.append("  node: " + summary.split("]: ", 1)[-1])
    assert answered == SEQUENCE_FRAMES
    assert wrong == 0
    assert right == visible
    assert tf_count == visible
    assert statistics.median(position_errors) < 0.005
    assert max(position_errors) < 0.02
    assert statistics.median(rotation_errors) < 2.0
    assert "frames answered" in summary


def test_every_encoding_reads_as_mono8(start_node, peer, scene):
    start_node(*node_args("-p", "tracking:=false"))
    rig = P.Rig(peer).ready(scene)
    reference = rig.send(scene, (2000, 0), "mono8")
    assert check_answer(reference, scene)[1] == 0
    expected = {m.id: m for m in reference.markers.markers}
    assert sorted(expected) == sorted(scene.markers())
    encodings = ["mono16", "rgb8", "bgr8", "rgba8", "bgra8", "yuv422", "uyvy", "yuv422_yuy2", "yuyv"]
    for k, encoding in enumerate(encodings):
        answer = rig.send(scene, (2001 + k, 0), encoding)
        got = {m.id: m for m in answer.markers.markers}
        assert sorted(got) == sorted(expected), encoding
        for marker_id, m in got.items():
            e = expected[marker_id]
            # Grey replicated into colour or luma reads back exactly; mono16
            # is stretched to the brightest value, a little off.
            tolerance = 0.05 if encoding == "mono16" else 1e-9
            assert abs(m.u - e.u) < tolerance and abs(m.v - e.v) < tolerance, encoding
        assert len(answer.transforms) == len(expected), encoding


def test_compressed_transport_reads_jpeg_and_png(start_node, peer, scene):
    start_node(*node_args("-p", "image_transport:=compressed", "-p", "tracking:=false"))
    rig = P.Rig(peer, compressed=True).ready(scene)
    raw = peer.writer("rt/camera/image_raw", t.Image)
    for k, fmt in enumerate(["png", "jpeg", "png"]):
        answer = rig.send(scene, (3000 + k, 0), fmt)
        right, wrong, pe, _ = check_answer(answer, scene)
        assert wrong == 0 and right == len(scene.markers()), fmt
        assert max(pe) < 0.02
    # The raw topic is not read with the compressed transport.
    assert raw.get_publication_matched_status().current_count == 0


def test_bad_input_is_logged_once_and_skipped(start_node, peer, scene):
    node = start_node(*node_args())
    rig = P.Rig(peer).ready(scene)
    stamp = iter((4000 + k, 0) for k in range(1000))
    good = lambda: rig.send(scene, next(stamp))  # noqa: E731

    def image(**fields):
        message = P.image_message(scene, next(stamp))
        for name, value in fields.items():
            setattr(message, name, value)
        return message

    def unanswered(message, info=True):
        s = P.stamp_of(message.header)
        rig.send(scene, s, message=message, info=info, expect_tf=False, timeout=0.2)
        return rig.silence(s, 0.1)

    assert check_answer(good(), scene)[0] == len(scene.markers())
    w, h = scene.width, scene.height
    bad_images = {
        "encoding 'bayer_rggb8' is not read": dict(encoding="bayer_rggb8"),
        "data holds": dict(data=scene.gray.tobytes()[:-7]),
        "step of 100 bytes is less than a row": dict(step=100),
        "empty image (0x0 pixels)": dict(width=0, height=0, step=0, data=b""),
        "a 4:2:2 image must have an even width": dict(
            encoding="yuyv", width=w - 1, step=2 * (w - 1), data=bytes(2 * (w - 1) * h)
        ),
    }
    for _ in range(3):
        for fields in bad_images.values():
            assert unanswered(image(**fields))
        # Each bad frame leaves the node answering the next good one.
        assert check_answer(good(), scene)[0] == len(scene.markers())

    # camera_info of zeros: refused; the calibration before stays in use.
    zeros = t.CameraInfo(header=t.Header(frame_id=rig.frame_id))
    for _ in range(3):
        answer = rig.send(scene, next(stamp), info=zeros)
        assert max(check_answer(answer, scene)[2]) < 0.02
    # A calibration for another image size of the same sensor is rescaled...
    info = scene.camera_info(rig.frame_id)
    double = scene.camera_info(rig.frame_id)
    double.width, double.height = 2 * info.width, 2 * info.height
    double.k = [2 * info.k[0], 0, 2 * info.k[2] + 0.5, 0, 2 * info.k[4], 2 * info.k[5] + 0.5, 0, 0, 1]
    rig.infos.write(double)
    time.sleep(0.1)
    answer = rig.send(scene, next(stamp), info=double)
    assert max(check_answer(answer, scene)[2]) < 0.02
    # ...and one of another aspect ratio is refused: the frame is skipped.
    square = scene.camera_info(rig.frame_id)
    square.height = square.width
    rig.infos.write(square)
    time.sleep(0.1)
    for _ in range(3):
        message = image()
        assert unanswered(message, info=square)
    # camera_info and images are two topics, in no order between them: the
    # calibration is given time to arrive before the next frame.
    rig.infos.write(info)
    time.sleep(0.1)
    answer = rig.send(scene, next(stamp))
    assert max(check_answer(answer, scene)[2]) < 0.02

    log = node.stop() == 0 and node.log()
    assert log, "the node did not exit cleanly"
    for needle in [*bad_images, "camera_info skipped: camera_info has no image size", "does not fit this image"]:
        assert log.count(needle) == 1, f"'{needle}' logged {log.count(needle)} times:\n{log}"
    assert "frames answered, 18 skipped" in log, log


def test_compressed_garbage_is_logged_once_and_skipped(start_node, peer, scene):
    node = start_node(*node_args("-p", "image_transport:=compressed"))
    rig = P.Rig(peer, compressed=True).ready(scene)
    for k in range(3):
        garbage = t.CompressedImage(
            header=t.Header(stamp=t.Time(sec=5000 + k), frame_id=rig.frame_id),
            format="jpeg",
            data=b"\xff\xd8\xff\xe0 not a jpeg",
        )
        rig.send(scene, (5000 + k, 0), message=garbage, expect_tf=False, timeout=0.2)
        assert rig.silence((5000 + k, 0), 0.1)
        assert rig.send(scene, (5100 + k, 0), "jpeg").markers is not None
    node.stop()
    assert node.log().count("compressed image does not decode") == 1, node.log()


def test_parameters_change_through_the_parameter_services(start_node, peer, scene):
    node = start_node(*node_args("-p", "tracking:=false"))
    rig = P.Rig(peer).ready(scene)
    request = peer.writer("rq/whycode/set_parametersRequest", t.SetParametersRequest, P.RELIABLE_QOS)
    reply = peer.reader("rr/whycode/set_parametersReply", t.SetParametersResponse)
    get_request = peer.writer("rq/whycode/get_parametersRequest", t.GetParametersRequest, P.RELIABLE_QOS)
    get_reply = peer.reader("rr/whycode/get_parametersReply", t.GetParametersResponse)
    peer.wait_matched(request, reply, get_request, get_reply)

    def set_parameter(name, value: t.ParameterValue) -> t.SetParametersResult:
        request.write(t.SetParametersRequest([t.Parameter(name, value)]))
        response = P.wait_for(reply, lambda r: True, 5.0)
        assert response is not None, f"no reply to setting {name}"
        return response.results[0]

    def get_parameter(name) -> t.ParameterValue:
        get_request.write(t.GetParametersRequest([name]))
        return P.wait_for(get_reply, lambda r: True, 5.0).values[0]

    def double(x):
        return t.ParameterValue(type=t.PARAMETER_DOUBLE, double_value=x)

    before = rig.send(scene, (6000, 0)).tf()
    result = set_parameter("diameter", double(2 * DIAMETER_M))
    assert result.successful, result.reason
    after = rig.send(scene, (6001, 0)).tf()
    assert sorted(after) == sorted(before)
    for frame, x in after.items():
        ratio = x.transform.translation.z / before[frame].transform.translation.z
        assert abs(ratio - 2.0) < 1e-6, (frame, ratio)
    assert get_parameter("diameter").double_value == 2 * DIAMETER_M

    # Bad values are refused with the reason, logged, and change nothing.
    for name, value, reason in [
        ("diameter", double(-1.0), "not a plausible marker diameter"),
        ("bits", t.ParameterValue(type=t.PARAMETER_INTEGER, integer_value=99), "2 to 24"),
        ("tag.frames", t.ParameterValue(type=t.PARAMETER_STRING, string_value="x"), "list of strings"),
        ("no_such", t.ParameterValue(type=t.PARAMETER_BOOL, bool_value=True), "no such parameter"),
    ]:
        result = set_parameter(name, value)
        assert not result.successful and reason in result.reason, (name, result)
    unchanged = rig.send(scene, (6002, 0)).tf()
    for frame, x in unchanged.items():
        assert x.transform.translation.z == after[frame].transform.translation.z
    assert get_parameter("diameter").double_value == 2 * DIAMETER_M

    # Another family: these markers are no members of the 8-bit family...
    result = set_parameter("bits", t.ParameterValue(type=t.PARAMETER_INTEGER, integer_value=8))
    assert result.successful, result.reason
    answer = rig.send(scene, (6003, 0), expect_tf=False)
    assert answer.markers is not None and answer.transforms == []
    assert all(m.id == 0 for m in answer.markers.markers)
    # ...and the transport switches without a restart.
    set_parameter("bits", t.ParameterValue(type=t.PARAMETER_INTEGER, integer_value=12))
    result = set_parameter(
        "image_transport", t.ParameterValue(type=t.PARAMETER_STRING, string_value="compressed")
    )
    assert result.successful, result.reason
    compressed = P.Rig(peer, compressed=True).ready(scene)
    answer = compressed.send(scene, (6004, 0), "png")
    assert len(answer.transforms) == len(scene.markers())
    node.stop()
    log = node.log()
    assert "refused: parameter diameter: -1 m is not a plausible marker diameter" in log, log
    assert "parameter diameter set to" in log


def test_per_id_frames_and_sizes(start_node, peer, scene):
    start_node(
        *node_args(
            "-p", "tag.ids:=[3, 17]",
            "-p", "tag.frames:=[dock, charger]",
            "-p", "tag.sizes:=[0.05, 0.1]",
            "-p", "frame_prefix:=marker_",
            "-p", "camera_frame:=camera_link_optical",
        )
    )
    rig = P.Rig(peer).ready(scene)
    message = P.image_message(scene, (7000, 0), "")
    answer = rig.send(scene, (7000, 0), message=message, expect_tf=False)
    tf = {x.child_frame_id: x for x in tf_of(peer, (7000, 0))}
    truth = scene.markers()
    assert {"dock", "charger"} <= set(tf)
    assert all(x.header.frame_id == "camera_link_optical" for x in tf.values())
    assert P.position_error(tf["dock"].transform, truth[3]) < 0.02
    # Declared twice as large: twice as far along the same ray.
    z = tf["charger"].transform.translation.z
    assert abs(z / truth[17]["position"][2] - 2.0) < 0.05
    others = set(tf) - {"dock", "charger"}
    assert others == {f"marker_{i}" for i in truth if i not in (3, 17)}
    assert answer.markers.header.frame_id == "camera_link_optical"


def tf_of(peer, stamp, timeout=5.0):
    """The transforms published for `stamp`."""
    message = peer.find(
        "rt/tf",
        t.TFMessage,
        lambda m: any(P.stamp_of(x.header) == stamp for x in m.transforms),
        timeout,
        P.TF_QOS,
    )
    assert message is not None, f"no /tf for {stamp}"
    return [x for x in message.transforms if P.stamp_of(x.header) == stamp]


def apply(transform: t.Transform, point) -> np.ndarray:
    """`point` carried by `transform` (rotation, then translation)."""
    q = transform.rotation
    x, y, z, w = q.x, q.y, q.z, q.w
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    p = transform.translation
    return rotation @ np.asarray(point, dtype=float) + np.array([p.x, p.y, p.z])


def test_boards_and_arena_on_tf_and_arena_markers(start_node, peer, sheet_scene):
    """A sheet as a board and its corner markers as an arena: the board's
    pose and the floor frame join the markers' transforms in one TFMessage,
    and ~/arena_markers places every marker on the floor."""
    scene = sheet_scene.scene
    start_node(
        *node_args(
            "-p", "diameter:=0.04",
            "-p", f"boards:=[{sheet_scene.manifest}]",
            "-p", f"arena_file:={sheet_scene.arena}",
            "-p", "arena_frame:=floor",
        )
    )
    rig = P.Rig(peer).ready(scene)
    placed_reader = peer.reader("rt/whycode/arena_markers", t.MarkerArray)
    peer.wait_matched(placed_reader)
    answer = rig.send(scene, (8000, 0))
    tf = answer.tf()
    truth = scene.markers()
    assert set(truth) == set(range(1, 13))
    assert {"sheet", "floor"} | {f"whycode_{i}" for i in truth} == set(tf), sorted(tf)
    assert all(x.header.frame_id == "camera_optical" for x in tf.values())
    board_errors = [
        float(np.linalg.norm(apply(tf["sheet"].transform, (*sheet_scene.on_page[i], 0.0)) - truth[i]["position"]))
        for i in truth
    ]
    origin = sheet_scene.on_page[sheet_scene.corners[0]]

    def on_floor(i):
        x, y = sheet_scene.on_page[i]
        return (x - origin[0], origin[1] - y)

    arena_errors = [
        float(np.linalg.norm(apply(tf["floor"].transform, (*on_floor(i), 0.0)) - truth[i]["position"]))
        for i in truth
    ]
    placed = peer.find("rt/whycode/arena_markers", t.MarkerArray, lambda m: P.stamp_of(m.header) == (8000, 0), 5.0)
    assert placed is not None, "no ~/arena_markers for the frame"
    assert placed.header.frame_id == "floor"
    assert [m.id for m in placed.markers] == [m.id for m in answer.markers.markers], "same markers, same order"
    floor_errors = [
        math.dist((m.pose.position.x, m.pose.position.y), on_floor(m.id)) for m in placed.markers
    ]
    assert all(m.has_pose and abs(m.pose.position.z) < 1e-9 for m in placed.markers)
    # The sheet lies square to the arena: every marker's +x is the floor's.
    yaw_deg = [math.degrees(2 * math.atan2(m.pose.orientation.z, m.pose.orientation.w)) for m in placed.markers]
    print(f"board: worst marker {max(board_errors) * 1e3:.2f} mm off; floor frame: worst "
          f"{max(arena_errors) * 1e3:.2f} mm; ~/arena_markers: worst {max(floor_errors) * 1e3:.2f} mm, "
          f"yaw worst {max(map(abs, yaw_deg)):.2f} deg")
    assert max(board_errors) < 2e-3, board_errors
    assert max(arena_errors) < 2e-3, arena_errors
    assert max(floor_errors) < 1e-3, floor_errors
    assert max(map(abs, yaw_deg)) < 0.5, yaw_deg


def test_compat_topic_carries_the_original_interface(start_node, peer, scene):
    node = start_node(*node_args("-p", "compat_markers:=true"))
    rig = P.Rig(peer).ready(scene)
    compat = peer.reader("rt/whycode/markers_compat", t.CompatMarkerArray)
    peer.wait_matched(compat)
    for k in range(3):
        answer = rig.send(scene, (7500 + k, 0))
        message = P.wait_for(compat, lambda m: P.stamp_of(m.header) == (7500 + k, 0))
        assert message is not None
        truth = scene.markers()
        small = {i for i in truth if i <= 127}
        assert {m.id for m in message.markers} == small
        ours = {m.id: m for m in answer.markers.markers}
        for m in message.markers:
            assert abs(m.u - ours[m.id].u) < 1e-3 and m.size > 0
            assert m.position.position.z == pytest.approx(ours[m.id].pose.position.z)
    node.stop()
    assert node.log().count("does not fit whycode_interfaces' int8 id") == 1


def test_debug_image(start_node, peer, scene):
    start_node(*node_args("-p", "debug_image:=true"))
    rig = P.Rig(peer).ready(scene)
    raw = peer.reader("rt/whycode/debug_image", t.Image)
    png = peer.reader("rt/whycode/debug_image/compressed", t.CompressedImage)
    peer.wait_matched(raw, png)
    rig.send(scene, (7800, 0))
    drawn = P.wait_for(raw, lambda m: P.stamp_of(m.header) == (7800, 0))
    encoded = P.wait_for(png, lambda m: P.stamp_of(m.header) == (7800, 0))
    assert drawn.encoding == "rgb8" and (drawn.width, drawn.height) == (scene.width, scene.height)
    assert len(drawn.data) == drawn.step * drawn.height
    pixels = np.frombuffer(drawn.data, dtype=np.uint8).reshape(drawn.height, drawn.width, 3)
    # The markers are outlined in colour over the grey picture.
    assert (pixels[:, :, 0] != pixels[:, :, 1]).sum() > 100
    assert encoded.format == "png" and encoded.data[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_newest_frame_wins_over_a_queue(start_node, peer, big_scene, figures):
    # The peer writes a small JPEG every millisecond or so, while the node
    # decodes each 1920x1080 frame, detects and draws a debug image of it
    # (many milliseconds): on any machine, frames come several times faster
    # than the node answers, also while it is busy with one.
    node = start_node(
        *node_args(
            "-p", "image_transport:=compressed", "-p", "debug_image:=true", "-p", "tracking:=false"
        )
    )
    rig = P.Rig(peer, compressed=True).ready(big_scene)
    warm = rig.send(big_scene, (7900, 0), "jpeg")
    assert warm.markers is not None
    info = big_scene.camera_info(rig.frame_id)
    rig.infos.write(info)
    sent = 40
    frames = [P.compressed_message(big_scene, (8000 + k, 0), "jpeg", rig.frame_id) for k in range(sent)]
    started = time.monotonic()
    for frame in frames:
        rig.images.write(frame)
        time.sleep(0.001)
    burst_ms = (time.monotonic() - started) * 1e3
    last = (8000 + sent - 1, 0)
    # Answered frames come in order, and the newest is among the last few.
    time.sleep(1.0)
    answered = sorted(
        P.stamp_of(m.header)
        for m in peer.received(rig.markers_topic, t.MarkerArray)
        if 8000 <= m.header.stamp.sec < 8000 + sent
    )
    node.stop()
    figures.append(
        f"burst of {sent} 1920x1080 JPEG frames ({len(big_scene.jpeg) // 1024} KiB) in {burst_ms:.0f} ms "
        f"to a node drawing debug images: {len(answered)} answered, newest answered "
        f"{answered[-1][0] - 8000 if answered else None} of 0..{sent - 1}"
    )
    assert 0 < len(answered) < 0.5 * sent, answered
    assert answered[-1][0] >= last[0] - 2, answered
    # The node counts the frames it never read (gaps in the writer's
    # sequence numbers, and frames a newer one replaced before it was read).
    match = re.search(r"(\d+) frames answered, \d+ skipped, (\d+) dropped for newer ones", node.log())
    assert match, node.log()
    assert int(match.group(2)) >= sent - len(answered) - 2, match.group(0)


def test_peer_restart(start_node, domain, scene):
    start_node(*node_args())
    for round_ in range(2):
        peer = P.Peer(domain)
        rig = P.Rig(peer).ready(scene)
        for k in range(3):
            answer = rig.send(scene, (9000 + 10 * round_ + k, 0))
            assert check_answer(answer, scene)[0] == len(scene.markers()), round_
        peer.close()
        del rig, peer


def test_node_restart(start_node, peer, scene, figures):
    rig = P.Rig(peer)
    entities = (rig.images, rig.infos, rig.tf_reader, rig.markers_reader)
    for round_ in range(2):
        node = start_node(*node_args())
        rig.ready(scene)
        for k in range(3):
            answer = rig.send(scene, (9500 + 10 * round_ + k, 0))
            assert check_answer(answer, scene)[0] == len(scene.markers()), round_
        assert node.stop() == 0
        assert "3 frames answered" in node.log()
        # The peer sees the node's readers and writers go before it starts
        # again (so that a match is the new node's, not the old one's).
        stopped = time.monotonic()
        while any(P.matched(e) for e in entities):
            assert time.monotonic() - stopped < 15, [P.matched(e) for e in entities]
            time.sleep(0.05)
        if round_ == 0:
            figures.append(
                f"node stopped (SIGINT): the peer saw its endpoints go in "
                f"{(time.monotonic() - stopped) * 1e3:.0f} ms"
            )


def test_second_camera_on_another_topic(start_node, peer, scene, other_scene):
    start_node(*node_args("-r", "__node:=left", image="/left/image_raw"))
    start_node(*node_args("-r", "__node:=right", image="/right/image_raw"))
    left = P.Rig(peer, camera="/left", node="/left", frame_id="left_optical").ready(scene)
    right = P.Rig(peer, camera="/right", node="/right", frame_id="right_optical").ready(other_scene)
    for k in range(3):
        a = left.send(scene, (9800 + k, 0))
        b = right.send(other_scene, (9800 + k, 0))
        assert check_answer(a, scene, "left_optical")[:2] == (len(scene.markers()), 0)
        assert check_answer(b, other_scene, "right_optical")[:2] == (len(other_scene.markers()), 0)


def test_namespace_and_params_file(start_node, peer, scene, tmp_path):
    params = tmp_path / "params.yaml"
    params.write_text(
        f"""
/**:
  ros__parameters:
    use_sim_time: false
    diameter: 0.5
/robot/whycode:
  ros__parameters:
    bits: 12
    diameter: {DIAMETER_M}
    tag:
      ids: [42]
      frames: [target]
other_node:
  ros__parameters:
    bits: 4
"""
    )
    start_node(
        "--params-file", str(params), "-r", "__ns:=/robot", "-r", "image:=/camera/image_raw"
    )
    rig = P.Rig(peer, node="/robot/whycode").ready(scene)
    answer = rig.send(scene, (9900, 0))
    truth = scene.markers()
    tf = answer.tf()
    assert set(tf) == {"target"} | {f"whycode_{i}" for i in truth if i != 42}
    # The node's own diameter (0.05), not the wildcard's (0.5).
    assert P.position_error(tf["target"].transform, truth[42]) < 0.02


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--ros-args", "-p", "diameter:=-3"], "parameter diameter: -3 m is not a plausible"),
        (["--ros-args", "-p", "bits:=4", "-p", "distance:=9"], "parameter distance:"),
        (["--ros-args", "-p", "tag.ids:=[1, 1]"], "parameter tag.ids: ID 1 is listed twice"),
        (["--ros-args", "-p", "boards:=[/nonexistent/board.json]"],
         "parameter boards: /nonexistent/board.json: cannot read board: No such file"),
        (["--ros-args", "-p", "arena_file:=/nonexistent/arena.yaml"],
         "parameter arena_file: /nonexistent/arena.yaml: cannot read arena file"),
        (["--ros-args", "--params-file", "/nonexistent.yaml"], "/nonexistent.yaml"),
        (["--ros-args", "-r", "__node:=2fast"], "node name '2fast'"),
        (["--ros-args", "--frobnicate"], "unknown ROS argument '--frobnicate'"),
        (["stray"], "unexpected argument 'stray'"),
    ],
)
def test_bad_command_lines_exit_with_one_line(node_bin, args, needle):
    run = subprocess.run([str(node_bin), *args], capture_output=True, text=True, timeout=20)
    assert run.returncode == 2, run
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("whycode_node: ") and needle in lines[0], run.stderr


def test_help(node_bin):
    run = subprocess.run([str(node_bin), "--help"], capture_output=True, text=True, timeout=20)
    assert run.returncode == 0 and "--ros-args" in run.stdout and "image:=" in run.stdout


def only_loopback() -> bool:
    links = subprocess.run(["ip", "-o", "link"], capture_output=True, text=True).stdout
    return [line.split(":")[1].strip() for line in links.splitlines()] == ["lo"]


@pytest.mark.skipif(not only_loopback(), reason="needs a network namespace holding only lo")
def test_traffic_stays_on_loopback(start_node, peer, scene, figures):
    """With a second interface in the namespace (a veth pair, both ends
    inside), nothing the node or the peer sends goes out of it: the node's
    ROS_LOCALHOST_ONLY=1 keeps RustDDS's discovery and data on lo."""
    import socket

    subprocess.run(["ip", "link", "add", "wc0", "type", "veth", "peer", "name", "wc1"], check=True)
    try:
        for link, address in (("wc0", "10.213.0.1/24"), ("wc1", "10.213.0.2/24")):
            subprocess.run(["ip", "addr", "add", address, "dev", link], check=True)
            subprocess.run(["ip", "link", "set", link, "up", "multicast", "on"], check=True)
        capture = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(0x0003))
        capture.bind(("wc0", 0))
        capture.settimeout(0.05)
        node = start_node(*node_args())
        rig = P.Rig(peer).ready(scene)
        for k in range(10):
            assert rig.send(scene, (9950 + k, 0)).markers is not None
        # RustDDS announces its participant every few seconds: wait for one.
        deadline = time.monotonic() + 4.0
        udp = []
        while time.monotonic() < deadline:
            try:
                frame = capture.recv(65536)
            except socket.timeout:
                continue
            # IPv4 (ethertype 0x0800) carrying UDP (protocol 17).
            if frame[12:14] == b"\x08\x00" and frame[23] == 17:
                udp.append(frame)
        sockets = subprocess.run(["ss", "-uanp"], capture_output=True, text=True).stdout
        node_sockets = [line for line in sockets.splitlines() if f"pid={node.proc.pid}," in line]
        figures.append(
            f"loopback only: {len(udp)} UDP packets on a second interface during 10 frames and "
            f"4 s; the node's {len(node_sockets)} UDP sockets (ss -uanp): "
            + ", ".join(sorted({line.split()[3] for line in node_sockets}))
        )
        assert udp == []
        assert node_sockets
    finally:
        subprocess.run(["ip", "link", "del", "wc0"], check=False)
