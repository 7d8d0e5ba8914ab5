//! `whycode.read_frames(path)`: the frames of a ROS 2 bag or a video, for
//! users who run their own loop, through the library's reader (the one
//! `whycode detect` reads recordings with).

use crate::{guard, pixels, spec_error, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::Mutex;
use whycode::recording::{Frame, Recording, RecordingError};
use whycode::spec::RecordingSpec;

/// One frame as Python gets it: index, stamp (ns) and the grey image.
type PyFrame<'py> = (u64, i64, Bound<'py, numpy::PyArray2<u8>>);

/// Frames decoded ahead of the Python loop.
const AHEAD: usize = 4;

fn recording_error(err: RecordingError) -> Error {
    match err {
        RecordingError::Io { .. } => Error::Os(err.to_string()),
        _ => Error::value(err.to_string()),
    }
}

/// An iterator over a recording's frames: `(frame, stamp_ns, image)` with
/// the image an HxW uint8 array. A thread of its own reads ahead, so that
/// decoding overlaps the caller's work.
#[pyclass(module = "whycode", name = "FrameReader")]
pub struct FrameReader {
    frames: Mutex<Receiver<Result<Frame, RecordingError>>>,
}

#[pymethods]
impl FrameReader {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&self, py: Python<'py>) -> PyResult<Option<PyFrame<'py>>> {
        let next = py.detach(|| {
            self.frames
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .recv()
                .ok()
        });
        match next {
            None => Ok(None),
            Some(Ok(frame)) => Ok(Some((
                frame.index,
                frame.stamp_ns,
                pixels::to_array(py, frame.image)?,
            ))),
            Some(Err(err)) => Err(recording_error(err).into()),
        }
    }
}

/// The frames of a ROS 2 bag (.mcap) or a video (through ffmpeg), as
/// `whycode detect` reads them.
#[pyfunction]
#[pyo3(signature = (path, *, topic=None, every=None, start=None, end=None))]
fn read_frames(
    path: PathBuf,
    topic: Option<String>,
    every: Option<u64>,
    start: Option<f64>,
    end: Option<f64>,
) -> PyResult<FrameReader> {
    let receiver = guard(|| {
        let read = RecordingSpec {
            topic,
            every,
            start,
            end,
        }
        .build()
        .map_err(spec_error)?;
        let recording = Recording::open(&path).map_err(recording_error)?;
        // Errors about the topic come now, not at the first frame.
        drop(recording.frames(&read).map_err(recording_error)?);
        let (send, receive) = sync_channel(AHEAD);
        std::thread::spawn(move || {
            let frames = match recording.frames(&read) {
                Ok(frames) => frames,
                Err(err) => {
                    let _ = send.send(Err(err));
                    return;
                }
            };
            for frame in frames {
                // The Python side gone (the iterator dropped) ends the read.
                if send.send(frame).is_err() {
                    break;
                }
            }
        });
        Ok(receive)
    })?;
    Ok(FrameReader {
        frames: Mutex::new(receiver),
    })
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<FrameReader>()?;
    m.add_function(wrap_pyfunction!(read_frames, m)?)
}
