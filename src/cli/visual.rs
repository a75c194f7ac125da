//! The outputs for people: `map.ply`, `run.mcap`, the PNG plots and
//! `report.md` (written when the run has finished).

use std::path::Path;

use anyhow::{Context, Result};
use specular::config::Config;
use specular::io;
use specular::pipeline::{PlaneOptimizedOutput, RunOutput};
use specular::reflect::BoundedPlane;
use specular::viz::{plots, report::Report, topdown};

use super::output::WrittenFrames;

/// Which optional outputs to write.
#[derive(Debug, Clone)]
pub(crate) struct VisualOptions {
    /// Write `run.mcap`.
    pub mcap: bool,
    /// Report title.
    pub title: String,
}

/// Write the map, plots and report into `out` (the recording was written
/// frame by frame, see [`RunWriter`](super::output::RunWriter)); returns
/// the files written (relative names with a description), the report last.
pub(crate) fn write_visual(
    out: &Path,
    config: &Config,
    frames: usize,
    run: &RunOutput,
    map: Option<&PlaneOptimizedOutput>,
    written: &WrittenFrames,
    options: &VisualOptions,
) -> Result<Vec<(String, String)>> {
    let mut files: Vec<(String, String)> = vec![
        (
            "predictions/".into(),
            "one `.label` file per frame (u32 class ids)".into(),
        ),
        ("config.toml".into(), "the configuration used".into()),
    ];
    let metrics = run.confusion.map(|c| c.metrics());
    if metrics.is_some() {
        files.push(("metrics.json".into(), "scores against the labels".into()));
    }
    if map.is_some() {
        files.push((
            "planes.json".into(),
            "reflective plane landmarks (world frame)".into(),
        ));
        files.push((
            "around_corner.ply".into(),
            "classified map with reflections mirrored back".into(),
        ));
    }
    let planes: &[BoundedPlane] = map.map(|m| m.planes.as_slice()).unwrap_or(&[]);
    let mut plot_list = Vec::new();

    if let Some(points) = &written.measured {
        let _span = tracing::info_span!("visual outputs").entered();
        io::write_map_ply(&out.join("map.ply"), points)?;
        files.push((
            "map.ply".into(),
            format!(
                "classified map, reflections where measured ({} points)",
                points.len()
            ),
        ));
        tracing::info!(points = points.len(), "map.ply written");

        if let Some(summary) = &written.mcap {
            tracing::info!(?summary, "run.mcap written");
            files.push((
                "run.mcap".into(),
                "Foxglove recording: /cloud, /mirrored, /planes, /tf, /trajectory".into(),
            ));
        }

        let trajectory = &written.trajectory;
        let top = topdown::topdown_png(
            &out.join("topdown.png"),
            points,
            planes,
            trajectory,
            config.output.topdown_slice(),
        )?;
        tracing::info!(
            floor = ?top.floor,
            left_out = top.outside_slice,
            "topdown.png written"
        );
        plot_list.push(("Top-down map".to_string(), "topdown.png".to_string()));
        plots::trajectory_png(
            &out.join("trajectory.png"),
            "Trajectory (world frame, top-down)",
            &[plots::TrajectorySeries {
                name: "poses".into(),
                colour: [0, 0, 0],
                width: 2,
                points: trajectory.iter().map(|p| [p[0], p[1]]).collect(),
            }],
        )?;
        plot_list.push(("Trajectory".to_string(), "trajectory.png".to_string()));
    }
    if let Some(m) = &metrics {
        plots::metrics_png(&out.join("metrics.png"), m)?;
        plot_list.push(("Per-class scores".to_string(), "metrics.png".to_string()));
    }
    for (_, f) in &plot_list {
        files.push((f.clone(), "plot".into()));
    }
    files.push(("report.md".into(), "this report".into()));

    let mut summary = vec![
        format!(
            "specular {} (commit {})",
            specular::VERSION,
            specular::GIT_COMMIT
        ),
        format!("{frames} frames, method {}", config.method.name()),
    ];
    if run.dropped_non_finite > 0 {
        summary.push(format!(
            "{} input points dropped: a coordinate or the intensity was NaN or infinite",
            run.dropped_non_finite
        ));
    }
    if let Some(m) = map {
        summary.push(format!(
            "plane map: {} landmarks, {} used ({})",
            m.map.landmarks.len(),
            m.used.len(),
            config.map.selection()
        ));
        summary.extend(m.mirror_lines());
        summary.extend(m.ghost_lines());
    }
    let report = Report {
        title: options.title.clone(),
        command_line: command_line(),
        config_toml: config.to_toml(),
        metrics: metrics.as_ref(),
        rules: Some(&run.rules),
        summary,
        plots: plot_list,
        files: files.clone(),
    };
    report
        .write(&out.join("report.md"))
        .context("writing report.md")?;
    Ok(files)
}

/// The command line of this process, shell-quoted where needed.
fn command_line() -> String {
    std::env::args()
        .map(|a| {
            if !a.is_empty()
                && a.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+".contains(c))
            {
                a
            } else {
                format!("'{}'", a.replace('\'', r"'\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// `OUT/report.md` of a run made of parts (each with its own report in a
/// subdirectory): links to the parts' reports and top-down maps.
pub(crate) fn write_index(
    out: &Path,
    title: &str,
    parts: &[(String, &str)],
    mcap: bool,
) -> Result<()> {
    let mut s = format!("# {title}\n\n");
    for (name, dir) in parts {
        let recording = if mcap {
            format!(", [Foxglove recording]({dir}/run.mcap)")
        } else {
            String::new()
        };
        s.push_str(&format!(
            "## {name}\n\n[report]({dir}/report.md){recording}, [map]({dir}/map.ply)\n\n![{name}]({dir}/topdown.png)\n\n"
        ));
    }
    s.push_str(&format!("Command line: `{}`\n", command_line()));
    io::write_atomic(&out.join("report.md"), |w| {
        std::io::Write::write_all(w, s.as_bytes())
    })?;
    Ok(())
}
