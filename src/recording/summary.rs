//! A stream's tally for its end: frames read, the frames each ID was seen
//! in, and the IDs that came and went.

use super::Skipped;
use crate::detect::Detection;
use std::collections::BTreeMap;

/// What a stream showed, frame by frame.
#[derive(Debug, Clone, Default)]
pub struct Summary {
    frames: u64,
    first: Option<u64>,
    last: Option<u64>,
    unknown: u64,
    ids: BTreeMap<u32, Seen>,
}

#[derive(Debug, Clone, Copy)]
struct Seen {
    frames: u64,
    first: u64,
    last: u64,
}

impl Summary {
    /// Counts the frame `index` and its detections.
    pub fn observe(&mut self, index: u64, detections: &[Detection]) {
        self.frames += 1;
        self.first.get_or_insert(index);
        self.last = Some(index);
        let mut ids: Vec<u32> = detections.iter().map(|d| d.id).collect();
        self.unknown += ids.iter().filter(|&&id| id == 0).count() as u64;
        ids.retain(|&id| id != 0);
        ids.sort_unstable();
        ids.dedup();
        for id in ids {
            let seen = self.ids.entry(id).or_insert(Seen {
                frames: 0,
                first: index,
                last: index,
            });
            seen.frames += 1;
            seen.last = index;
        }
    }

    /// Frames counted.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Each ID and the number of frames it was seen in.
    pub fn frames_per_id(&self) -> BTreeMap<u32, u64> {
        self.ids.iter().map(|(&id, s)| (id, s.frames)).collect()
    }

    /// The summary in a few lines: frames read (and skipped), markers per
    /// ID, and the IDs not seen in every frame with the frames they were
    /// seen from and to.
    pub fn lines(&self, skipped: &Skipped) -> Vec<String> {
        let mut lines = Vec::new();
        let span = match (self.first, self.last) {
            (Some(a), Some(b)) => format!(" (frames {a} to {b})"),
            _ => String::new(),
        };
        let mut read = format!("read {} frame{}{span}", self.frames, plural(self.frames));
        if let Some((index, reason)) = &skipped.first {
            read.push_str(&format!(
                "; skipped {} that did not decode (first: frame {index}: {reason})",
                skipped.count
            ));
        }
        lines.push(read);
        if let Some(reason) = &skipped.first_refused_calibration {
            lines.push(format!(
                "refused {} camera_info message{} (first: {reason}); frames before a sound one have no poses",
                skipped.refused_calibrations,
                plural(skipped.refused_calibrations)
            ));
        }
        if self.ids.is_empty() {
            lines.push("no marker identified".into());
        } else {
            let per_id: Vec<String> = self
                .ids
                .iter()
                .map(|(id, s)| format!("{id}: {}", s.frames))
                .collect();
            lines.push(format!("frames per ID: {}", per_id.join(", ")));
        }
        if self.unknown > 0 {
            lines.push(format!("markers without ID: {}", self.unknown));
        }
        let came_and_went: Vec<String> = self
            .ids
            .iter()
            .filter(|(_, s)| s.frames < self.frames)
            .map(|(id, s)| format!("{id} (frames {} to {}, in {})", s.first, s.last, s.frames))
            .collect();
        if !came_and_went.is_empty() {
            lines.push(format!(
                "IDs that came and went: {}",
                came_and_went.join(", ")
            ));
        }
        lines
    }
}

fn plural(n: u64) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seen(ids: &[u32]) -> Vec<Detection> {
        ids.iter()
            .map(|&id| Detection {
                id,
                code: None,
                u: 0.0,
                v: 0.0,
                yaw: None,
                axes: [1.0, 1.0],
                angle: 0.0,
                confidence: 1.0,
                status: None,
                pose: None,
                bits: None,
                unreadable: false,
                unnamed: None,
                track: None,
            })
            .collect()
    }

    #[test]
    fn ids_that_come_and_go_are_named_with_their_frames() {
        let mut summary = Summary::default();
        summary.observe(0, &seen(&[1, 2]));
        summary.observe(5, &seen(&[1, 2, 3, 0]));
        summary.observe(10, &seen(&[1]));
        let lines = summary.lines(&Skipped::default());
        assert_eq!(lines[0], "read 3 frames (frames 0 to 10)");
        assert_eq!(lines[1], "frames per ID: 1: 3, 2: 2, 3: 1");
        assert_eq!(lines[2], "markers without ID: 1");
        assert_eq!(
            lines[3],
            "IDs that came and went: 2 (frames 0 to 5, in 2), 3 (frames 5 to 5, in 1)"
        );
    }
}
