//! `ntori new`: the initial model of a genus, fitted to an n-holed mesh, with its checks.

use charts::Atlas;
use embedding::fit::{FitSettings, InitialFit, initial_model};
use embedding::integrals::surface_integrals;
use embedding::{Layout, Model, SplineSettings};
use serde::Serialize;

/// What `ntori new` made and how well it fits.
#[derive(Clone, Debug, Serialize)]
pub struct NewReport {
    pub genus: u32,
    pub settings: SplineSettings,
    pub smoothness: f64,
    pub mesh_vertices: usize,
    pub mesh_triangles: usize,
    pub control_points: usize,
    /// Relaxation sweeps of the parameterization, and triangles it folds (0: a bijection).
    pub sweeps: usize,
    pub folded_triangles: usize,
    /// |S(p_i) − P_i| over the mesh vertices, as fractions of the mesh's bounding-box diagonal.
    pub rms_residual: f64,
    pub max_residual: f64,
    pub diagonal: f64,
    /// ∫ K dA from the analytic curvature, and 2π(2 − 2n).
    pub total_curvature: f64,
    pub expected_curvature: f64,
    /// |∫K dA − 2π(2 − 2n)| / max(|2π(2 − 2n)|, ∫|K| dA).
    pub curvature_error: f64,
    pub area: f64,
    pub seconds: f64,
    pub passed: bool,
}

/// Largest relative Gauss–Bonnet error the check accepts (relative to ∫|K| dA for the torus).
pub const CURVATURE_TOLERANCE: f64 = 1e-3;
/// Largest residual, as a fraction of the diagonal, the check accepts.
pub const RESIDUAL_TOLERANCE: f64 = 0.01;

/// Fits the model and checks it. `stage` is told what is being done.
pub fn make(
    genus: u32,
    resolution: usize,
    settings: SplineSettings,
    fit: FitSettings,
    stage: &dyn Fn(&str),
) -> Result<(Model, NewReport), embedding::EmbeddingError> {
    let start = std::time::Instant::now();
    stage("meshing, flattening and fitting");
    let InitialFit {
        model,
        mesh,
        parameterization,
        rms_residual,
        max_residual,
        mesh_diagonal,
    } = initial_model(genus, resolution, settings, fit)?;
    stage("integrating the curvature");
    let atlas = Atlas::new(genus)?;
    let layout = Layout::new(&atlas, settings)?;
    let sums = surface_integrals(&layout, &model.points(), 8);
    let expected = std::f64::consts::TAU * (2.0 - 2.0 * f64::from(genus));
    let curvature_error =
        (sums.gaussian_curvature - expected).abs() / expected.abs().max(sums.absolute_curvature);
    let report = NewReport {
        genus,
        settings,
        smoothness: fit.smoothness,
        mesh_vertices: mesh.positions.len(),
        mesh_triangles: mesh.triangles.len(),
        control_points: model.control_points.len(),
        sweeps: parameterization.sweeps,
        folded_triangles: parameterization.folded,
        rms_residual: rms_residual / mesh_diagonal,
        max_residual: max_residual / mesh_diagonal,
        diagonal: mesh_diagonal,
        total_curvature: sums.gaussian_curvature,
        expected_curvature: expected,
        curvature_error,
        area: sums.area,
        seconds: start.elapsed().as_secs_f64(),
        passed: parameterization.folded == 0
            && curvature_error <= CURVATURE_TOLERANCE
            && max_residual <= RESIDUAL_TOLERANCE * mesh_diagonal,
    };
    Ok((model, report))
}

impl NewReport {
    pub fn to_text(&self) -> String {
        let verdict = |ok: bool| if ok { "ok" } else { "FAILED" };
        format!(
            "genus {genus}: degree {degree}, C^{cont} blends, {grid}×{grid} control grid per chart, \
             {controls} control points\n\
             input mesh: {v} vertices, {f} triangles, bounding-box diagonal {diag:.3}\n\
             parameterization: {sweeps} relaxation sweeps, {folded} folded triangles ({bij})\n\
             fit residual: rms {rms:.3}%, max {max:.3}% of the diagonal ({res})\n\
             Gauss–Bonnet: ∫K dA = {k:.6}, 2π(2 − 2n) = {e:.6}, relative error {gb:.1e} ({gbv})\n\
             area {area:.4}, {secs:.2} s\n",
            genus = self.genus,
            degree = self.settings.degree,
            cont = self.settings.continuity,
            grid = self.settings.grid,
            controls = self.control_points,
            v = self.mesh_vertices,
            f = self.mesh_triangles,
            diag = self.diagonal,
            sweeps = self.sweeps,
            folded = self.folded_triangles,
            bij = verdict(self.folded_triangles == 0),
            rms = 100.0 * self.rms_residual,
            max = 100.0 * self.max_residual,
            res = verdict(self.max_residual <= RESIDUAL_TOLERANCE),
            k = self.total_curvature,
            e = self.expected_curvature,
            gb = self.curvature_error,
            gbv = verdict(self.curvature_error <= CURVATURE_TOLERANCE),
            area = self.area,
            secs = self.seconds,
        )
    }
}
