//! The verdict over all photos of a sheet: each printed marker's best
//! observation, per-page scale, counts, and the report as JSON or a table.

use super::photo::{MarkerStatus, PageCheck, PhotoReport};
use super::scale::{self, ScaleStatus};
use crate::manifest::Manifest;
use serde::Serialize;
use std::fmt::Write as _;

/// A printed marker's verdict over all photos.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MarkerVerdict {
    /// The printed ID.
    pub id: u32,
    /// The page it is printed on.
    pub page: u32,
    /// The best status any photo gave it.
    pub status: MarkerStatus,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// The ID it read as, when misread.
    pub read_as: Option<u32>,
    /// The photo that gave the verdict.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub photo: Option<String>,
}

/// A page's verdict over all photos.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PageVerdict {
    /// Page number, from 1.
    pub page: u32,
    /// Photos in which the page was located.
    pub photos: Vec<String>,
    /// Printed size / intended size, when some photo measured it.
    #[serde(serialize_with = "super::written::ratio_opt")]
    pub scale: Option<f64>,
    /// Whether that scale is within tolerance.
    pub scale_status: ScaleStatus,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// Why the scale is unknown, or a remark on it.
    pub note: Option<String>,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
/// How many printed markers ended in each status.
pub struct Counts {
    /// Markers on the sheet.
    pub printed: usize,
    /// Found and read as their own ID.
    pub found: usize,
    /// Read as another ID.
    pub misread: usize,
    /// Found, but the ring did not read.
    pub unidentified: usize,
    /// Never found (including not in view of any photo).
    pub missing: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
/// The verdict on a printed sheet over all its photos: what `whycode validate` prints and writes.
pub struct Report {
    /// Every marker found and right, and no page printed at a wrong scale.
    pub ok: bool,
    /// Markers per status.
    pub counts: Counts,
    /// Each page's verdict.
    pub pages: Vec<PageVerdict>,
    /// Each printed marker's verdict.
    pub markers: Vec<MarkerVerdict>,
    /// The per-photo checks the verdicts come from.
    pub photos: Vec<PhotoReport>,
}

/// Combines the photos: each marker keeps its best observation (a marker
/// read right in one photo is fine even if another photo was too blurred);
/// a marker never in view counts as missing.
pub fn summarise(manifest: &Manifest, photos: Vec<PhotoReport>) -> Report {
    let mut markers = Vec::new();
    let mut counts = Counts::default();
    for m in &manifest.markers {
        let best = photos
            .iter()
            .flat_map(|p| p.markers.iter().map(move |c| (p, c)))
            .filter(|(_, c)| c.id == m.id && c.page == m.page)
            .min_by_key(|(_, c)| c.status.rank());
        let verdict = match best {
            Some((p, c)) => MarkerVerdict {
                id: m.id,
                page: m.page,
                status: if c.status == MarkerStatus::NotInView {
                    MarkerStatus::Missing
                } else {
                    c.status
                },
                read_as: c.read_as,
                photo: (c.status != MarkerStatus::NotInView).then(|| p.photo.clone()),
            },
            None => MarkerVerdict {
                id: m.id,
                page: m.page,
                status: MarkerStatus::Missing,
                read_as: None,
                photo: None,
            },
        };
        counts.printed += 1;
        match verdict.status {
            MarkerStatus::Found => counts.found += 1,
            MarkerStatus::Misread => counts.misread += 1,
            MarkerStatus::Unidentified => counts.unidentified += 1,
            MarkerStatus::Missing | MarkerStatus::NotInView => counts.missing += 1,
        }
        markers.push(verdict);
    }
    let page_count = manifest
        .pages
        .max(manifest.markers.iter().map(|m| m.page).max().unwrap_or(0));
    let mut pages = Vec::new();
    for page in 1..=page_count {
        let checks: Vec<(&PhotoReport, &PageCheck)> = photos
            .iter()
            .flat_map(|p| p.pages.iter().map(move |c| (p, c)))
            .filter(|(_, c)| c.page == page)
            .collect();
        // The photo whose measurement decides the verdict speaks for the
        // page: its status, its figure and its note stay together.
        let severity = |status: ScaleStatus| match status {
            ScaleStatus::Error => 2,
            ScaleStatus::Warning => 1,
            _ => 0,
        };
        let deciding = checks
            .iter()
            .filter_map(|(p, c)| c.scale.scale.map(|s| (p, c, s)))
            .max_by(|a, b| {
                severity(a.1.scale.status)
                    .cmp(&severity(b.1.scale.status))
                    .then((a.2 - 1.0).abs().total_cmp(&(b.2 - 1.0).abs()))
            });
        let scale = deciding.map(|(_, _, s)| s);
        let (scale_status, note) = match deciding {
            Some((p, c, s)) => {
                let mut notes: Vec<String> = c.scale.note.iter().cloned().collect();
                let others: Vec<String> = checks
                    .iter()
                    .filter(|(q, _)| q.photo != p.photo)
                    .filter_map(|(q, c)| c.scale.scale.map(|t| (q, t)))
                    .filter(|(_, t)| (t - s).abs() > scale::SCALE_WARNING)
                    .map(|(q, t)| format!("{} measured {:.1} %", q.photo, t * 100.0))
                    .collect();
                if !others.is_empty() {
                    notes.push(format!(
                        "photos disagree: {} measured {:.1} %, {}",
                        p.photo,
                        s * 100.0,
                        others.join(", ")
                    ));
                }
                (
                    c.scale.status,
                    (!notes.is_empty()).then(|| notes.join("; ")),
                )
            }
            _ if checks.is_empty() => (
                ScaleStatus::Unknown,
                Some("page not located in any photo".to_string()),
            ),
            _ => (
                ScaleStatus::Unknown,
                Some(
                    checks
                        .iter()
                        .filter_map(|(p, c)| {
                            c.scale.note.as_ref().map(|n| format!("{}: {n}", p.photo))
                        })
                        .collect::<Vec<_>>()
                        .join("; "),
                ),
            ),
        };
        pages.push(PageVerdict {
            page,
            photos: checks.iter().map(|(p, _)| p.photo.clone()).collect(),
            scale,
            scale_status,
            note,
        });
    }
    let scale_ok = pages
        .iter()
        .all(|p| matches!(p.scale_status, ScaleStatus::Ok | ScaleStatus::Unknown));
    Report {
        ok: counts.found == counts.printed && scale_ok,
        counts,
        pages,
        markers,
        photos,
    }
}

impl Report {
    /// The report as the JSON `whycode validate` writes.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("report serialises");
        s.push('\n');
        s
    }

