//! The bar's table: per item our figure, AprilTag's measured on the same
//! scenes in the same run, the original WhyCode's as quoted, and whether
//! ours passes (meets the item's target and beats AprilTag's figure).

pub struct Row {
    item: String,
    ours: String,
    apriltag: String,
    original: String,
    pass: bool,
}

pub struct Table {
    rows: Vec<Row>,
    /// AprilTag could not be run: every AprilTag cell says so.
    apriltag_missing: bool,
}

impl Table {
    pub fn new(apriltag_missing: bool) -> Table {
        Table {
            rows: Vec::new(),
            apriltag_missing,
        }
    }

    /// A row; `apriltag` is `None` when AprilTag was not measured on it
    /// (not installed, or the row has no AprilTag counterpart: then `-`).
    pub fn row(
        &mut self,
        item: &str,
        ours: String,
        apriltag: Option<String>,
        original: &str,
        pass: bool,
    ) {
        let apriltag = apriltag.unwrap_or_else(|| {
            if self.apriltag_missing {
                "not measured".into()
            } else {
                "-".into()
            }
        });
        println!("  {item}: {ours}  [{}]", if pass { "pass" } else { "FAIL" });
        println!("    AprilTag: {apriltag}");
        self.rows.push(Row {
            item: item.to_string(),
            ours,
            apriltag,
            original: original.to_string(),
            pass,
        });
    }

    pub fn note(&mut self, s: String) {
        println!("    {s}");
    }

    /// The table as Markdown (also readable in a terminal), and the tally.
    pub fn print(&self) {
        println!();
        println!("| item | ours | AprilTag (measured, same scenes) | original WhyCode (quoted) | result |");
        println!("| --- | --- | --- | --- | --- |");
        for r in &self.rows {
            println!(
                "| {} | {} | {} | {} | {} |",
                r.item,
                r.ours,
                r.apriltag,
                r.original,
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

pub fn pct(x: f64) -> String {
    format!("{:.1}%", 100.0 * x)
}

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
