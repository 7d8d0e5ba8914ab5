//! `whycode ids`: a family's IDs and codes, or the count matrix.

use super::args::{spec_error, Format, FormatArg};
use super::output;
use anyhow::{bail, Result};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use whycode::family::{CountTable, Family, MAX_BITS};
use whycode::spec::{Bits, TargetSpec};

const EXAMPLES: &str = "\
Examples:
  whycode ids                                        # 8 bits, distance 2: 16 IDs
  whycode ids --bits 12 --distance 3 --format csv
  whycode ids --bits 12 --distance 3 --format json -o family.json
  whycode ids --family family.json                   # check and show a saved family
  whycode ids --counts --bits 4..16:2 --distance 1..4

The json format is the family file a lab keeps to pin its family.";

#[derive(Debug, clap::Args)]
#[command(after_help = EXAMPLES)]
pub struct IdsArgs {
    /// Code length in bits, 2 to 24 [default: 8]. With --counts, a list of
    /// values: 12, 4..16 or 4..=16 (both ends included), 4..16:2 (every
    /// second), or several joined by commas [default: 4..16:2]
    #[arg(long, short = 'b', value_name = "BITS", allow_hyphen_values = true)]
    bits: Option<String>,

    /// Minimum cyclic Hamming distance between IDs, 1 to the bit count
    /// [default: 2, which detects any single misread bit; 3 corrects it].
    /// With --counts, a list like --bits [default: 1..4]
    #[arg(long, short = 'd', value_name = "D", allow_hyphen_values = true)]
    distance: Option<String>,

    /// Print the number of IDs for every bit length and distance instead of
    /// one family's codes
    #[arg(long)]
    counts: bool,

    /// Show and check the family stored in a family file (as written by
    /// --format json) instead of generating one
    #[arg(long, value_name = "FILE")]
    family: Option<PathBuf>,

    #[command(flatten)]
    format: FormatArg,

    /// Write to FILE (whole or not at all) instead of standard output
    #[arg(long, short = 'o', value_name = "FILE")]
    output: Option<PathBuf>,
}

pub fn run(args: IdsArgs) -> Result<ExitCode> {
    let format = args.format.format;
    let text = if args.counts {
        if args.family.is_some() {
            bail!("--counts and --family cannot be used together");
        }
        let bits = parse_list(args.bits.as_deref().unwrap_or("4..16:2"), "--bits")?;
        let distances = parse_list(args.distance.as_deref().unwrap_or("1..4"), "--distance")?;
        counts_text(&bits, &distances, format)?
    } else {
        if args.family.is_some() && (args.bits.is_some() || args.distance.is_some()) {
            bail!("--family takes bits and distance from the file; drop --bits and --distance");
        }
        let family = TargetSpec {
            bits: parse_single(args.bits.as_deref(), "--bits")?.map(Bits::Count),
            distance: parse_single(args.distance.as_deref(), "--distance")?,
            family_file: args.family.clone(),
            ..TargetSpec::default()
        }
        .family()
        .map_err(spec_error)?;
        family_text(&family, format)
    };
    match &args.output {
        Some(path) => {
            let inputs: Vec<&std::path::Path> = args.family.as_deref().into_iter().collect();
            whycode::io::check_outputs(&inputs, &[path])?;
            whycode::io::write_atomic(path, text.as_bytes())?
        }
        None => output::print(&text)?,
    }
    Ok(ExitCode::SUCCESS)
}

fn parse_single(text: Option<&str>, option: &str) -> Result<Option<u32>> {
    let Some(text) = text else {
        return Ok(None);
    };
    match text.trim().parse::<u32>() {
        Ok(value) => Ok(Some(value)),
        Err(_) if text.contains("..") || text.contains(',') => {
            bail!("{option}: '{text}' is a list; lists need --counts")
        }
        Err(_) if !text.trim().is_empty() && text.trim().bytes().all(|b| b.is_ascii_digit()) => {
            bail!("{option}: {text} is far above {MAX_BITS}, the most bits a family can have")
        }
        Err(_) => bail!("{option}: '{text}' is not a whole number"),
    }
}

/// Parses `8`, `4..16`, `4..=16`, `4..16:2` and comma-joined lists of
/// those into sorted, distinct values. Both range ends are included, as in
/// the spec's table `--bits 4..16`.
fn parse_list(text: &str, option: &str) -> Result<Vec<u32>> {
    let malformed = |item: &str| {
        anyhow::anyhow!(
            "{option}: '{item}' is not a number or range (write 8, 4..16, 4..=16, 4..16:2 or 4,8,12)"
        )
    };
    let number = |s: &str, item: &str| s.trim().parse::<u32>().map_err(|_| malformed(item));
    let mut values = Vec::new();
    for item in text.split(',') {
        let item = item.trim();
        match item.split_once("..") {
            None => values.push(number(item, item)?),
            Some((start, rest)) => {
                let rest = rest.strip_prefix('=').unwrap_or(rest);
                let (end, step) = match rest.split_once(':') {
                    Some((end, step)) => (end, number(step, item)?),
                    None => (rest, 1),
                };
                let (start, end) = (number(start, item)?, number(end, item)?);
                if step == 0 {
                    bail!("{option}: '{item}' has step 0");
                }
                if start > end {
                    bail!("{option}: range '{item}' is empty (its start is above its end)");
                }
                // Neither bits nor distance can exceed MAX_BITS; refusing here
                // keeps a range like 1..4294967295 from being expanded at all.
                if end > MAX_BITS {
                    bail!("{option}: range '{item}' goes past {MAX_BITS}, the most bits a family can have");
                }
                values.extend((start..=end).step_by(step as usize));
            }
        }
    }
    values.sort_unstable();
    values.dedup();
    Ok(values)
}

