//! Batch application: one scene's stack applied to many meshes (`ductile apply SCENE --input
//! MESH… --out-dir DIR`), on one machine (a bounded number of meshes in flight) or split over
//! a cluster's array jobs ([`Shard`]). The rules are documented in `docs/batch.md`.
//!
//! A batch is planned before anything runs ([`plan`]): the inputs are expanded (globs, list
//! files), sorted and de-duplicated, every output name is derived and collisions are refused,
//! and only then is the shard taken, so every shard of a cluster job agrees on the plan.
//! Each input then succeeds or fails on its own ([`apply_one`]); a failure is reported and the
//! batch goes on. Outputs are written atomically, so an interrupted batch leaves no
//! half-written file, and a resumed one (`--skip-existing`) redoes only what is missing.

use std::collections::{BTreeMap, HashSet};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use anyhow::{Context as _, bail};
use ductile_core::mesh::RestMesh;
use ductile_io::{ExportMesh, MeshRef};
use ductile_scene::prelude::Document;

/// The environment variable that tells `--shard auto` the number of shards of a Kubernetes
/// Indexed Job (Kubernetes gives each pod its index, `JOB_COMPLETION_INDEX`, but not the
/// Job's `completions`; the manifest sets this to the same number).
pub const SHARD_COUNT_VAR: &str = "DUCTILE_SHARD_COUNT";

/// One part of a batch split over several processes: the inputs whose position in the sorted
/// input list is `index` modulo `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This process's shard, `0 ≤ index < count`.
    pub index: usize,
    /// The number of shards.
    pub count: usize,
}

impl Shard {
    /// The whole batch in one process.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` (`0 ≤ I < N`).
    pub fn parse(text: &str) -> anyhow::Result<Self> {
        let (i, n) = text
            .split_once('/')
            .with_context(|| format!("--shard '{text}': expected I/N (e.g. 0/4) or auto"))?;
        let index: usize = i
            .trim()
            .parse()
            .with_context(|| format!("--shard '{text}': the index '{i}' is not a whole number"))?;
        let count: usize = n
            .trim()
            .parse()
            .with_context(|| format!("--shard '{text}': the count '{n}' is not a whole number"))?;
        Self::new(index, count).with_context(|| format!("--shard '{text}'"))
    }

    /// A checked shard.
    pub fn new(index: usize, count: usize) -> anyhow::Result<Self> {
        if count == 0 {
            bail!("the number of shards must be at least 1");
        }
        if index >= count {
            bail!(
                "shard index {index} must be below the number of shards {count} (indices start at 0)"
            );
        }
        Ok(Self { index, count })
    }

