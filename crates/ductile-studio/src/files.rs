//! File and edit actions (menus and shortcuts) and the file dialogs (egui-file-dialog, no
//! GTK): New, Open, Save, Save As, Import mesh, Export glTF, Export animation, Export
//! variants as morph targets, Undo, Redo, Delete, Quit.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use bevy::prelude::*;
use bevy_egui::egui;
use ductile_bevy::prelude::*;
use ductile_history::operation::Operation;
use ductile_io::project::Project;
use egui_file_dialog::FileDialog;

use crate::studio::{FramePending, Notices, OpenProject};

/// An export running in the background (File ▸ Export animation or variants): the file, the
/// samples done and to do, and the task that writes it (its result is the message shown).
#[derive(Resource, Default)]
pub struct ExportJob(pub Option<RunningExport>);

/// See [`ExportJob`].
pub struct RunningExport {
    /// What is being written, for the status bar.
    pub what: String,
    /// Samples done and in all (both 0 until the bake reports).
    pub progress: std::sync::Arc<(AtomicUsize, AtomicUsize)>,
    task: bevy::tasks::Task<Result<String, String>>,
}

impl RunningExport {
    /// Runs `work` on the background task pool; it reports its progress (done, in all)
    /// through the function it is given and returns the message to show.
    pub fn spawn(
        what: String,
        work: impl FnOnce(&mut dyn FnMut(usize, usize)) -> Result<String, String> + Send + 'static,
    ) -> Self {
        let progress = std::sync::Arc::new((AtomicUsize::new(0), AtomicUsize::new(0)));
        let shared = std::sync::Arc::clone(&progress);
        let task = bevy::tasks::AsyncComputeTaskPool::get().spawn(async move {
            work(&mut |done: usize, total: usize| {
                shared.0.store(done, Ordering::Relaxed);
                shared.1.store(total, Ordering::Relaxed);
            })
        });
        Self {
            what,
            progress,
            task,
        }
    }

    /// The fraction done, in [0, 1].
    #[must_use]
    pub fn fraction(&self) -> f32 {
        let (done, total) = (
            self.progress.0.load(Ordering::Relaxed),
            self.progress.1.load(Ordering::Relaxed),
        );
        if total == 0 {
            0.0
        } else {
            done as f32 / total as f32
        }
    }
}

/// Collects a finished background export and tells the user what it wrote.
pub fn poll_export(mut job: ResMut<ExportJob>, mut notices: ResMut<Notices>) {
    let Some(running) = &mut job.0 else {
        return;
    };
    if let Some(result) = bevy::tasks::futures::check_ready(&mut running.task) {
        notices.push_result(result);
        job.0 = None;
    }
}

/// Something the user asked for from a menu or a shortcut.
#[derive(Message, Debug, Clone, PartialEq, Eq)]
pub enum StudioAction {
    /// Start an empty scene.
    New,
    /// Choose a scene or history file to open.
    Open,
    /// Open this file.
    OpenPath(PathBuf),
    /// Save to the project's file (or ask where, the first time).
    Save,
    /// Choose where to save.
    SaveAs,
    /// Save to this file.
    SaveAsPath(PathBuf),
    /// Choose a mesh to import.
    ImportMesh,
    /// Import this mesh file (asking which part when it holds several).
    ImportPath(PathBuf),
    /// Import this part of the mesh file (`None`: the whole file).
    ImportPart(PathBuf, Option<String>),
    /// Choose where to export.
    ExportGltf,
    /// Export the deformed meshes to this file.
    ExportPath(PathBuf),
    /// Choose where to export the baked animation.
    ExportAnimation,
    /// Bake the timeline and write it to this file (morph targets and their weights).
    ExportAnimationPath(PathBuf),
    /// Choose where to export the variants as morph targets.
    ExportMorphs,
    /// Write the rest meshes with one morph target per variant to this file.
    ExportMorphsPath(PathBuf),
    /// Undo the last step.
    Undo,
    /// Redo the next step.
    Redo,
    /// Remove the selected node (and the layers and references that use it).
    Delete,
    /// Frame the selection.
    FrameSelected,
    /// Leave the Studio.
    Quit,
    /// Carry out this action even though the document has unsaved changes.
    Discard(Box<StudioAction>),
}

