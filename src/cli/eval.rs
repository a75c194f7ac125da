//! `specular eval`: score predictions against labelled frames.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use specular::classify::Class;
use specular::eval::{Confusion, Reliability};
use specular::io;

/// Arguments of `eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Directory of labelled 3DRef frames.
    #[arg(long)]
    pub frames: PathBuf,
    /// Directory of `<stem>.label` predictions (or a run directory holding
    /// `predictions/`). A `<stem>.prob` beside a label file (one
    /// little-endian f32 per point, the confidence of its class) is read
    /// too, and the calibration of the confidences reported.
    #[arg(long)]
    pub pred: PathBuf,
    /// Also write the metrics as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Whether `id` is one a prediction file may hold: a class id (0 to 6).
fn is_class_id(id: u32) -> bool {
    id <= 6
}

/// Run `eval`.
pub fn run(args: EvalArgs) -> Result<()> {
    let pred_dir = if args.pred.join("predictions").is_dir() {
        args.pred.join("predictions")
    } else {
        args.pred.clone()
    };
    let entries = io::list_frames(&args.frames)?;
    let mut conf = Confusion::default();
    let mut reliability = Reliability::default();
    // Frames with a `.prob` file beside their labels.
    let mut with_probs = 0usize;
    for e in &entries {
        // Scored against every input point: the labels of the points the
        // reader set aside (not finite, at the origin) are put back in
        // place, where a prediction file holds 0.
        let (frame, aside) = io::read_frame_full(&e.path)?;
        if !frame.has_labels {
            bail!(
                "{}: frame has no 'label' property, nothing to score against",
                e.path.display()
            );
        }
        let pred_path = pred_dir.join(format!("{}.label", e.name));
        if !pred_path.exists() {
            bail!(
                "{}: missing prediction for frame {}",
                pred_path.display(),
                e.name
            );
        }
        let pred = io::read_labels(&pred_path)?;
        let points = frame.points.len() + aside.len();
        if pred.len() != points {
            bail!(
                "{}: {} predictions for {} points in {} (one per input point)",
                pred_path.display(),
                pred.len(),
                points,
                e.path.display()
            );
        }
        if let Some((i, bad)) = pred.iter().enumerate().find(|(_, &id)| !is_class_id(id)) {
            bail!(
                "{}: point {i} has label {bad}, not a class id (0 unclassified, 1 normal, 2 reflective surface, 5 reflection, 6 obstacle)",
                pred_path.display()
            );
        }
        let labels = aside.scatter_labels(&frame.labels());
        let classes: Vec<Class> = pred.iter().map(|&id| Class::from_id(id)).collect();
        conf.add(&labels, &classes);
        let prob_path = pred_dir.join(format!("{}.prob", e.name));
        if prob_path.exists() {
            let probs = io::read_probs_for(&prob_path, points)?;
            reliability.add(&labels, &classes, &probs);
            with_probs += 1;
        }
    }
    let metrics = conf.metrics();
    println!("{} frames scored", entries.len());
    print!("{}", metrics.table());
    let report = (with_probs > 0).then(|| reliability.report());
    if let Some(r) = &report {
        if with_probs < entries.len() {
            eprintln!(
                "warning: only {with_probs} of {} frames have a .prob file: the calibration is of those",
                entries.len()
            );
        }
        println!("confidence calibration ({with_probs} frames with .prob files):");
        print!("{}", r.markdown());
    }
    if let Some(path) = args.json {
        let mut value = serde_json::to_value(&metrics)?;
        if let (Some(obj), Some(r)) = (value.as_object_mut(), &report) {
            obj.insert("reliability".into(), serde_json::to_value(r)?);
        }
        let json = serde_json::to_string_pretty(&value)?;
        io::write_atomic(&path, |w| std::io::Write::write_all(w, json.as_bytes()))?;
    }
    Ok(())
}
