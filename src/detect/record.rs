//! The JSON record of a detection, shared by `whycode detect --format json`
//! and the bindings (a Python `Marker.as_dict()` is this object), so every
//! caller sees the same fields, order and rounding.

use super::Detection;

/// Rounds to `decimals` places: the printed precision of each field is part
/// of the documented output (pixels to 1/1000, angles and metres to 1e-5).
pub fn round(x: f64, decimals: i32) -> f64 {
    let k = 10f64.powi(decimals);
    (x * k).round() / k
}

/// One image's detections, fields in the documented order.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FrameRecord {
    pub image: String,
    pub width: u32,
    pub height: u32,
    pub elapsed_ms: f64,
    pub markers: Vec<MarkerRecord>,
}

/// One marker, rounded as printed.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MarkerRecord {
    pub id: u32,
    pub code: Option<u32>,
    pub u: f64,
    pub v: f64,
    pub yaw: Option<f64>,
    pub axes: [f64; 2],
    pub confidence: f64,
    pub position: Option<[f64; 3]>,
    pub rotation: Option<[[f64; 3]; 3]>,
    pub quaternion: Option<[f64; 4]>,
}

impl MarkerRecord {
    pub fn of(m: &Detection) -> MarkerRecord {
        let pose = m.pose.as_ref();
        MarkerRecord {
            id: m.id,
            code: m.code,
            u: round(m.u, 3),
            v: round(m.v, 3),
            yaw: m.yaw.map(|y| round(y, 5)),
            axes: [round(m.axes[0], 3), round(m.axes[1], 3)],
            confidence: round(m.confidence, 3),
            position: pose.map(|p| {
                [
                    round(p.position.x, 5),
                    round(p.position.y, 5),
                    round(p.position.z, 5),
                ]
            }),
            rotation: pose.map(|p| {
                std::array::from_fn(|r| std::array::from_fn(|c| round(p.rotation[(r, c)], 6)))
            }),
            quaternion: pose.map(|p| p.quaternion.map(|q| round(q, 6))),
        }
    }

    /// The record as one JSON object.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("plain records serialise")
    }
}

impl FrameRecord {
    pub fn new(
        image: String,
        width: u32,
        height: u32,
        elapsed_ms: f64,
        markers: &[Detection],
    ) -> FrameRecord {
        FrameRecord {
            image,
            width,
            height,
            elapsed_ms: round(elapsed_ms, 3),
            markers: markers.iter().map(MarkerRecord::of).collect(),
        }
    }

    /// The record as one line of JSON (what `whycode detect --format json`
    /// prints per image).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("plain records serialise")
    }
}