/// Which dialog is open and for what.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DialogPurpose {
    /// Open a scene or history.
    Open,
    /// Save the scene.
    SaveAs,
    /// Import a mesh.
    Import,
    /// Export glTF.
    Export,
    /// Export the baked animation.
    ExportAnimation,
    /// Export the variants as morph targets.
    ExportMorphs,
}

/// The file dialog and the question about unsaved changes.
#[derive(Resource, Default)]
pub struct FileDialogs {
    /// The open dialog and its purpose.
    pub dialog: Option<(DialogPurpose, FileDialog)>,
    /// An action waiting for "discard unsaved changes?".
    pub confirm: Option<StudioAction>,
    /// A mesh file of several parts waiting for the choice of what to import.
    pub parts: Option<PartChoice>,
}

/// The question "import which part?" for a mesh file of several parts (OBJ objects or
/// groups, named glTF meshes), as Blender's importers offer to split or pick them.
#[derive(Debug, Clone)]
pub struct PartChoice {
    /// The file.
    pub path: PathBuf,
    /// Its parts, the largest first.
    pub parts: Vec<ductile_io::MeshPart>,
    /// The chosen part (`None`: the whole file).
    pub chosen: Option<usize>,
}

impl PartChoice {
    /// The question for `parts` of the file `path`, the largest part first and the whole
    /// file chosen.
    #[must_use]
    pub fn new(path: PathBuf, mut parts: Vec<ductile_io::MeshPart>) -> Self {
        parts.sort_by(|a, b| b.vertices.cmp(&a.vertices).then(a.name.cmp(&b.name)));
        Self {
            path,
            parts,
            chosen: None,
        }
    }

    /// Draws the choice; returns the import to do when the user confirms, and whether the
    /// question is over (imported or cancelled).
    pub fn show(&mut self, ctx: &egui::Context) -> (Option<StudioAction>, bool) {
        let mut result = (None, false);
        let file = self.path.file_name().map_or_else(
            || self.path.display().to_string(),
            |f| f.to_string_lossy().into_owned(),
        );
        let total: usize = self.parts.iter().map(|p| p.vertices).sum();
        egui::Window::new("Import which part?")
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
            .show(ctx, |ui| {
                ui.label(format!("{file} holds {} parts.", self.parts.len()));
                egui::ScrollArea::vertical()
                    .max_height(220.0)
                    .show(ui, |ui| {
                        ui.selectable_value(
                            &mut self.chosen,
                            None,
                            format!("Whole file ({total} vertices)"),
                        );
                        for (i, p) in self.parts.iter().enumerate() {
                            ui.selectable_value(
                                &mut self.chosen,
                                Some(i),
                                format!("{} ({} vertices)", p.name, p.vertices),
                            );
                        }
                    });
                ui.horizontal(|ui| {
                    let enter = ui.input(|i| i.key_pressed(egui::Key::Enter));
                    if ui.button("Import").clicked() || enter {
                        let part = self.chosen.map(|i| self.parts[i].name.clone());
                        result = (
                            Some(StudioAction::ImportPart(self.path.clone(), part)),
                            true,
                        );
                    }
                    if ui.button("Cancel").clicked()
                        || ui.input(|i| i.key_pressed(egui::Key::Escape))
                    {
                        result.1 = true;
                    }
                });
            });
        result
    }
}

