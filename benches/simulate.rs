//! Simulator throughput: QT64 frames per second on the built-in scenes.
//!
//! `cargo bench --bench simulate [-- SCENE ...]` (default: office, corridor,
//! lobby). For each scene it times
//!
//! - one thread: `Simulator::frame` for 200 frames spread over the sequence;
//! - rayon on 2 threads (and on all cores when there are more): the same
//!   frames in parallel;
//! - for both, frames per CPU-second of the process (Linux), which does not
//!   depend on other load on the machine: frames are independent, so `n`
//!   free cores give about `n` times that;
//! - where the time goes, one thread: casting the primary rays only (the
//!   BVH), tracing every beam with its secondary rays (beam physics), and the
//!   rest of a frame (merging, return selection, noise, points).

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use specular::sim::{Scene, Simulator};

const FRAMES: usize = 200;

fn frames_of(scene: &Scene) -> Vec<usize> {
    let step = (scene.frames / FRAMES).max(1);
    (0..FRAMES).map(|i| (i * step) % scene.frames).collect()
}

/// CPU time used by this process so far (user + system), seconds, from
/// `/proc/self/stat` (Linux; `None` elsewhere). Clock ticks are taken as
/// 1/100 s (USER_HZ on Linux).
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which is in parentheses).
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// Seconds per frame of `f` run over `ks` on the current thread pool.
fn time_parallel(ks: &[usize], f: impl Fn(usize) -> usize + Sync) -> (f64, usize) {
    let t = Instant::now();
    let points: usize = ks.par_iter().map(|&k| f(k)).sum();
    (t.elapsed().as_secs_f64() / ks.len() as f64, points)
}

fn main() {
    let mut names: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    if names.is_empty() {
        names = ["office", "corridor", "lobby"].map(String::from).to_vec();
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("simulate bench: {FRAMES} frames per scene, {cores} cores available");
    for name in &names {
        let scene = match Scene::resolve(name) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("simulate bench: {e}");
                std::process::exit(1);
            }
        };
        let t = Instant::now();
        let sim = Simulator::new(&scene);
        let build = t.elapsed().as_secs_f64();
        let ks = frames_of(&scene);
        let model = &scene.sensor.model;
        println!(
            "\n{name}: {} surfaces, {} patches, {} x {} beams ({} outside the blind sector), index built in {:.2} ms",
            scene.surfaces.len(),
            sim.tracer().index().patch_count(),
            model.rings(),
            model.columns,
            sim.beam_count(),
            build * 1e3
        );

        let mut pools = vec![1, 2];
        if cores > 2 {
            pools.push(cores);
        }
        for threads in pools {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            let cpu0 = cpu_seconds();
            let (spf, points) =
                pool.install(|| time_parallel(&ks, |k| sim.frame(k, 1).frame.points.len()));
            // Frames per CPU-second: what one core delivers, whatever else
            // runs on the machine.
            let per_cpu = match (cpu0, cpu_seconds()) {
                (Some(a), Some(b)) if b > a => {
                    format!(", {:.0} frames per CPU-second", ks.len() as f64 / (b - a))
                }
                _ => String::new(),
            };
            println!(
                "  {threads} thread(s): {:7.1} frames/s ({:.2} ms/frame, {:.0} points/frame{per_cpu})",
                1.0 / spf,
                spf * 1e3,
                points as f64 / ks.len() as f64
            );
        }

        // Where the time goes (one thread).
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("thread pool");
        let beams: Vec<DVec3> = (0..model.columns)
            .filter(|&c| !scene.sensor.is_blind(model.column_azimuth_deg(c)))
            .flat_map(|c| {
                (0..model.rings()).map(move |r| {
                    let d = model.beam_direction(r, c);
                    DVec3::new(d.x, d.y, d.z)
                })
            })
            .collect();
        let rot = |k: usize| {
            let p = sim.pose(k).pose;
            let t = p.translation.vector;
            (p.rotation, DVec3::new(t.x, t.y, t.z))
        };
        let (cast, _) = one.install(|| {
            time_parallel(&ks, |k| {
                let (q, o) = rot(k);
                let index = sim.tracer().index();
                beams
                    .iter()
                    .filter(|d| {
                        let w = q * nalgebra::Vector3::new(d.x, d.y, d.z);
                        index
                            .cast(o, DVec3::new(w.x, w.y, w.z), 60.0, None)
                            .is_some()
                    })
                    .count()
            })
        });
        let (trace, _) = one.install(|| {
            time_parallel(&ks, |k| {
                let (q, o) = rot(k);
                let mut echoes = Vec::new();
                let mut n = 0;
                for d in &beams {
                    let w = q * nalgebra::Vector3::new(d.x, d.y, d.z);
                    echoes.clear();
                    sim.tracer()
                        .trace(o, DVec3::new(w.x, w.y, w.z), &mut echoes);
                    n += echoes.len();
                }
                n
            })
        });
        let (full, _) = one.install(|| time_parallel(&ks, |k| sim.frame(k, 1).frame.points.len()));
        let per_beam = |s: f64| s / beams.len() as f64 * 1e9;
        println!(
            "  one thread, per frame: primary rays {:.2} ms ({:.0} ns/beam), all rays + physics {:.2} ms ({:.0} ns/beam), full frame {:.2} ms ({:.0} ns/beam)",
            cast * 1e3,
            per_beam(cast),
            trace * 1e3,
            per_beam(trace),
            full * 1e3,
            per_beam(full),
        );
    }
}
