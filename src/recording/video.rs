//! Video files through the `ffmpeg` program: it decodes any codec it knows
//! into raw 8-bit grey frames on a pipe, and its `showinfo` filter reports
//! each frame's presentation time on its standard error, read on a thread
//! of its own. A pipe rather than a binding to libav: the pipe costs
//! nothing measurable next to decoding (docs/recordings.md), and a binding
//! would tie the build to one libav version and its C headers.
//!
//! `--start` seeks in ffmpeg (`-ss` before the input, with the input's
//! timestamps kept), `--end` stops it, and `--every` thins in its `select`
//! filter, so frames never asked for are not converted or piped.

use super::{Frame, ReadOptions, RecordingError, Skipped};
use image::GrayImage;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::mpsc::{Receiver, Sender};

/// The ffmpeg program: `WHYCODE_FFMPEG` when set, else `ffmpeg` on the path.
pub fn ffmpeg_program() -> PathBuf {
    std::env::var_os("WHYCODE_FFMPEG")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("ffmpeg"))
}

/// What ffmpeg's standard error tells while it runs.
enum Report {
    /// A frame's showinfo line: its number out of the filters, its pts in
    /// the filter's time base, and its size.
    Frame {
        n: u64,
        pts: i64,
        width: u32,
        height: u32,
    },
    /// The input's duration and frame rate, when it gives them.
    Expected(u64),
}

/// A video's frames as ffmpeg decodes them.
pub struct VideoFrames {
    path: PathBuf,
    child: Child,
    stdout: ChildStdout,
    reports: Receiver<Report>,
    /// ffmpeg's last lines on standard error, for the error message.
    tail: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
    /// The filter's time base (numerator, denominator), once reported.
    time_base: std::sync::Arc<std::sync::Mutex<Option<(i64, i64)>>>,
    /// ffmpeg's first line saying the file is cut short or damaged: it
    /// then decodes what it can and exits with success.
    damage: std::sync::Arc<std::sync::Mutex<Option<String>>>,
    every: u64,
    expected: Option<u64>,
    skipped: Skipped,
    done: bool,
}