impl FileDialogs {
    fn open(&mut self, purpose: DialogPurpose, dir: Option<PathBuf>) {
        let mut d = FileDialog::new().default_size([720.0, 460.0]);
        if let Some(dir) = dir {
            d = d.initial_directory(dir);
        }
        d = match purpose {
            DialogPurpose::Open => d
                .title("Open scene or history")
                .add_file_filter_extensions("Scenes and histories (.ron)", vec!["ron"])
                .default_file_filter("Scenes and histories (.ron)"),
            DialogPurpose::SaveAs => d
                .title("Save scene (its history is saved beside it)")
                .add_save_extension("Scene (.ron)", "ron")
                .default_save_extension("Scene (.ron)")
                .default_file_name("scene.ron"),
            DialogPurpose::Import => d
                .title("Import mesh (glTF or OBJ)")
                .add_file_filter_extensions(
                    "Meshes (.glb, .gltf, .obj)",
                    vec!["glb", "gltf", "obj"],
                )
                .default_file_filter("Meshes (.glb, .gltf, .obj)"),
            DialogPurpose::Export => d
                .title("Export deformed meshes as glTF")
                .add_save_extension("glTF binary (.glb)", "glb")
                .default_save_extension("glTF binary (.glb)")
                .default_file_name("deformed.glb"),
            DialogPurpose::ExportAnimation => d
                .title("Export the timeline as glTF morph targets and animation")
                .add_save_extension("glTF binary (.glb)", "glb")
                .default_save_extension("glTF binary (.glb)")
                .default_file_name("animation.glb"),
            DialogPurpose::ExportMorphs => d
                .title("Export the variants as glTF morph targets")
                .add_save_extension("glTF binary (.glb)", "glb")
                .default_save_extension("glTF binary (.glb)")
                .default_file_name("variants.glb"),
        };
        match purpose {
            DialogPurpose::Open | DialogPurpose::Import => d.pick_file(),
            DialogPurpose::SaveAs
            | DialogPurpose::Export
            | DialogPurpose::ExportAnimation
            | DialogPurpose::ExportMorphs => d.save_file(),
        }
        self.dialog = Some((purpose, d));
    }

    /// Shows the dialog and the unsaved-changes question; returns what the user chose.
    pub fn show(&mut self, ctx: &egui::Context) -> Option<StudioAction> {
        let mut chosen = None;
        if let Some((purpose, dialog)) = &mut self.dialog {
            dialog.update(ctx);
            if let Some(path) = dialog.take_picked() {
                chosen = Some(match purpose {
                    DialogPurpose::Open => StudioAction::OpenPath(path),
                    DialogPurpose::SaveAs => StudioAction::SaveAsPath(path),
                    DialogPurpose::Import => StudioAction::ImportPath(path),
                    DialogPurpose::Export => StudioAction::ExportPath(path),
                    DialogPurpose::ExportAnimation => StudioAction::ExportAnimationPath(path),
                    DialogPurpose::ExportMorphs => StudioAction::ExportMorphsPath(path),
                });
                self.dialog = None;
            } else if matches!(
                dialog.state(),
                egui_file_dialog::DialogState::Closed | egui_file_dialog::DialogState::Cancelled
            ) {
                self.dialog = None;
            }
        }
        if let Some(choice) = &mut self.parts {
            let (action, done) = choice.show(ctx);
            if action.is_some() {
                chosen = action;
            }
            if done {
                self.parts = None;
            }
        }
        if let Some(action) = self.confirm.clone() {
            egui::Window::new("Unsaved changes")
                .collapsible(false)
                .resizable(false)
                .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
                .show(ctx, |ui| {
                    ui.label("The scene has unsaved changes. Discard them?");
                    ui.horizontal(|ui| {
                        if ui.button("Discard").clicked() {
                            chosen = Some(StudioAction::Discard(Box::new(action.clone())));
                            self.confirm = None;
                        }
                        if ui.button("Cancel").clicked() {
                            self.confirm = None;
                        }
                    });
                });
        }
        chosen
    }
}