    /// The shard a cluster scheduler gave this process, read from the environment through
    /// `var`: a Kubernetes Indexed Job (`JOB_COMPLETION_INDEX`, with the count in
    /// [`SHARD_COUNT_VAR`]) or a Slurm job array (`SLURM_ARRAY_TASK_ID`,
    /// `SLURM_ARRAY_TASK_COUNT`, and `SLURM_ARRAY_TASK_MIN` / `SLURM_ARRAY_TASK_STEP` when
    /// the array does not start at 0 or has a step; or, with [`SHARD_COUNT_VAR`] set, the
    /// task id as the shard index, so that a task resubmitted alone keeps its shard).
    pub fn from_env(var: impl Fn(&str) -> Option<String>) -> anyhow::Result<Self> {
        let number =
            |name: &str| -> anyhow::Result<Option<usize>> {
                match var(name) {
                    None => Ok(None),
                    Some(v) => v.trim().parse().map(Some).with_context(|| {
                        format!("--shard auto: {name}='{v}' is not a whole number")
                    }),
                }
            };
        if let Some(index) = number("JOB_COMPLETION_INDEX")? {
            let count = number(SHARD_COUNT_VAR)?.with_context(|| {
                format!(
                    "--shard auto: JOB_COMPLETION_INDEX is set (a Kubernetes Indexed Job) but \
                     {SHARD_COUNT_VAR} is not: set it to the Job's completions"
                )
            })?;
            return Self::new(index, count).context("--shard auto (Kubernetes Indexed Job)");
        }
        if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            // With the count given, the task ids are the shard indices (`--array=0-N−1`),
            // so that one task resubmitted alone (`sbatch --array=17`, an array of one task)
            // still takes its own shard and not every input.
            if let Some(count) = number(SHARD_COUNT_VAR)? {
                // The array must be 0 to count − 1 (a lone resubmitted task aside): an array
                // of another size would leave shards to no task, or give two tasks one.
                let tasks = number("SLURM_ARRAY_TASK_COUNT")?.unwrap_or(1);
                let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
                let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1);
                if tasks > 1 && (tasks != count || min != 0 || step != 1) {
                    bail!(
                        "--shard auto: {SHARD_COUNT_VAR}={count} but the Slurm array has \
                         {tasks} tasks from {min} in steps of {step}: with {SHARD_COUNT_VAR} \
                         the array must be --array=0-{} (one task per shard)",
                        count.saturating_sub(1)
                    );
                }
                return Self::new(id, count).with_context(|| {
                    format!(
                        "--shard auto (Slurm job array with {SHARD_COUNT_VAR}: the task ids \
                         are the shard indices 0 to {})",
                        count.saturating_sub(1)
                    )
                });
            }
            let count = number("SLURM_ARRAY_TASK_COUNT")?.context(
                "--shard auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not",
            )?;
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            if id < min || (id - min) % step != 0 {
                bail!(
                    "--shard auto: SLURM_ARRAY_TASK_ID={id} is not in the array {min}, {}, … \
                     (SLURM_ARRAY_TASK_MIN, SLURM_ARRAY_TASK_STEP)",
                    min + step
                );
            }
            if count == 1 && id != 0 {
                bail!(
                    "--shard auto: SLURM_ARRAY_TASK_ID={id} is the only task of its array: if it \
                     is one shard of a larger batch resubmitted alone, set {SHARD_COUNT_VAR} to \
                     the number of shards (else it would take every input); use --array=0 for a \
                     batch of one shard"
                );
            }
            return Self::new((id - min) / step, count).context("--shard auto (Slurm job array)");
        }
        bail!(
            "--shard auto: neither JOB_COMPLETION_INDEX (Kubernetes Indexed Job) nor \
             SLURM_ARRAY_TASK_ID (Slurm job array) is set; give the shard as I/N"
        )
    }

    /// Whether the input at `position` of the sorted input list belongs to this shard.
    #[must_use]
    pub fn takes(&self, position: usize) -> bool {
        position % self.count == self.index
    }
}

/// One input of a batch and the file it is written to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Job {
    /// The input mesh (a path, with an optional `#name` part selection).
    pub input: MeshRef,
    /// The output `.glb` in the output folder.
    pub output: PathBuf,
}

/// Whether `text` is a glob pattern rather than a plain path.
fn is_pattern(text: &str) -> bool {
    text.contains(['*', '?', '['])
}

/// Every input named by `specs` (paths or glob patterns, each with an optional `#name`) and by
/// the list file `list` (one per line; blank lines and lines starting with `#` are skipped;
/// paths as on the command line, relative to the current folder), sorted, each once.
///
/// A pattern that matches no file is an error (a typo would otherwise give an empty batch); a
/// plain path is kept as it is, so a missing file fails as that input's own error.
pub fn expand_inputs(specs: &[String], list: Option<&Path>) -> anyhow::Result<Vec<String>> {
    let mut all: Vec<String> = Vec::new();
    let mut add = |spec: &str, origin: &str| -> anyhow::Result<()> {
        let r = MeshRef::parse(spec);
        let path = r.path.to_string_lossy().into_owned();
        if !is_pattern(&path) {
            all.push(spec.to_owned());
            return Ok(());
        }
        let matches = glob::glob(&path)
            .with_context(|| format!("{origin}: '{spec}' is not a valid glob pattern"))?;
        let before = all.len();
        for m in matches {
            let m = m.with_context(|| format!("{origin}: '{spec}'"))?;
            if !m.is_file() {
                continue;
            }
            let m = m.to_string_lossy().into_owned();
            all.push(match &r.select {
                Some(name) => format!("{m}#{name}"),
                None => m,
            });
        }
        if all.len() == before {
            bail!("{origin}: '{spec}' matches no file");
        }
        Ok(())
    };
    for s in specs {
        add(s, "--input")?;
    }
    if let Some(list) = list {
        let text = std::fs::read_to_string(list)
            .with_context(|| format!("--input-list {}: cannot read the file", list.display()))?;
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            add(line, &format!("{}:{}", list.display(), n + 1))?;
        }
    }
    all.sort();
    all.dedup();
    Ok(all)
}

/// The output file name of `input`: its file stem (with `-name` for a `#name` selection) and
/// `.glb`.
pub fn output_name(input: &MeshRef) -> anyhow::Result<OsString> {
    let stem = input
        .path
        .file_stem()
        .filter(|s| !s.is_empty())
        .with_context(|| format!("input '{input}' has no file name"))?;
    let mut name = stem.to_owned();
    if let Some(part) = &input.select {
        name.push("-");
        name.push(part);
    }
    name.push(".glb");
    Ok(name)
}

