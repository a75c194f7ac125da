//! `specular demo`: the main job on a built-in default.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use super::detect::{detect, write_outputs};
use super::{bundled_sample, load_config};

/// Arguments of `demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output directory.
    #[arg(long, default_value = "runs/demo")]
    pub out: PathBuf,
    /// Configuration: built-in name (default, paper) or TOML file.
    #[arg(long, default_value = "default")]
    pub config: String,
}

/// Run the demo: the bundled real 3DRef sample through the default method.
pub fn run(args: DemoArgs) -> Result<()> {
    let config = load_config(&args.config)?;
    let sample = bundled_sample();
    let frames = sample.join("frames");
    let poses = sample.join("poses.txt");
    let (sequence, output, map) = detect(&frames, Some(&poses), &config)
        .with_context(|| format!("running the demo on {}", sample.display()))?;
    write_outputs(&args.out, &config, &sequence, &output, map.as_ref())?;
    println!(
        "specular demo: {} real 3DRef frames ({}), method {}",
        sequence.len(),
        sample.display(),
        config.method.name()
    );
    if let Some(conf) = output.confusion(&sequence) {
        print!("{}", conf.metrics().table());
    }
    print!("{}", output.timings.table());
    println!("outputs: {}", args.out.display());
    Ok(())
}