impl VideoFrames {
    /// Starts ffmpeg on `path`.
    pub fn open(path: &Path, options: &ReadOptions) -> Result<VideoFrames, RecordingError> {
        let mut command = Command::new(ffmpeg_program());
        command.args(["-hide_banner", "-nostdin", "-nostats", "-loglevel", "info"]);
        if let Some(start) = options.start_ns {
            command.args(["-ss", &seconds(start)]);
        }
        if let Some(end) = options.end_ns {
            command.args(["-to", &seconds(end)]);
        }
        // Timestamps as the file has them, also after a seek.
        command.args(["-copyts", "-i"]).arg(path);
        let mut filters = String::new();
        if options.every > 1 {
            filters.push_str(&format!("select=not(mod(n\\,{})),", options.every));
        }
        filters.push_str("showinfo=checksum=0");
        command.args([
            "-map",
            "0:v:0",
            "-vf",
            &filters,
            "-fps_mode",
            "passthrough",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "gray",
            "-",
        ]);
        command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = command.spawn().map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => RecordingError::FfmpegMissing {
                path: path.to_path_buf(),
            },
            _ => RecordingError::Video {
                path: path.to_path_buf(),
                problem: format!("cannot start ffmpeg: {e}"),
            },
        })?;
        let stdout = child.stdout.take().expect("piped");
        let stderr = child.stderr.take().expect("piped");
        let (send, reports) = std::sync::mpsc::channel();
        let tail = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let time_base = std::sync::Arc::new(std::sync::Mutex::new(None));
        let damage = std::sync::Arc::new(std::sync::Mutex::new(None));
        {
            let (tail, time_base, damage) = (tail.clone(), time_base.clone(), damage.clone());
            let (every, window) = (options.every, (options.start_ns, options.end_ns));
            std::thread::spawn(move || {
                read_reports(stderr, &send, &tail, &time_base, &damage, every, window)
            });
        }
        Ok(VideoFrames {
            path: path.to_path_buf(),
            child,
            stdout,
            reports,
            tail,
            time_base,
            damage,
            every: options.every,
            expected: None,
            skipped: Skipped::default(),
            done: false,
        })
    }

    /// The frames ffmpeg expects to give (its duration times the frame
    /// rate, over the thinning), once it has said.
    pub fn expected(&self) -> Option<u64> {
        self.expected
    }

    /// Always none: a frame ffmpeg cannot decode ends the stream with its
    /// error.
    pub fn skipped(&self) -> &Skipped {
        &self.skipped
    }

    fn failure(&mut self, fallback: &str) -> RecordingError {
        let _ = self.child.kill();
        let _ = self.child.wait();
        RecordingError::Video {
            path: self.path.clone(),
            problem: self.problem(fallback),
        }
    }

    /// ffmpeg's own last words on the file, else `fallback`.
    fn problem(&self, fallback: &str) -> String {
        let tail = self.tail.lock().unwrap_or_else(|p| p.into_inner());
        // ffmpeg's advice for `-map 0:v:0` on a file without video ("add a
        // trailing '?' to the map") is about its command line, not the user's.
        if tail.iter().any(|line| line.contains("matches no streams")) {
            return "holds no video stream (sound only?)".to_string();
        }
        let name = self.path.display().to_string();
        tail.iter()
            .rev()
            .find(|line| !line.trim().is_empty())
            .map(|line| {
                // "run.mp4: Invalid data found when processing input": the
                // file is named once, by us.
                let line = line.trim();
                let line = line.strip_prefix(&format!("{name}: ")).unwrap_or(line);
                format!("ffmpeg cannot read it: {line}")
            })
            .unwrap_or_else(|| fallback.to_string())
    }

    fn next_frame(&mut self) -> Result<Option<Frame>, RecordingError> {
        let (n, pts, width, height) = loop {
            match self.reports.recv() {
                Ok(Report::Frame {
                    n,
                    pts,
                    width,
                    height,
                }) => break (n, pts, width, height),
                Ok(Report::Expected(frames)) => self.expected = Some(frames),
                // Standard error closed: ffmpeg is done.
                Err(_) => {
                    let status = self.child.wait().map_err(|e| RecordingError::Video {
                        path: self.path.clone(),
                        problem: format!("ffmpeg: {e}"),
                    })?;
                    let damage = self.damage.lock().unwrap_or_else(|p| p.into_inner()).take();
                    if let Some(line) = damage {
                        return Err(RecordingError::Video {
                            path: self.path.clone(),
                            problem: format!(
                                "truncated or damaged video: frames were read up to the damage \
                                 (ffmpeg: {})",
                                // "[mov,mp4,... @ 0x55ca64003900] stream 0, ...":
                                // the component and its address mean nothing here.
                                line.split_once("] ")
                                    .map_or(line.trim(), |(_, rest)| rest.trim())
                            ),
                        });
                    }
                    if status.success() {
                        return Ok(None);
                    }
                    return Err(self.failure("ffmpeg failed without saying why"));
                }
            }
        };
        // The size comes from ffmpeg's log, which also echoes the file's
        // own metadata: checked before it is allocated.
        let limit = crate::image_io::SizeLimit::FRAMES;
        if width == 0 || height == 0 || !limit.admits(width, height) {
            let _ = self.child.kill();
            let _ = self.child.wait();
            return Err(RecordingError::Video {
                path: self.path.clone(),
                problem: format!(
                    "ffmpeg reports frames of {width}x{height} pixels, outside 1 to {} px a side and {} megapixels",
                    limit.max_side,
                    limit.max_pixels / 1_000_000
                ),
            });
        }
        let mut pixels = vec![0u8; width as usize * height as usize];
        if self.stdout.read_exact(&mut pixels).is_err() {
            return Err(self.failure("the video ends inside a frame"));
        }
        let (num, den) = self
            .time_base
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .unwrap_or((1, 1_000_000_000));
        let stamp_ns = (i128::from(pts) * i128::from(num) * 1_000_000_000 / i128::from(den)) as i64;
        Ok(Some(Frame {
            index: n * self.every,
            stamp_ns,
            topic: None,
            frame_id: String::new(),
            image: GrayImage::from_raw(width, height, pixels).expect("width x height pixels"),
            camera: None,
        }))
    }
}

impl Iterator for VideoFrames {
    type Item = Result<Frame, RecordingError>;

    fn next(&mut self) -> Option<Self::Item> {
        let mut done = self.done;
        let result = super::fused(&mut done, || self.next_frame());
        self.done = done;
        result
    }
}