    /// A readable summary: pages with their scale, then every marker that
    /// is not right, then the totals.
    pub fn to_table(&self) -> String {
        let mut out = String::new();
        for photo in &self.photos {
            let pages: Vec<String> = photo.pages.iter().map(|p| p.page.to_string()).collect();
            let _ = writeln!(
                out,
                "{}: {}x{}, {} markers detected, page(s) located: {}",
                photo.photo,
                photo.width,
                photo.height,
                photo.detections,
                if pages.is_empty() {
                    "none".to_string()
                } else {
                    pages.join(", ")
                }
            );
        }
        let _ = writeln!(out);
        let _ = writeln!(out, "page  scale     status   note");
        for p in &self.pages {
            let scale = p
                .scale
                .map_or("-".to_string(), |s| format!("{:.1} %", s * 100.0));
            let status = match p.scale_status {
                ScaleStatus::Ok => "ok",
                ScaleStatus::Warning => "WARNING",
                ScaleStatus::Error => "ERROR",
                ScaleStatus::Unknown => "unknown",
            };
            let mut note = p.note.clone().unwrap_or_default();
            if let Some(s) = p.scale {
                if p.scale_status != ScaleStatus::Ok {
                    let measured = format!("printed at {:.1} % of the intended size", s * 100.0);
                    note = if note.is_empty() {
                        measured
                    } else {
                        format!("{measured}; {note}")
                    };
                }
            }
            let _ = writeln!(
                out,
                "{:<5} {:<9} {:<8} {}",
                p.page,
                scale,
                status,
                note.trim()
            );
        }
        for photo in &self.photos {
            for page in &photo.pages {
                for odd in &page.odd_sizes {
                    let _ = writeln!(
                        out,
                        "note: {}: marker {} on page {} is {:+.0} % the size of its neighbours",
                        photo.photo,
                        odd.id,
                        page.page,
                        (odd.relative_size - 1.0) * 100.0
                    );
                }
            }
            for note in &photo.notes {
                let _ = writeln!(out, "note: {}: {note}", photo.photo);
            }
            for stray in &photo.stray {
                let _ = writeln!(
                    out,
                    "note: {}: a marker reading as ID {} at ({:.0}, {:.0}) on page {} is not in the manifest there",
                    photo.photo, stray.id, stray.u, stray.v, stray.page
                );
            }
        }
        let problems: Vec<&MarkerVerdict> = self
            .markers
            .iter()
            .filter(|m| m.status != MarkerStatus::Found)
            .collect();
        if !problems.is_empty() {
            let _ = writeln!(out);
            let _ = writeln!(out, "id     page  status        detail");
            for m in problems {
                let page_located = self
                    .photos
                    .iter()
                    .any(|p| p.pages.iter().any(|c| c.page == m.page));
                let detail = match (m.status, m.read_as, &m.photo) {
                    (MarkerStatus::Misread, Some(r), Some(p)) => format!("read as ID {r} in {p}"),
                    (_, _, Some(p)) => format!("in {p}"),
                    _ if !page_located => format!("page {} was not found in any photo", m.page),
                    _ => "its place was not in any photo".to_string(),
                };
                let _ = writeln!(
                    out,
                    "{:<6} {:<5} {:<13} {}",
                    m.id,
                    m.page,
                    m.status.label(),
                    detail
                );
            }
        }
        let c = &self.counts;
        let _ = writeln!(out);
        let unmeasured: Vec<String> = self
            .pages
            .iter()
            .filter(|p| p.scale_status == ScaleStatus::Unknown)
            .map(|p| p.page.to_string())
            .collect();
        // Every marker reading right is the verdict; an unmeasured scale is
        // not a failure, but "OK" alone would read as "the size was checked".
        let verdict = match (self.ok, unmeasured.is_empty()) {
            (false, _) => "PROBLEMS".to_string(),
            (true, true) => "OK".to_string(),
            (true, false) => format!(
                "OK, but the printed scale of page {} was not measured",
                unmeasured.join(", ")
            ),
        };
        let _ = writeln!(
            out,
            "{} printed: {} found, {} misread, {} unidentified, {} missing -> {}",
            c.printed, c.found, c.misread, c.unidentified, c.missing, verdict
        );
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::manifest::FamilyRef;
    use crate::manifest::PrintedMarker;
    use crate::validate::photo::{not_in_view, MarkerCheck};

    #[test]
    fn best_observation_over_photos_wins() {
        let manifest = Manifest {
            format: "whycode-sheet".into(),
            version: 1,
            tool: String::new(),
            family: Some(FamilyRef {
                bits: 8,
                distance: 2,
            }),
            legacy: false,
            template: String::new(),
            page_size_mm: [100.0, 100.0],
            pages: 1,
            files: Vec::new(),
            markers: vec![PrintedMarker {
                id: 3,
                code: 11,
                page: 1,
                x_mm: 50.0,
                y_mm: 50.0,
                diameter_mm: 40.0,
            }],
        };
        let photo = |name: &str, status| PhotoReport {
            photo: name.into(),
            width: 10,
            height: 10,
            detections: 1,
            pages: Vec::new(),
            markers: vec![MarkerCheck {
                status,
                ..not_in_view(&manifest.markers[0], (1.0, 1.0))
            }],
            stray: Vec::new(),
            notes: Vec::new(),
        };
        let report = summarise(
            &manifest,
            vec![
                photo("a", MarkerStatus::Unidentified),
                photo("b", MarkerStatus::Found),
            ],
        );
        assert!(report.ok);
        assert_eq!(report.markers[0].photo.as_deref(), Some("b"));
        let report = summarise(&manifest, vec![photo("a", MarkerStatus::NotInView)]);
        assert!(!report.ok);
        assert_eq!(report.markers[0].status, MarkerStatus::Missing);
    }
}
