//! Model and project files: export and import model.json, save and open a project. Each returns
//! its failure (the session is left as it was) for the caller to show: the error window, or the
//! in-app path field that asked for the file.
use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};

use crate::io::atomic::write_atomic;
use crate::io::model_file::{ModelFile, structures_from_model, write_model};
use crate::io::project::load_project;
use crate::ui::app::App;
use crate::ui::project_io;
use crate::ui::state::command::FileAction;
use crate::ui::state::session::file_label;
use crate::workflow::model_file::{new_model_file, output_entry};
use crate::workflow::uncertainty::parameter_covariance;

impl App {
    /// Show an error until dismissed (and name it in the status bar).
    pub(super) fn push_error(&mut self, error: &anyhow::Error) {
        let message = format!("{error:#}");
        self.view.status = Some(message.lines().next().unwrap_or_default().to_owned());
        self.view.errors.retain(|e| *e != message);
        self.view.errors.push(message);
    }

    /// Carry out a file action on `path`; on success the status bar says what was done.
    pub(super) fn file_action(&mut self, action: FileAction, path: &Path) -> Result<()> {
        match action {
            FileAction::ExportModel => self.export_model(path),
            FileAction::ImportModel => self.import_model(path),
            FileAction::SaveProject => self.save_project(path),
            FileAction::OpenProject => self.open_project(path),
            FileAction::OpenFleet => {
                self.open_fleet(path);
                Ok(())
            }
        }
    }

    /// Compute the fleet of the manifest at `path` in the background and show the History view;
    /// its errors are shown there, and the session is not touched.
    fn open_fleet(&mut self, path: &Path) {
        self.view.views.history.open(path.to_owned());
        self.view.tab = crate::ui::state::Tab::History;
        self.view.status = Some(format!("Fleet {}: see the History view", file_label(path)));
    }

    fn export_model(&mut self, path: &Path) -> Result<()> {
        self.refresh();
        let (written, skipped, uncertain) = self
            .model_file()
            .and_then(|(file, skipped, uncertain)| {
                write_model(path, &file)?;
                Ok((file.outputs.len(), skipped, uncertain))
            })
            .with_context(|| format!("exporting the model to {}", path.display()))?;
        let mut status = format!("Exported {written} output model(s) to {}", file_label(path));
        if !skipped.is_empty() {
            status += &format!("; not exported (no valid model): {}", skipped.join(", "));
        }
        if !uncertain.is_empty() {
            status += &format!("; without a parameter covariance: {}", uncertain.join("; "));
        }
        self.view.status = Some(status);
        Ok(())
    }

    /// The committed model of every output that has one (with its parameter covariance from the
    /// identification run, as the batch stores it), the names of those that have none, and why an
    /// output's covariance could not be estimated.
    fn model_file(&self) -> Result<(ModelFile, Vec<String>, Vec<String>)> {
        let Some(ident) = &self.cache.ident else {
            bail!("there is no identification run, so there is no model");
        };
        let mut file = new_model_file(&ident.run);
        let (mut skipped, mut uncertain) = (Vec::new(), Vec::new());
        for output in &ident.outputs {
            let Ok(live) = &output.live else {
                skipped.push(output.name.clone());
                continue;
            };
            if live.effects.model.is_none() && !live.effects.requested.is_empty() {
                // Exporting it without the effects the user asked for would be a different model.
                skipped.push(format!("{} (its effects could not be added)", output.name));
                continue;
            }
            let current = live.current_model();
            let mut entry = output_entry(&live.model, &current, &output.unit);
            if let Ok(fits) = &output.fits {
                match parameter_covariance(fits, &current, &ident.run, &output.setup.settings) {
                    Ok(covariance) => entry.covariance = Some(covariance),
                    Err(e) => uncertain.push(format!("{}: {e}", output.name)),
                }
            }
            file.outputs.push(entry);
        }
        if file.outputs.is_empty() {
            bail!("no output has a valid model ({})", skipped.join(", "));
        }
        Ok((file, skipped, uncertain))
    }

    /// Take the clusters of every output the file and the identification run share, as one
    /// undoable change; the model is fitted again on the session's runs.
    fn import_model(&mut self, path: &Path) -> Result<()> {
        self.refresh();
        let clusters = (|| {
            let Some(ident) = &self.cache.ident else {
                bail!("open an identification run first: clusters are fitted on it");
            };
            let saved = structures_from_model(path, ident.run.dt_secs)?;
            let shared: Vec<_> = saved
                .into_iter()
                .filter(|(name, _)| ident.output(name).is_some())
                .map(|(name, s)| (name, s.clusters, s.dead_time_samples))
                .collect();
            if shared.is_empty() {
                let in_file = crate::io::model_file::read_model(path)?;
                let names: Vec<&str> = in_file.outputs.iter().map(|o| o.name.as_str()).collect();
                bail!(
                    "the model's outputs with clusters ({}) are not outputs of the identification run ({})",
                    names.join(", "),
                    ident.outputs.iter().map(|o| o.name.as_str()).collect::<Vec<_>>().join(", ")
                );
            }
            Ok(shared)
        })();
        let clusters = clusters.context("importing a model (the clusters were kept)")?;
        let names: Vec<String> = clusters.iter().map(|(name, _, _)| name.clone()).collect();
        let status = format!(
            "Imported the clusters of {} from {}; the model is fitted again on the session's runs",
            names.join(", "),
            file_label(path)
        );
        self.edit_setup(&status, |setup| {
            // The model's input dead time comes with its clusters: it is part of the structure the
            // clusters were chosen with.
            for (name, clusters, dead_time) in clusters {
                let output = setup.output_mut(&name);
                output.clusters = Some(clusters);
                output.settings.dead_time_samples = Some(dead_time);
            }
        });
        self.view.status = Some(status);
        Ok(())
    }

    fn save_project(&mut self, path: &Path) -> Result<()> {
        let notes = project_io::project_text(&self.session, path)
            .and_then(|(text, notes)| write_atomic(path, text.as_bytes()).map(|()| notes))
            .with_context(|| format!("saving the project to {}", path.display()))?;
        let mut status = format!("Saved the project as {}", file_label(path));
        for note in notes {
            status += &format!("; {note}");
        }
        self.view.status = Some(status);
        Ok(())
    }

    /// Replace the session by the project's, unless none of its runs can be read.
    fn open_project(&mut self, path: &Path) -> Result<()> {
        let project = load_project(path).context("opening a project (the session was kept)")?;
        let (mut session, failures) = project_io::session_from_project(&project)
            .with_context(|| format!("opening {} (the session was kept)", path.display()))?;
        if session.runs.is_empty() {
            let why = failures.iter().map(|f| f.message.as_str()).collect::<Vec<_>>().join("; ");
            return Err(anyhow!("none of the project's runs could be read: {why}")
                .context(format!("opening {} (the session was kept)", path.display())));
        }
        session.revision = self.session.revision + 1;
        let loaded = session.runs.len();
        let failed = failures.len();
        let mut app = App::with_failures(session, failures);
        app.view.tab = self.view.tab;
        app.view.output = self.view.output.take();
        *self = app;
        self.view.status = Some(format!(
            "Opened project {} ({loaded} run(s){})",
            file_label(path),
            if failed > 0 { format!(", {failed} could not be read") } else { String::new() }
        ));
        Ok(())
    }
}