/// Plans a batch: every input with its output in `out_dir`, collisions refused (two inputs
/// that would write the same file), then the inputs of `shard` only, in input order.
pub fn plan(inputs: &[String], out_dir: &Path, shard: Shard) -> anyhow::Result<Vec<Job>> {
    let mut seen: BTreeMap<OsString, &str> = BTreeMap::new();
    let mut jobs = Vec::with_capacity(inputs.len() / shard.count + 1);
    for (position, spec) in inputs.iter().enumerate() {
        let input = MeshRef::parse(spec);
        let name = output_name(&input)?;
        if let Some(first) = seen.insert(name.clone(), spec) {
            bail!(
                "inputs '{first}' and '{spec}' would both be written to {}: rename one, or \
                 run them in separate batches",
                out_dir.join(&name).display()
            );
        }
        if shard.takes(position) {
            jobs.push(Job {
                input,
                output: out_dir.join(name),
            });
        }
    }
    Ok(jobs)
}

/// What is applied to every input: the stack of one mesh node of a scene.
#[derive(Debug)]
pub struct Template<'a> {
    /// The scene document (posed at a frame already, if one was asked for).
    pub document: &'a Document,
    /// The mesh node whose stack is applied.
    pub node: &'a str,
    /// The stored vertex count of the node's own mesh.
    pub scene_vertices: usize,
    /// The areas the stack reads that are given by vertex indices (they carry over only to
    /// meshes with `scene_vertices` stored vertices).
    pub vertex_areas: Vec<&'a str>,
}

impl<'a> Template<'a> {
    /// The stack of mesh node `node` of `document`, whose own rest mesh is `rest`.
    pub fn new(document: &'a Document, node: &'a str, rest: &RestMesh) -> anyhow::Result<Self> {
        Ok(Self {
            document,
            node,
            scene_vertices: rest.topology().stored_count(),
            vertex_areas: document.vertex_index_areas_in_stack(node)?,
        })
    }
}

/// Applies the template's stack to `input` and writes `output` (atomically). Returns the
/// input's stored vertex count.
pub fn apply_one(template: &Template<'_>, input: &MeshRef, output: &Path) -> anyhow::Result<usize> {
    let rest = ductile_io::load_rest_mesh(input)?;
    let vertices = rest.topology().stored_count();
    if let Some(area) = template.vertex_areas.first()
        && vertices != template.scene_vertices
    {
        bail!(
            "the stack reads area '{area}', given by vertex indices of mesh '{}' ({} vertices), \
             but this mesh has {vertices} vertices: vertex-index areas carry over only to meshes \
             with the same vertex count (region areas carry over to any mesh)",
            template.node,
            template.scene_vertices
        );
    }
    let deformed = template
        .document
        .evaluate(template.node, &rest)
        .with_context(|| format!("cannot apply the stack of mesh '{}'", template.node))?;
    let name = input.path.file_stem().map_or_else(
        || template.node.to_owned(),
        |s| s.to_string_lossy().into_owned(),
    );
    ductile_io::export_gltf(output, &[ExportMesh::deformed(&name, &rest, &deformed)])?;
    Ok(vertices)
}

/// How one input of a batch ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Applied and written.
    Done,
    /// Refused or failed; nothing was written.
    Failed,
    /// Its output existed already (`--skip-existing`).
    Skipped,
}

impl Status {
    /// The status as the report writes it.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Done => "done",
            Status::Failed => "failed",
            Status::Skipped => "skipped",
        }
    }
}

/// The outcome of one input.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The input as given (path with `#name`).
    pub input: String,
    /// The output file.
    pub output: PathBuf,
    /// How it ended.
    pub status: Status,
    /// The input's stored vertex count, when it loaded.
    pub vertices: Option<usize>,
    /// Wall-clock milliseconds spent on it.
    pub ms: f64,
    /// Why it failed.
    pub error: Option<String>,
}

impl Record {
    /// The record as one line of the JSON-lines report (no line break).
    #[must_use]
    pub fn json(&self) -> String {
        serde_json::json!({
            "input": self.input,
            "output": self.output.to_string_lossy(),
            "status": self.status.as_str(),
            "vertices": self.vertices,
            "ms": (self.ms * 1000.0).round() / 1000.0,
            "error": self.error,
        })
        .to_string()
    }
}

