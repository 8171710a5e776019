//! The batch half of `ductile apply`: `--input MESH… [--input-list FILE] --out-dir DIR
//! [--mesh NODE] [--jobs N] [--shard I/N|auto] [--skip-existing] [--report FILE]`. The engine
//! is [`crate::batch`]; this file reads the arguments and reports progress.

use std::fs::File;
use std::io::{BufWriter, IsTerminal as _, Write};
use std::time::Instant;

use anyhow::{Context as _, bail};
use ductile_io::LoadedScene;

use super::apply::Args;
use crate::batch::{self, Record, Shard, Status, Template};

/// Runs a batch on the loaded (and, with `--frame`, posed) scene.
pub fn run(args: &Args, scene: &LoadedScene, out: &mut dyn Write) -> anyhow::Result<u8> {
    let Some(out_dir) = &args.out_dir else {
        bail!("a batch (--input, --input-list) needs --out-dir DIR for its outputs");
    };
    let node = match &args.mesh {
        Some(name) => scene.mesh(name).with_context(|| {
            format!(
                "{}: --mesh '{name}' is not a mesh node of the scene (its meshes: {})",
                scene.path.display(),
                mesh_names(scene)
            )
        })?,
        None => match scene.meshes.as_slice() {
            [only] => only,
            [] => bail!(
                "{}: the scene has no mesh node to apply",
                scene.path.display()
            ),
            _ => bail!(
                "{}: the scene has several mesh nodes ({}); choose one with --mesh NODE",
                scene.path.display(),
                mesh_names(scene)
            ),
        },
    };
    let shard = match args.shard.as_deref() {
        None => Shard::ALL,
        Some("auto") => Shard::from_env(|k| std::env::var(k).ok())?,
        Some(text) => Shard::parse(text)?,
    };
    let inputs = batch::expand_inputs(&args.inputs, args.input_list.as_deref())?;
    let jobs = batch::plan(&inputs, out_dir, shard)?;
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("--out-dir {}: cannot create the folder", out_dir.display()))?;
    let stale = batch::remove_stale_temporaries(out_dir, &jobs)
        .with_context(|| format!("--out-dir {}: cannot list the folder", out_dir.display()))?;
    let template = Template::new(&scene.document, &node.name, &node.rest)?;
    let workers = args.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, usize::from),
        |n| n as usize,
    );
    let mut report = match &args.report {
        None => None,
        Some(p) => Some(BufWriter::new(File::create(p).with_context(|| {
            format!("--report {}: cannot create the file", p.display())
        })?)),
    };

    writeln!(
        out,
        "applying the stack of mesh '{}' ({} layers) to {} of {} inputs{}, {} at a time",
        node.name,
        scene.document.mesh(&node.name).map_or(0, |n| n.stack.len()),
        jobs.len(),
        inputs.len(),
        if shard == Shard::ALL {
            String::new()
        } else {
            format!(" (shard {}/{})", shard.index, shard.count)
        },
        workers.min(jobs.len().max(1))
    )?;
    if stale > 0 {
        writeln!(
            out,
            "removed {stale} temporary files an interrupted run left"
        )?;
    }
    let start = Instant::now();
    // A bar on a terminal; plain lines (one per input) for logs and schedulers.
    let bar = std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(jobs.len() as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} {per_sec} eta {eta} {wide_msg}",
        ) {
            bar.set_style(style);
        }
        bar
    });
    let total = jobs.len();
    let mut count = 0;
    let mut write_error: Option<anyhow::Error> = None;
    let records = batch::run(&template, &jobs, workers, args.skip_existing, |r| {
        count += 1;
        let line = progress_line(count, total, r);
        let result = (|| -> anyhow::Result<()> {
            if let Some(report) = &mut report {
                writeln!(report, "{}", r.json())?;
                report.flush()?;
            }
            match &bar {
                Some(bar) => {
                    if r.status == Status::Failed {
                        bar.println(&line);
                    }
                    bar.set_message(r.input.clone());
                    bar.inc(1);
                }
                None => writeln!(out, "{line}")?,
            }
            Ok(())
        })();
        if let (Err(e), None) = (result, &write_error) {
            write_error = Some(e);
        }
    });
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    if let Some(e) = write_error {
        return Err(e.context("cannot write the batch's progress or report"));
    }
    let of = |s: Status| records.iter().filter(|r| r.status == s).count();
    let (done, failed, skipped) = (of(Status::Done), of(Status::Failed), of(Status::Skipped));
    writeln!(
        out,
        "batch: {done} done, {failed} failed, {skipped} skipped in {:.2} s",
        start.elapsed().as_secs_f64()
    )?;
    if failed > 0 {
        for r in records.iter().filter(|r| r.status == Status::Failed) {
            writeln!(out, "failed: {}", r.input)?;
        }
    }
    Ok(u8::from(failed > 0))
}

/// The names of the scene's mesh nodes, for messages.
fn mesh_names(scene: &LoadedScene) -> String {
    let names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
    names.join(", ")
}

/// One input's progress line: `[k/n] INPUT -> OUTPUT: V vertices, T ms`, or why it failed.
fn progress_line(k: usize, n: usize, r: &Record) -> String {
    match r.status {
        Status::Done => format!(
            "[{k}/{n}] {} -> {}: {} vertices, {:.1} ms",
            r.input,
            r.output.display(),
            r.vertices.unwrap_or(0),
            r.ms
        ),
        Status::Skipped => format!(
            "[{k}/{n}] {}: skipped, {} exists",
            r.input,
            r.output.display()
        ),
        Status::Failed => format!(
            "[{k}/{n}] {}: error: {}",
            r.input,
            r.error.as_deref().unwrap_or("failed")
        ),
    }
}
