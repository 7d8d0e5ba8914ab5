"""read_frames: a video's frames through the library's reader, with their
presentation times, and bad input refused."""

import pathlib
import subprocess

import numpy as np
import pytest

import whycode


def write_video(folder: pathlib.Path, frames: list[np.ndarray]) -> pathlib.Path:
    for k, image in enumerate(frames):
        h, w = image.shape
        (folder / f"f{k:03d}.pgm").write_bytes(b"P5\n%d %d\n255\n" % (w, h) + image.tobytes())
    video = folder / "run.avi"
    subprocess.run(
        ["ffmpeg", "-hide_banner", "-loglevel", "error", "-y", "-framerate", "5",
         "-i", str(folder / "f%03d.pgm"), "-c:v", "mjpeg", "-q:v", "2", str(video)],
        check=True,
    )
    return video


def test_a_video_yields_its_frames_stamps_and_markers(tmp_path: pathlib.Path) -> None:
    frames = [
        whycode.simulate(ids=[1, 2, 3], size=(320, 240), camera_distance="0.5m", seed=k)[0]
        for k in range(6)
    ]
    video = write_video(tmp_path, frames)
    read = list(whycode.read_frames(video))
    assert [(k, stamp) for k, stamp, _ in read] == [(k, k * 200_000_000) for k in range(6)]
    for (_, _, image), original in zip(read, frames):
        assert image.shape == original.shape and image.dtype == np.uint8
        # MJPG at high quality: the grey levels within a few steps
        assert np.abs(image.astype(int) - original.astype(int)).mean() < 3
        assert sorted(m.id for m in whycode.Detector().detect(image)) == [1, 2, 3]
    thinned = [(k, stamp) for k, stamp, _ in whycode.read_frames(video, every=2, start=0.2)]
    assert thinned == [(0, 200_000_000), (2, 600_000_000), (4, 1_000_000_000)]


def test_bad_recordings_are_refused(tmp_path: pathlib.Path) -> None:
    with pytest.raises(whycode.WhycodeOSError, match="gone.mcap"):
        whycode.read_frames(tmp_path / "gone.mcap")
    noise = tmp_path / "noise.mkv"
    noise.write_bytes(bytes(5000))
    with pytest.raises(whycode.WhycodeValueError, match="noise.mkv"):
        list(whycode.read_frames(noise))
    with pytest.raises(whycode.WhycodeValueError, match="every"):
        whycode.read_frames(noise, every=0)
