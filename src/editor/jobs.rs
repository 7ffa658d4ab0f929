//! Work done off the UI thread: fitting a new model, importing a mesh (fitting it as `ntori fit`
//! does), refitting to new spline settings, exporting the mesh. One job at a time; its result comes back through a channel, and the app applies it
//! ([`super::commands::Command::JobDone`]).

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::{Duration, Instant};

use embedding::fit::{FitSettings, default_mesh, initial_model_of, vertex_areas};
use embedding::mesh_fit::{self, fit_user_mesh};
use embedding::{EmbeddingError, Layout, Point3, SplineSettings, Surface};

use super::state::EditorError;
use crate::io::export::{self, ExportError, Format};
use crate::io::import;

/// What a finished job produced.
#[derive(Debug)]
pub enum JobOutput {
    /// A new model was fitted.
    NewModel { genus: u32, surface: Surface },
    /// A user's mesh was fitted: the largest distance from its vertices to the surface (a fraction
    /// of its bounding-box diagonal) and the triangles the map folds (both 0 when all is well).
    Imported {
        path: PathBuf,
        genus: u32,
        surface: Surface,
        max_residual: f64,
        folded: usize,
    },
    /// The control points for `settings`, and how far the refitted surface lies from the old one
    /// at most.
    Refit {
        settings: SplineSettings,
        control: Vec<Point3>,
        worst: f64,
    },
    /// The mesh was written.
    Exported {
        exported: export::Exported,
        path: PathBuf,
    },
}

