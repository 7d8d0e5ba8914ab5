//! The original WhyCode detector as the bar measures it: CWhycon from the
//! public whycon-ros sources, built by `original/build.sh` with the small
//! driver `original/whycon_bar.cpp`, reading our markers on the same
//! frames. Found at `$WHYCON_BAR`, else `whycon_bar` in the target folder.
//! Building the original's ID table takes it up to minutes (16 bits), so
//! serving processes stay up for the whole run: one per image size, as its
//! detectors share one static pixel buffer sized by the first image.

use std::collections::hash_map::{Entry, HashMap};
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::Mutex;

use image::GrayImage;
use nalgebra::Vector3;
use serde::Deserialize;

use crate::rival::{parse_reports, write_frames, Rival, Setup};
use whycode::simulate::Sighting;
use whycode_testkit::scenario::Print;

pub struct Original {
    program: PathBuf,
    servers: Mutex<HashMap<(u32, u32), Server>>,
}

struct Server {
    child: Child,
    input: ChildStdin,
    output: BufReader<ChildStdout>,
}

impl Drop for Original {
    fn drop(&mut self) {
        if let Ok(servers) = self.servers.get_mut() {
            for (_, server) in servers.drain() {
                let Server {
                    mut child, input, ..
                } = server;
                drop(input);
                let _ = child.wait();
            }
        }
    }
}

#[derive(Deserialize)]
struct FrameReport {
    ms: f64,
    markers: Vec<MarkerReport>,
}

#[derive(Deserialize)]
struct MarkerReport {
    id: i32,
    u: f64,
    v: f64,
    angle: f64,
    x: f64,
    y: f64,
    z: f64,
    n: [f64; 3],
}

impl Original {
    /// The built driver, or why there is none.
    pub fn find() -> Result<Original, String> {
        let program = match std::env::var_os("WHYCON_BAR") {
            Some(p) => PathBuf::from(p),
            None => {
                let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(
                    || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"),
                    PathBuf::from,
                );
                target.join("whycon_bar")
            }
        };
        if program.is_file() {
            Ok(Original {
                program,
                servers: Mutex::new(HashMap::new()),
            })
        } else {
            Err(format!(
                "{} not built; see examples/detector_bar/original/build.sh",
                program.display()
            ))
        }
    }
}

impl Rival for Original {
    fn name(&self) -> &'static str {
        "original WhyCode"
    }

    fn print(&self) -> Print {
        Print::WhyCode
    }

    fn tracks(&self) -> bool {
        true
    }

    fn detect(
        &self,
        setup: &Setup,
        frames: &[&GrayImage],
    ) -> Result<Vec<(Vec<Sighting>, f64)>, String> {
        let camera = setup.camera;
        let dir = write_frames(frames)?;
        let mut args = vec![
            dir.path().display().to_string(),
            "--diameter".to_string(),
            setup.size_m.to_string(),
            "--markers".into(),
            setup.targets.max(1).to_string(),
            "--fx".into(),
            camera.fx.to_string(),
            "--fy".into(),
            camera.fy.to_string(),
            "--cx".into(),
            camera.cx.to_string(),
            "--cy".into(),
            camera.cy.to_string(),
        ];
        match setup.family {
            Some((bits, distance)) => args.extend([
                "--bits".into(),
                bits.to_string(),
                "--distance".into(),
                distance.to_string(),
            ]),
            None => args.push("--legacy".into()),
        }
        let size = frames.first().map_or((0, 0), |f| f.dimensions());
        let lines = self.request(size, &args.join(" "))?;
        let reports: Vec<FrameReport> =
            parse_reports(&self.program.display().to_string(), &lines, frames.len())?;
        Ok(reports
            .into_iter()
            .map(|r| (r.markers.iter().map(seen).collect(), r.ms))
            .collect())
    }
}

impl Original {
    /// Sends one request line to the serving process for frames of `size`
    /// (started on first use) and collects its frame lines up to the end
    /// mark.
    fn request(&self, size: (u32, u32), line: &str) -> Result<Vec<String>, String> {
        let name = self.program.display().to_string();
        let mut servers = self.servers.lock().map_err(|_| "server lock poisoned")?;
        let server = match servers.entry(size) {
            Entry::Occupied(e) => e.into_mut(),
            Entry::Vacant(e) => {
                let mut child = Command::new(&self.program)
                    .arg("--serve")
                    .stdin(Stdio::piped())
                    .stdout(Stdio::piped())
                    .spawn()
                    .map_err(|e| format!("{name}: {e}"))?;
                let input = child.stdin.take().ok_or("no stdin")?;
                let output = BufReader::new(child.stdout.take().ok_or("no stdout")?);
                e.insert(Server {
                    child,
                    input,
                    output,
                })
            }
        };
        writeln!(server.input, "{line}").map_err(|e| format!("{name}: {e}"))?;
        server.input.flush().map_err(|e| format!("{name}: {e}"))?;
        let mut lines = Vec::new();
        loop {
            let mut l = String::new();
            let n = server
                .output
                .read_line(&mut l)
                .map_err(|e| format!("{name}: {e}"))?;
            if n == 0 {
                if let Some(mut gone) = servers.remove(&size) {
                    let _ = gone.child.wait();
                }
                return Err(format!("{name} stopped"));
            }
            let l = l.trim();
            if l == r#"{"end": true}"# {
                return Ok(lines);
            }
            if l.starts_with('{') {
                lines.push(l.to_string());
            }
        }
    }
}

/// The original's report in our terms: IDs from 1 (0 unknown); its
/// normal points away from the camera, ours towards it; its position is
/// in the ROS body frame (x forward, y left, z up); it gives no in-plane
/// axes, so no full rotation.
fn seen(m: &MarkerReport) -> Sighting {
    let n = Vector3::from(m.n);
    Sighting {
        u: m.u,
        v: m.v,
        id: u32::try_from(m.id).ok().filter(|&id| id != 0),
        yaw: Some(m.angle),
        normal: (n.norm() > 0.0).then(|| -n.normalize()),
        rotation: None,
        position: Some(Vector3::new(-m.y, -m.z, m.x)),
    }
}