fn family_text(family: &Family, format: Format) -> String {
    let bits = family.bits() as usize;
    let self_distances = family.self_distances();
    match format {
        Format::Json => family.to_json(),
        Format::Csv => {
            let mut out = String::from("id,code,binary,self_distance\n");
            for (k, (&code, sd)) in family.codes().iter().zip(&self_distances).enumerate() {
                let _ = writeln!(out, "{},{code},{code:0bits$b},{sd}", k + 1);
            }
            out
        }
        Format::Table => {
            let min_distance = match family.min_distance() {
                Some(d) => d.to_string(),
                None => "- (a single ID)".to_string(),
            };
            let worst_self = self_distances.iter().min().copied().unwrap_or(0);
            let mut out = String::new();
            let _ = writeln!(
                out,
                "# {} {}, {} bits, distance {}: min distance {min_distance}, worst self-distance {worst_self}",
                family.len(),
                if family.len() == 1 { "ID" } else { "IDs" },
                family.bits(),
                family.distance()
            );
            let id_width = family.len().to_string().len().max(2);
            let max_code = family.codes().iter().max().copied().unwrap_or(0);
            let code_width = max_code.to_string().len().max(4);
            let binary_width = bits.max(6);
            let _ = writeln!(
                out,
                "{:>id_width$}  {:>code_width$}  {:<binary_width$}  self_distance",
                "id", "code", "binary"
            );
            for (k, (&code, sd)) in family.codes().iter().zip(&self_distances).enumerate() {
                let binary = format!("{code:0bits$b}");
                let _ = writeln!(
                    out,
                    "{:>id_width$}  {code:>code_width$}  {binary:<binary_width$}  {sd:>13}",
                    k + 1
                );
            }
            out
        }
    }
}

fn counts_text(bits: &[u32], distances: &[u32], format: Format) -> Result<String> {
    let counts = CountTable::new(bits, distances)
        .map_err(|e| spec_error(e.into()))?
        .counts;
    let cell = |c: Option<usize>| c.map_or("-".to_string(), |c| c.to_string());
    let mut out = String::new();
    match format {
        Format::Table => {
            let width = counts
                .iter()
                .flatten()
                .map(|&c| cell(c).len())
                .chain(bits.iter().map(|n| n.to_string().len()))
                .max()
                .unwrap_or(1);
            let _ = write!(out, "{:<5}", "d \\ n");
            for n in bits {
                let _ = write!(out, "  {n:>width$}");
            }
            out.push('\n');
            for (&d, row) in distances.iter().zip(&counts) {
                let _ = write!(out, "{d:<5}");
                for &c in row {
                    let _ = write!(out, "  {:>width$}", cell(c));
                }
                out.push('\n');
            }
        }
        Format::Csv => {
            out.push_str("bits,distance,count\n");
            for (&d, row) in distances.iter().zip(&counts) {
                for (&n, &c) in bits.iter().zip(row) {
                    if let Some(c) = c {
                        let _ = writeln!(out, "{n},{d},{c}");
                    }
                }
            }
        }
        Format::Json => {
            let join = |v: Vec<String>| v.join(", ");
            out.push_str("{\n  \"format\": \"whycode-counts\",\n  \"version\": 1,\n");
            let _ = writeln!(
                out,
                "  \"bits\": [{}],",
                join(bits.iter().map(u32::to_string).collect())
            );
            let _ = writeln!(
                out,
                "  \"distances\": [{}],",
                join(distances.iter().map(u32::to_string).collect())
            );
            out.push_str("  \"counts\": [\n");
            for (k, row) in counts.iter().enumerate() {
                let cells = row
                    .iter()
                    .map(|c| c.map_or("null".to_string(), |c| c.to_string()))
                    .collect();
                let separator = if k + 1 == counts.len() { "" } else { "," };
                let _ = writeln!(out, "    [{}]{separator}", join(cells));
            }
            out.push_str("  ]\n}\n");
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_and_ranges() {
        assert_eq!(parse_list("8", "--bits").unwrap(), vec![8]);
        assert_eq!(parse_list("4..8", "--bits").unwrap(), vec![4, 5, 6, 7, 8]);
        assert_eq!(parse_list("4..=8", "--bits").unwrap(), vec![4, 5, 6, 7, 8]);
        assert_eq!(parse_list("4..16:4", "--bits").unwrap(), vec![4, 8, 12, 16]);
        assert_eq!(parse_list("4..=9:2", "--bits").unwrap(), vec![4, 6, 8]);
        assert_eq!(
            parse_list("12, 4..6,5", "--bits").unwrap(),
            vec![4, 5, 6, 12]
        );
        for bad in [
            "", "4..", "..4", "a..b", "4...8", "8..4", "4..8:0", "4..8:", "-1", "4;8",
        ] {
            let err = parse_list(bad, "--bits").unwrap_err().to_string();
            assert!(err.starts_with("--bits: "), "{bad}: {err}");
        }
    }
}
