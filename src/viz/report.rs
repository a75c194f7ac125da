//! `report.md`: a run summarised for people — metrics, plots, files, the
//! command line and the configuration.

use std::path::Path;

use crate::classify::RuleTally;
use crate::eval::Metrics;
use crate::io::write_atomic;
use crate::Result;

/// What a report shows.
#[derive(Debug, Clone, Default)]
pub struct Report<'a> {
    /// Title (first heading).
    pub title: String,
    /// The command line that produced the run.
    pub command_line: String,
    /// The effective configuration as TOML.
    pub config_toml: String,
    /// Scores, when the frames carry labels.
    pub metrics: Option<&'a Metrics>,
    /// Points by the rule that decided them, their prediction and label.
    pub rules: Option<&'a RuleTally>,
    /// Free lines shown under the title (frames, landmarks, ...).
    pub summary: Vec<String>,
    /// Plots: (caption, file name relative to the report).
    pub plots: Vec<(String, String)>,
    /// Files written (relative to the report) with a description.
    pub files: Vec<(String, String)>,
}

impl Report<'_> {
    /// The report as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = format!("# {}\n\n", self.title);
        for line in &self.summary {
            s.push_str(&format!("- {line}\n"));
        }
        if !self.summary.is_empty() {
            s.push('\n');
        }
        if let Some(m) = self.metrics {
            s.push_str("## Metrics\n\n| class | precision % | recall % | IoU % | truth | predicted |\n|---|---:|---:|---:|---:|---:|\n");
            for c in &m.classes {
                s.push_str(&format!(
                    "| {} | {:.2} | {:.2} | {:.2} | {} | {} |\n",
                    c.class.name(),
                    c.precision,
                    c.recall,
                    c.iou,
                    c.truth,
                    c.predicted
                ));
            }
            s.push_str(&format!(
                "\naccuracy {:.2} %, mIoU {:.2} %, non-reflection precision {:.2} %, indoor precision {:.2} %, reflection removal {:.2} %, unclassified {:.2} % ({} points, {} ignored)\n\n",
                m.accuracy,
                m.miou,
                m.non_reflection_precision,
                m.indoor_precision,
                m.reflection_removal,
                m.unclassified_share,
                m.points,
                m.ignored
            ));
            s.push_str("### Confusion matrix\n\nEvery point by its 3DRef label (rows) and the predicted class (columns), ignored labels included:\n\n");
            s.push_str(&m.confusion.label_table());
            s.push('\n');
        }
        if let Some(rules) = self.rules {
            s.push_str("## Which rule decided\n\nPoints by the rule of the decision procedure that gave them their class, the class given, and their 3DRef label (columns; all 0 for unlabelled frames). The Foxglove recording carries the rule of every point as the `rule` field of `/cloud` (ids in `classify::Rule`).\n\n");
            s.push_str(&rules.table());
            s.push('\n');
        }
        if !self.plots.is_empty() {
            s.push_str("## Plots\n\n");
            for (caption, file) in &self.plots {
                s.push_str(&format!("### {caption}\n\n![{caption}]({file})\n\n"));
            }
        }
        if !self.files.is_empty() {
            s.push_str("## Files\n\n| file | content |\n|---|---|\n");
            for (file, what) in &self.files {
                s.push_str(&format!("| [{file}]({file}) | {what} |\n"));
            }
            s.push('\n');
        }
        s.push_str(&format!(
            "## Command line\n\n```sh\n{}\n```\n\n## Configuration\n\n```toml\n{}\n```\n",
            self.command_line,
            self.config_toml.trim_end()
        ));
        s
    }

    /// Write the report (atomically).
    pub fn write(&self, path: &Path) -> Result<()> {
        let text = self.markdown();
        write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))
    }
}