/// Why a job failed.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error("cannot make a genus-{genus} model: {source}")]
    NewModel { genus: u32, source: EmbeddingError },
    /// The mesh could not be read or is not one a fit takes (the message names the file).
    #[error("cannot import: {0}")]
    Import(String),
    #[error("cannot fit {}: {source}", .path.display())]
    ImportFit {
        path: PathBuf,
        source: EmbeddingError,
    },
    #[error("cannot refit: {0}")]
    Refit(#[source] EditorError),
    #[error("export failed: {0}")]
    Export(#[from] ExportError),
    #[error("a background job stopped unexpectedly")]
    Stopped,
}

pub type JobResult = Result<JobOutput, JobError>;

struct Job {
    what: String,
    started: Instant,
    receiver: Receiver<JobResult>,
}

/// The background job, if one runs.
#[derive(Default)]
pub struct Jobs {
    current: Option<Job>,
}

impl Jobs {
    pub fn busy(&self) -> bool {
        self.current.is_some()
    }

    /// What runs ("fitting a new genus-2 model"), and since when.
    pub fn running(&self) -> Option<(&str, Instant)> {
        self.current.as_ref().map(|j| (j.what.as_str(), j.started))
    }

    fn spawn(&mut self, what: String, work: impl FnOnce() -> JobResult + Send + 'static) {
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = sender.send(work());
        });
        self.current = Some(Job {
            what,
            started: Instant::now(),
            receiver,
        });
    }

    /// Fits a new model of `genus` (as `ntori new` does).
    pub fn new_model(&mut self, genus: u32, settings: SplineSettings) {
        self.spawn(format!("fitting a new genus-{genus} model"), move || {
            let fail = |source| JobError::NewModel { genus, source };
            // The input mesh as `ntori new` chooses it (choosing it builds it: fitted as built).
            let (resolution, mesh) = default_mesh(genus).map_err(fail)?;
            let fit = initial_model_of(
                mesh,
                resolution,
                settings,
                FitSettings::for_plate(genus, settings),
                &|_| {},
            )
            .map_err(fail)?;
            Ok(JobOutput::NewModel {
                genus,
                surface: fit.surface,
            })
        });
    }

    /// Reads, checks and fits the mesh at `path` (as `ntori fit` does, with its default grid).
    pub fn import_mesh(&mut self, path: PathBuf) {
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        self.spawn(format!("importing {name}"), move || {
            let read = import::read_mesh(&path).map_err(|e| JobError::Import(e.to_string()))?;
            let mut valid = import::validate(read, false)
                .and_then(|valid| import::check_fittable(&valid).map(|()| valid))
                .map_err(|e| JobError::Import(format!("{}: {e}", path.display())))?;
            // In the model's frame, as `ntori fit` places it by the format's conventions.
            import::Placement::for_file(&path, None, export::DEFAULT_UNITS)
                .place_points(&mut valid.positions);
            // `ntori fit`'s settings.
            let (settings, fit_settings) =
                mesh_fit::default_settings(valid.genus, valid.positions.len());
            let fit = fit_user_mesh(
                &valid.positions,
                &valid.triangles,
                settings,
                fit_settings,
                &|_| {},
            )
            .map(|user| user.fit)
            .map_err(|source| JobError::ImportFit {
                path: path.clone(),
                source,
            })?;
            Ok(JobOutput::Imported {
                max_residual: fit.max_residual / fit.mesh_diagonal,
                folded: fit.parameterization.folded,
                genus: fit.genus,
                surface: fit.surface,
                path,
            })
        });
    }

    /// Refits `surface` with other spline settings.
    pub fn refit(&mut self, surface: Surface, settings: SplineSettings) {
        let what = format!(
            "refitting to degree {}, C^{}, {}",
            settings.degree,
            settings.continuity,
            settings.grid_text()
        );
        self.spawn(what, move || {
            let (control, worst) = refit(&surface, settings).map_err(JobError::Refit)?;
            Ok(JobOutput::Refit {
                settings,
                control,
                worst,
            })
        });
    }

    /// Writes `surface`, tessellated as `meshing` says (the viewport's), to `path`, in the format
    /// its extension names.
    pub fn export(&mut self, surface: Surface, meshing: export::Meshing, path: PathBuf) {
        self.spawn("exporting".into(), move || {
            let format = Format::from_path(&path)?;
            let options = export::ExportOptions::default();
            let exported = export::export_surface(&surface, meshing, &path, format, &options)?;
            Ok(JobOutput::Exported { exported, path })
        });
    }

    /// The job's result if it is done; while it runs, a repaint is asked for soon.
    pub fn poll(&mut self, ctx: &egui::Context) -> Option<JobResult> {
        let job = self.current.as_ref()?;
        let result = match job.receiver.try_recv() {
            Ok(result) => result,
            Err(TryRecvError::Empty) => {
                ctx.request_repaint_after(Duration::from_millis(50));
                return None;
            }
            Err(TryRecvError::Disconnected) => Err(JobError::Stopped),
        };
        self.current = None;
        Some(result)
    }

    /// Blocks until the job, if any, is done, and returns its result.
    pub fn wait(&mut self) -> Option<JobResult> {
        let job = self.current.take()?;
        Some(job.receiver.recv().unwrap_or(Err(JobError::Stopped)))
    }
}

/// A model's control points for other spline settings: the new layout fitted (least squares, as the
/// initial fit does) to the current surface sampled at a tessellation's vertices. Returns the
/// control points and the largest distance between the two surfaces at the samples.
pub fn refit(
    surface: &Surface,
    settings: SplineSettings,
) -> Result<(Vec<Point3>, f64), EditorError> {
    let atlas = surface.atlas();
    let new = Layout::new(atlas, settings)?;
    // About four samples per control point along each side of a chart.
    let finest = |s: SplineSettings| s.grid.max(s.disk_grid());
    let t = (2 * finest(settings).max(finest(surface.settings()))).clamp(16, 96) as u32;
    let tessellation = atlas.tessellate(t, t)?;
    let stencil = embedding::Stencil::build_parallel(&surface.layout(), &tessellation.vertices);
    let mut targets = vec![Point3::origin(); stencil.rows()];
    stencil.positions(surface.control_points(), &mut targets);
    let weights = vertex_areas(&targets, &tessellation.triangles);
    let fitted = embedding::fit::fit(
        &new,
        &tessellation.vertices,
        &targets,
        &weights,
        FitSettings::default(),
    )?;
    let check = embedding::Stencil::build_parallel(&new, &tessellation.vertices);
    let mut now = vec![Point3::origin(); check.rows()];
    check.positions(&fitted, &mut now);
    let worst = now
        .iter()
        .zip(&targets)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    Ok((fitted, worst))
}
