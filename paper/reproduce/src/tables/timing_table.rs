//! The machine-dependent timing table (`timings.md`): milliseconds per
//! frame and stage of each timed run, beside the original code's figures.

use std::fmt::Write as _;

use crate::published::ORIGINAL_CODE_MS;
use crate::timing::TimingReport;

/// The machine-dependent timing table, with the original code's figures.
/// `load` is the system's load average at the end of the run, when known
/// (the machine may be shared).
pub fn timing_markdown(
    report: &TimingReport,
    total_wall_s: f64,
    load: Option<&str>,
    command: &str,
) -> String {
    let mut stages: Vec<String> = Vec::new();
    for r in &report.rows {
        for (name, _) in &r.stages_ms {
            if !stages.contains(name) {
                stages.push(name.clone());
            }
        }
    }
    let mut s = format!(
        "Machine-dependent (this run, {} threads available), milliseconds per frame on `{}`, median of {} runs. Produced by `{command}`.\n\n| stage |",
        report.threads_available,
        report.data,
        report.rows.first().map_or(0, |r| r.repeats)
    );
    for r in &report.rows {
        let _ = write!(
            s,
            " {}, {} thread{} |",
            r.method,
            r.threads,
            if r.threads == 1 { "" } else { "s" }
        );
    }
    s.push_str(" original code (one pass) |\n|---|");
    for _ in &report.rows {
        s.push_str("---:|");
    }
    s.push_str("---:|\n");
    let (algo, parse, two_pass) = ORIGINAL_CODE_MS;
    for name in &stages {
        let _ = write!(s, "| {name} |");
        for r in &report.rows {
            let v = r.stages_ms.iter().find(|(n, _)| n == name).map(|(_, v)| *v);
            let _ = write!(s, " {} |", v.map_or("–".into(), |v| format!("{v:.2}")));
        }
        let original = if name == "parse" {
            format!("{parse:.0}")
        } else {
            String::new()
        };
        let _ = writeln!(s, " {original} |");
    }
    s.push_str("| **wall per frame (parse included)** |");
    for r in &report.rows {
        let _ = write!(s, " **{:.2}** |", r.wall_ms);
    }
    let _ = writeln!(
        s,
        " {algo:.0} + {parse:.0} per pass; ≈ {two_pass:.0} for its two passes |"
    );
    let _ = writeln!(
        s,
        "\nStage times are CPU time summed over the workers; the wall row is elapsed time. The whole `{command}` took {total_wall_s:.0} s of wall time{}.",
        load.map_or(String::new(), |l| format!(
            " (load average at the end: {l}, on {} threads)",
            report.threads_available
        ))
    );
    s
}
