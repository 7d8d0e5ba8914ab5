//! The original WhyCode detector as the bar measures it: CWhycon from the
//! public whycon-ros sources, built by `original/build.sh` with the small
//! driver `original/whycon_bar.cpp`, reading our markers on the same
//! frames. Found at `$WHYCON_BAR`, else `whycon_bar` in the target folder.

use std::path::PathBuf;
use std::process::Command;

use image::GrayImage;
use nalgebra::Vector3;
use serde::Deserialize;

use crate::rival::{run_on_frames, Rival, Setup};
use crate::scenario::{Print, Seen};

pub struct Original {
    program: PathBuf,
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
            Ok(Original { program })
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

    fn detect(
        &self,
        setup: &Setup,
        frames: &[&GrayImage],
    ) -> Result<Vec<(Vec<Seen>, f64)>, String> {
        let camera = setup.camera;
        let mut args = vec![
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
        let reports: Vec<FrameReport> = run_on_frames(Command::new(&self.program), &args, frames)?;
        Ok(reports
            .into_iter()
            .map(|r| (r.markers.iter().map(seen).collect(), r.ms))
            .collect())
    }
}

/// The original's report in our terms: IDs from 1 (0 unknown); its
/// normal points away from the camera, ours towards it; it gives no
/// in-plane axes, so no full rotation.
fn seen(m: &MarkerReport) -> Seen {
    let n = Vector3::from(m.n);
    Seen {
        u: m.u,
        v: m.v,
        id: u32::try_from(m.id).ok().filter(|&id| id != 0),
        yaw: Some(m.angle),
        normal: (n.norm() > 0.0).then(|| -n.normalize()),
        rotation: None,
        position: Some(Vector3::new(m.x, m.y, m.z)),
    }
}
