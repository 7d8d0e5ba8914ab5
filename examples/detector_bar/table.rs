//! The bar's table: per item our figure, the rivals' measured on the same
//! scenes in the same run (AprilTag, the original WhyCode, and on the
//! defocus row OpenCV's ArUco; the original's figure as quoted in issue 9
//! where it could not be run), and whether ours passes (meets the item's
//! target and is no worse than any rival).

use whycode_testkit::tally::Counts;

/// The rivals' columns, in this order.
pub const RIVALS: [&str; 3] = ["AprilTag", "original WhyCode", "ArUco 4x4"];

/// Rival figures of one row, in [`RIVALS`] order; `None`: not measured.
pub type Cells = [Option<String>; 3];

pub struct Row {
    item: String,
    ours: String,
    theirs: [String; 3],
    pass: bool,
}

pub struct Table {
    rows: Vec<Row>,
    /// Which rivals could not be run at all.
    missing: [bool; 3],
}

impl Table {
    pub fn new(missing: [bool; 3]) -> Table {
        Table {
            rows: Vec::new(),
            missing,
        }
    }

    /// A row; `quoted` is the original's figure from issue 9, shown where
    /// the original was not measured ("" if the issue gives none).
    pub fn row(&mut self, item: &str, ours: String, theirs: Cells, quoted: &str, pass: bool) {
        let [apriltag, original, aruco] = theirs;
        let missing = |k: usize| if self.missing[k] { "not measured" } else { "-" };
        let apriltag = apriltag.unwrap_or_else(|| missing(0).into());
        let original = original.unwrap_or_else(|| match quoted {
            "" => missing(1).into(),
            q => format!("quoted (issue 9): {q}"),
        });
        let aruco = aruco.unwrap_or_else(|| missing(2).into());
        println!("  {item}: {ours}  [{}]", if pass { "pass" } else { "FAIL" });
        let theirs = [apriltag, original, aruco];
        for (name, figure) in RIVALS.iter().zip(&theirs) {
            println!("    {name}: {figure}");
        }
        self.rows.push(Row {
            item: item.to_string(),
            ours,
            theirs,
            pass,
        });
    }

    pub fn note(&mut self, s: String) {
        println!("    {s}");
    }

    /// The table as Markdown (also readable in a terminal), and the tally.
    pub fn print(&self) {
        println!();
        println!(
            "| item | ours | {} (same scenes) | {} (same frames) | {} (same scenes) | result |",
            RIVALS[0], RIVALS[1], RIVALS[2]
        );
        println!("| --- | --- | --- | --- | --- | --- |");
        for r in &self.rows {
            println!(
                "| {} | {} | {} | {} | {} | {} |",
                r.item,
                r.ours,
                r.theirs[0],
                r.theirs[1],
                r.theirs[2],
                if r.pass { "pass" } else { "FAIL" }
            );
        }
        let failed = self.rows.iter().filter(|r| !r.pass).count();
        println!(
            "\n{} of {} items pass",
            self.rows.len() - failed,
            self.rows.len()
        );
    }
}

/// Each rival's figure, where measured.
pub fn cells<T>(theirs: &[Option<T>], show: impl Fn(&T) -> String) -> Cells {
    [0, 1, 2].map(|k| theirs.get(k).and_then(|t| t.as_ref()).map(&show))
}

/// Ours no worse than every measured rival by `better`.
pub fn beats<T>(ours: &T, theirs: &[Option<T>], better: impl Fn(&T, &T) -> bool) -> bool {
    theirs.iter().flatten().all(|t| better(ours, t))
}

/// Ours at least as many right IDs as every measured rival.
pub fn beats_ids(ours: &Counts, theirs: &[Option<Counts>]) -> bool {
    beats(ours, theirs, |o, t| o.correct_id >= t.correct_id)
}

pub fn pct(x: f64) -> String {
    format!("{:.1}%", 100.0 * x)
}

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