/// Removes the temporary files that an interrupted earlier run left while writing these jobs'
/// outputs (`.NAME.XXXXXX.tmp`, see [`ductile_io::write_atomic`]); other files, and the
/// temporary files of other shards' outputs, are left alone.
pub fn remove_stale_temporaries(out_dir: &Path, jobs: &[Job]) -> std::io::Result<usize> {
    let names: HashSet<&std::ffi::OsStr> =
        jobs.iter().filter_map(|j| j.output.file_name()).collect();
    let mut removed = 0;
    for entry in std::fs::read_dir(out_dir)? {
        let entry = entry?;
        let file_name = entry.file_name();
        let Some(name) = file_name.to_str() else {
            continue;
        };
        let Some(output) = ductile_io::atomic_temporary_target(name) else {
            continue;
        };
        if names.contains(std::ffi::OsStr::new(output)) && entry.file_type()?.is_file() {
            std::fs::remove_file(entry.path())?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// Runs `jobs` with at most `workers` meshes in flight (each worker thread holds one mesh; the
/// evaluation of each mesh runs on the shared rayon pool), calling `on_record` on the calling
/// thread as each input ends, and returns the records in the order they ended.
pub fn run(
    template: &Template<'_>,
    jobs: &[Job],
    workers: usize,
    skip_existing: bool,
    mut on_record: impl FnMut(&Record),
) -> Vec<Record> {
    let next = AtomicUsize::new(0);
    let (tx, rx) = mpsc::channel::<Record>();
    let mut records = Vec::with_capacity(jobs.len());
    std::thread::scope(|scope| {
        for _ in 0..workers.clamp(1, jobs.len().max(1)) {
            let tx = tx.clone();
            let next = &next;
            scope.spawn(move || {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(job) = jobs.get(i) else { break };
                    if tx.send(run_job(template, job, skip_existing)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        for record in rx {
            on_record(&record);
            records.push(record);
        }
    });
    records
}

/// One job, its failure (a panic included) turned into a record.
fn run_job(template: &Template<'_>, job: &Job, skip_existing: bool) -> Record {
    let start = Instant::now();
    let mut record = Record {
        input: job.input.to_string(),
        output: job.output.clone(),
        status: Status::Done,
        vertices: None,
        ms: 0.0,
        error: None,
    };
    if skip_existing && job.output.exists() {
        record.status = Status::Skipped;
        return record;
    }
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        apply_one(template, &job.input, &job.output)
    }));
    match result {
        Ok(Ok(vertices)) => record.vertices = Some(vertices),
        Ok(Err(e)) => {
            record.status = Status::Failed;
            record.error = Some(crate::error_message(&e));
        }
        Err(panic) => {
            record.status = Status::Failed;
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            record.error = Some(format!("internal error (a bug, please report it): {what}"));
        }
    }
    record.ms = crate::commands::ms(start.elapsed());
    record
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            vars.iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| (*v).to_owned())
        }
    }

    #[test]
    fn shards_parse_and_refuse_nonsense() {
        assert_eq!(Shard::parse("2/5").unwrap(), Shard { index: 2, count: 5 });
        for bad in ["5/5", "0/0", "1", "a/3", "1/x", "-1/3"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        let e = Shard::parse("3/3").unwrap_err();
        assert!(format!("{e:#}").contains("indices start at 0"), "{e:#}");
    }

    #[test]
    fn auto_shards_come_from_kubernetes_or_slurm() {
        let k8s = [("JOB_COMPLETION_INDEX", "7"), (SHARD_COUNT_VAR, "10")];
        assert_eq!(
            Shard::from_env(env(&k8s)).unwrap(),
            Shard::new(7, 10).unwrap()
        );
        let e = Shard::from_env(env(&[("JOB_COMPLETION_INDEX", "7")])).unwrap_err();
        assert!(format!("{e:#}").contains(SHARD_COUNT_VAR), "{e:#}");
        // `#SBATCH --array=1-100`: ids 1..=100.
        let slurm = [
            ("SLURM_ARRAY_TASK_ID", "100"),
            ("SLURM_ARRAY_TASK_COUNT", "100"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
        ];
        assert_eq!(
            Shard::from_env(env(&slurm)).unwrap(),
            Shard::new(99, 100).unwrap()
        );
        // `--array=0-18:2`: ids 0, 2, …, 18.
        let stepped = [
            ("SLURM_ARRAY_TASK_ID", "6"),
            ("SLURM_ARRAY_TASK_COUNT", "10"),
            ("SLURM_ARRAY_TASK_STEP", "2"),
        ];
        assert_eq!(
            Shard::from_env(env(&stepped)).unwrap(),
            Shard::new(3, 10).unwrap()
        );
        assert!(Shard::from_env(env(&[])).is_err());
        assert!(Shard::from_env(env(&[("SLURM_ARRAY_TASK_ID", "3")])).is_err());
        // Task 17 of 500 resubmitted alone (`sbatch --array=17`): an array of one task.
        let alone = [
            ("SLURM_ARRAY_TASK_ID", "17"),
            ("SLURM_ARRAY_TASK_COUNT", "1"),
            ("SLURM_ARRAY_TASK_MIN", "17"),
        ];
        let e = Shard::from_env(env(&alone)).unwrap_err();
        assert!(format!("{e:#}").contains(SHARD_COUNT_VAR), "{e:#}");
        let mut counted = alone.to_vec();
        counted.push((SHARD_COUNT_VAR, "500"));
        assert_eq!(
            Shard::from_env(env(&counted)).unwrap(),
            Shard::new(17, 500).unwrap()
        );
        counted[0].1 = "500";
        assert!(Shard::from_env(env(&counted)).is_err(), "ids are 0 to 499");
        // With the count given, the array must be 0 to count − 1.
        let whole = [
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "500"),
            (SHARD_COUNT_VAR, "500"),
        ];
        assert_eq!(
            Shard::from_env(env(&whole)).unwrap(),
            Shard::new(3, 500).unwrap()
        );
        for wrong in [
            [
                ("SLURM_ARRAY_TASK_COUNT", "250"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
            ],
            [
                ("SLURM_ARRAY_TASK_COUNT", "500"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
            ],
        ] {
            let mut e = whole.to_vec();
            e.retain(|(k, _)| *k != "SLURM_ARRAY_TASK_COUNT");
            e.extend(wrong);
            let err = Shard::from_env(env(&e)).unwrap_err();
            assert!(format!("{err:#}").contains("--array=0-499"), "{err:#}");
        }
        // A batch of one shard.
        let one = [
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "1"),
        ];
        assert_eq!(Shard::from_env(env(&one)).unwrap(), Shard::ALL);
    }

    #[test]
    fn shards_partition_the_sorted_inputs() {
        let inputs: Vec<String> = (0..23).map(|i| format!("m{i:02}.obj")).collect();
        let mut all: Vec<PathBuf> = Vec::new();
        for index in 0..4 {
            let jobs = plan(&inputs, Path::new("out"), Shard::new(index, 4).unwrap()).unwrap();
            all.extend(jobs.into_iter().map(|j| j.output));
        }
        all.sort();
        let expected: Vec<PathBuf> = (0..23)
            .map(|i| PathBuf::from(format!("out/m{i:02}.glb")))
            .collect();
        assert_eq!(all, expected);
    }

    #[test]
    fn outputs_keep_the_name_and_collisions_are_refused() {
        let jobs = plan(
            &["a/head.obj".into(), "b/body.glb#arm".into()],
            Path::new("out"),
            Shard::ALL,
        )
        .unwrap();
        assert_eq!(jobs[0].output, Path::new("out/head.glb"));
        assert_eq!(jobs[1].output, Path::new("out/body-arm.glb"));
        let e = plan(
            &["a/head.obj".into(), "b/head.glb".into()],
            Path::new("out"),
            Shard::ALL,
        )
        .unwrap_err();
        let e = format!("{e:#}");
        assert!(
            e.contains("'a/head.obj' and 'b/head.glb'") && e.contains("out/head.glb"),
            "{e}"
        );
    }

    #[test]
    fn globs_and_lists_expand_sorted_once() {
        let dir = tempfile::tempdir().unwrap();
        for n in ["b.obj", "a.obj", "c.txt"] {
            std::fs::write(dir.path().join(n), "").unwrap();
        }
        let d = dir.path().display();
        let list = dir.path().join("list.txt");
        std::fs::write(
            &list,
            format!("# meshes\n\n{d}/b.obj\n  {d}/a.obj#part  \n"),
        )
        .unwrap();
        let got = expand_inputs(&[format!("{d}/*.obj")], Some(&list)).unwrap();
        assert_eq!(
            got,
            [
                format!("{d}/a.obj"),
                format!("{d}/a.obj#part"),
                format!("{d}/b.obj")
            ]
        );
        let e = expand_inputs(&[format!("{d}/*.stl")], None).unwrap_err();
        assert!(format!("{e:#}").contains("matches no file"), "{e:#}");
        // A plain path is kept: a missing file is that input's own failure.
        assert_eq!(
            expand_inputs(&["missing.obj".into()], None).unwrap(),
            ["missing.obj"]
        );
    }
}