impl Drop for VideoFrames {
    fn drop(&mut self) {
        // A stream left early (an error downstream, --end reached by the
        // caller) leaves no ffmpeg behind.
        if !self.done {
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

/// ffmpeg's time syntax for nanoseconds: seconds with a decimal point.
fn seconds(ns: i64) -> String {
    format!("{}.{:09}", ns / 1_000_000_000, (ns % 1_000_000_000).abs())
}

/// What ffmpeg says of a file cut short (MP4, Matroska, AVI) before it
/// decodes what it can and exits with success anyway.
const TRUNCATED: [&str; 4] = [
    "partial file",
    "File ended prematurely",
    "Packet corrupt",
    "Truncating packet",
];

/// Reads ffmpeg's standard error: showinfo's frame lines and time base,
/// the duration and rate for the expected frame count, a truncated file's
/// first complaint, and the last lines for an error message.
fn read_reports(
    stderr: std::process::ChildStderr,
    send: &Sender<Report>,
    tail: &std::sync::Mutex<Vec<String>>,
    time_base: &std::sync::Mutex<Option<(i64, i64)>>,
    damage: &std::sync::Mutex<Option<String>>,
    every: u64,
    (start_ns, end_ns): (Option<i64>, Option<i64>),
) {
    let mut duration_s: Option<f64> = None;
    let mut told = false;
    for line in BufReader::new(stderr).split(b'\n') {
        let Ok(line) = line else { break };
        let line = String::from_utf8_lossy(&line).into_owned();
        if line.contains("Parsed_showinfo") {
            if let Some(base) = field(&line, "config in time_base:") {
                *time_base.lock().unwrap_or_else(|p| p.into_inner()) = ratio(base);
            } else if let (Some(n), Some(pts), Some(size)) = (
                field(&line, " n:"),
                field(&line, " pts:"),
                field(&line, " s:"),
            ) {
                let size = size.split_once('x');
                if let (Ok(n), Ok(pts), Some((Ok(w), Ok(h)))) = (
                    n.parse(),
                    pts.parse(),
                    size.map(|(w, h)| (w.parse(), h.parse())),
                ) {
                    if send
                        .send(Report::Frame {
                            n,
                            pts,
                            width: w,
                            height: h,
                        })
                        .is_err()
                    {
                        break;
                    }
                }
            }
            continue;
        }
        if TRUNCATED.iter().any(|t| line.contains(t)) {
            damage
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .get_or_insert_with(|| line.clone());
        }
        if let Some(d) = field(&line, "Duration:") {
            duration_s = clock(d.trim_end_matches(','));
        }
        if !told && line.trim_start().starts_with("Stream #0:") && line.contains("Video:") {
            let fps = line
                .split(',')
                .find_map(|part| part.trim().strip_suffix(" fps"))
                .and_then(|f| f.parse::<f64>().ok());
            let start = start_ns.unwrap_or(0) as f64 * 1e-9;
            let end = match end_ns {
                Some(end) => {
                    Some(duration_s.map_or(end as f64 * 1e-9, |d| d.min(end as f64 * 1e-9)))
                }
                None => duration_s,
            };
            if let (Some(fps), Some(end)) = (fps, end) {
                told = true;
                let frames = (fps * (end - start)).round().max(0.0) as u64;
                let _ = send.send(Report::Expected(frames.div_ceil(every.max(1))));
            }
        }
        let mut tail = tail.lock().unwrap_or_else(|p| p.into_inner());
        tail.push(line);
        if tail.len() > 20 {
            tail.remove(0);
        }
    }
}

/// The word after `key` in a line.
fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    let rest = &line[line.find(key)? + key.len()..];
    rest.split_whitespace().next()
}

/// "1/15360" as (1, 15360).
fn ratio(text: &str) -> Option<(i64, i64)> {
    let (num, den) = text.trim_end_matches(',').split_once('/')?;
    let (num, den) = (num.parse().ok()?, den.parse().ok()?);
    (den != 0).then_some((num, den))
}

/// "00:01:02.50" in seconds.
fn clock(text: &str) -> Option<f64> {
    let mut seconds = 0.0;
    for part in text.split(':') {
        seconds = seconds * 60.0 + part.parse::<f64>().ok()?;
    }
    Some(seconds)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn showinfo_lines_are_read() {
        let line = "[Parsed_showinfo_1 @ 0x5] n:  12 pts:  30720 pts_time:2       pos: 1 fmt:yuv420p sar:1/1 s:640x480 i:P";
        assert_eq!(field(line, " n:"), Some("12"));
        assert_eq!(field(line, " pts:"), Some("30720"));
        assert_eq!(field(line, " s:"), Some("640x480"));
        assert_eq!(ratio("1/15360,"), Some((1, 15360)));
        assert_eq!(clock("00:01:02.50"), Some(62.5));
        assert_eq!(seconds(2_500_000_000), "2.500000000");
    }
}