/// Carries out file and edit actions.
#[allow(clippy::too_many_arguments)]
pub fn run_actions(
    mut actions: MessageReader<StudioAction>,
    mut doc: ResMut<SceneDocument>,
    mut project: ResMut<OpenProject>,
    mut rests: ResMut<RestMeshes>,
    mut selection: ResMut<Selection>,
    mut dialogs: ResMut<FileDialogs>,
    mut notices: ResMut<Notices>,
    mut frame: ResMut<FramePending>,
    mut frame_selected: ResMut<crate::camera::FrameRequest>,
    mut edits: MessageWriter<DocumentCommand>,
    mut exit: MessageWriter<AppExit>,
    mut export: ResMut<ExportJob>,
    mut autosave: ResMut<crate::autosave::Autosave>,
) {
    let mut queue: std::collections::VecDeque<StudioAction> = actions.read().cloned().collect();
    while let Some(action) = queue.pop_front() {
        let (action, confirmed) = match action {
            StudioAction::Discard(a) => (*a, true),
            a => (a, false),
        };
        let project_dir = project.0.path().and_then(|p| p.parent()).map(PathBuf::from);
        let needs_confirm = matches!(
            action,
            StudioAction::New | StudioAction::Open | StudioAction::OpenPath(_) | StudioAction::Quit
        );
        if needs_confirm && doc.is_modified() && !confirmed {
            dialogs.confirm = Some(action);
            continue;
        }
        let mut notice = |r: Result<String, String>| notices.push_result(r);
        let exports_animation = matches!(action, StudioAction::ExportAnimationPath(_));
        match action {
            StudioAction::New => {
                replace_project(
                    Project::new_empty(),
                    &mut doc,
                    &mut project,
                    &mut rests,
                    &mut selection,
                    &mut frame,
                );
            }
            StudioAction::Open => dialogs.open(DialogPurpose::Open, project_dir),
            StudioAction::OpenPath(path) => match Project::open(&path) {
                Ok((p, warnings)) => {
                    replace_project(
                        p,
                        &mut doc,
                        &mut project,
                        &mut rests,
                        &mut selection,
                        &mut frame,
                    );
                    for w in warnings {
                        notice(Err(w.to_string()));
                    }
                    notice(Ok(format!("opened {}", path.display())));
                }
                Err(e) => notice(Err(ductile_io::report(&e))),
            },
            StudioAction::Save => {
                if project.0.path().is_none() {
                    dialogs.open(DialogPurpose::SaveAs, project_dir);
                } else {
                    project
                        .0
                        .set_state(doc.document().clone(), doc.history().clone());
                    match project.0.save() {
                        Ok(()) => {
                            doc.mark_saved();
                            notice(Ok(format!("saved {}", project.0.display_name())));
                        }
                        Err(e) => notice(Err(ductile_io::report(&e))),
                    }
                }
            }
            StudioAction::SaveAs => dialogs.open(DialogPurpose::SaveAs, project_dir),
            StudioAction::SaveAsPath(path) => {
                project
                    .0
                    .set_state(doc.document().clone(), doc.history().clone());
                match project.0.save_as(&path) {
                    Ok(()) => {
                        // Mesh sources may have been rewritten relative to the new place.
                        let (document, history) =
                            (project.0.document().clone(), project.0.history().clone());
                        if &document != doc.document() || &history != doc.history() {
                            doc.replace(history, document);
                        }
                        doc.mark_saved();
                        notice(Ok(format!("saved {}", path.display())));
                    }
                    Err(e) => notice(Err(ductile_io::report(&e))),
                }
            }
            StudioAction::ImportMesh => dialogs.open(DialogPurpose::Import, project_dir),
            StudioAction::ImportPath(path) => match ductile_io::mesh_parts(&path) {
                Ok(parts) if parts.len() > 1 => {
                    dialogs.parts = Some(PartChoice::new(path, parts));
                }
                Ok(_) => {
                    queue.push_back(StudioAction::ImportPart(path, None));
                }
                Err(e) => notice(Err(ductile_io::report(&e))),
            },
            StudioAction::ImportPart(path, part) => {
                project
                    .0
                    .set_state(doc.document().clone(), doc.history().clone());
                match project.0.import_mesh_part(&path, part.as_deref()) {
                    Ok(imported) => {
                        if let ductile_scene::document::NodeKind::Mesh(m) = &imported.node.kind {
                            rests.insert(m.source.clone(), (*imported.rest).clone());
                        }
                        selection.node = Some(imported.node.name.clone());
                        let op = Operation::add_node(doc.shown(), imported.node);
                        edits.write(DocumentCommand::Apply {
                            op: Box::new(op),
                            label: match &part {
                                Some(p) => format!("import {}#{p}", path.display()),
                                None => format!("import {}", path.display()),
                            },
                            gesture: None,
                        });
                        frame.0 = true;
                    }
                    Err(e) => notice(Err(ductile_io::report(&e))),
                }
            }
            StudioAction::ExportGltf => dialogs.open(DialogPurpose::Export, project_dir),
            StudioAction::ExportPath(path) => {
                project
                    .0
                    .set_state(doc.document().clone(), doc.history().clone());
                match project.0.export_gltf(&path) {
                    Ok(()) => notice(Ok(format!("exported {}", path.display()))),
                    Err(e) => notice(Err(ductile_io::report(&e))),
                }
            }
            StudioAction::ExportAnimation => {
                dialogs.open(DialogPurpose::ExportAnimation, project_dir);
            }
            StudioAction::ExportAnimationPath(path) | StudioAction::ExportMorphsPath(path) => {
                if export.0.is_some() {
                    notice(Err(
                        "an export is still running; wait for it to finish".into()
                    ));
                    continue;
                }
                project
                    .0
                    .set_state(doc.document().clone(), doc.history().clone());
                // The meshes are loaded here (cached); the bake runs in the background with
                // its progress in the status bar.
                let scene = match project.0.loaded_scene() {
                    Ok(s) => s,
                    Err(e) => {
                        notice(Err(ductile_io::report(&e)));
                        continue;
                    }
                };
                let out = path.clone();
                let what = format!("exporting {}", path.display());
                export.0 = Some(RunningExport::spawn(what, move |progress| {
                    let start = std::time::Instant::now();
                    let seconds = || start.elapsed().as_secs_f64();
                    let result = if exports_animation {
                        let options = ductile_io::bake::BakeOptions::timeline(&scene.document);
                        ductile_io::bake::export_animation(&scene, &out, &options, progress).map(
                            |report| {
                                format!(
                                    "exported {}: {} frames, {} morph targets, in {:.1} s",
                                    out.display(),
                                    report.samples.len(),
                                    report.targets.iter().map(|(_, n)| n).sum::<usize>(),
                                    seconds()
                                )
                            },
                        )
                    } else {
                        ductile_io::bake::export_variant_morphs(&scene, &out, progress).map(
                            |names| {
                                format!(
                                    "exported {}: morph targets {}, in {:.1} s",
                                    out.display(),
                                    names.join(", "),
                                    seconds()
                                )
                            },
                        )
                    };
                    result.map_err(|e| ductile_io::report(&e))
                }));
            }
            StudioAction::ExportMorphs => dialogs.open(DialogPurpose::ExportMorphs, project_dir),
            StudioAction::Undo => {
                edits.write(DocumentCommand::Undo);
            }
            StudioAction::Redo => {
                edits.write(DocumentCommand::Redo);
            }
            StudioAction::Delete => {
                if let Some(name) = selection.node.clone() {
                    match Operation::remove_node_and_references(doc.shown(), &name) {
                        Ok(op) => {
                            edits.write(DocumentCommand::Apply {
                                op: Box::new(op),
                                label: format!("delete '{name}'"),
                                gesture: None,
                            });
                            selection.node = None;
                            selection.layer = None;
                        }
                        Err(e) => notice(Err(e.to_string())),
                    }
                }
            }
            StudioAction::FrameSelected => frame_selected.0 = true,
            StudioAction::Quit => {
                // Quitting after "Discard" drops the unsaved edits: no recovery file stays.
                autosave.discard_on_exit = confirmed;
                exit.write(AppExit::Success);
            }
            StudioAction::Discard(_) => {}
        }
    }
}

fn replace_project(
    p: Project,
    doc: &mut SceneDocument,
    project: &mut OpenProject,
    rests: &mut RestMeshes,
    selection: &mut Selection,
    frame: &mut FramePending,
) {
    doc.replace(p.history().clone(), p.document().clone());
    doc.mark_saved();
    rests.clear();
    *selection = Selection::default();
    frame.0 = true;
    project.0 = p;
}
