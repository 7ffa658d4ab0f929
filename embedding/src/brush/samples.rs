//! The surface points a brush is fitted over, kept apart from whatever tessellation a viewer shows.
//!
//! A brush's least-squares problem needs samples a few times denser than the control points, no
//! more: the spline cannot follow a field more finely than its grid. Fitted over the viewer's own
//! vertices, a dab at 10⁶ vertices did 20 times the work of one at 10⁵ (finding, hashing and
//! thinning half a million reached rows) and gave a slightly different edit, and a tessellation
//! that is not mirror-symmetric broke a symmetric stroke's symmetry. So the samples are a t_e = t_r
//! tessellation of the surface's own, of about [`SAMPLES_PER_CONTROL_POINT`] vertices per control
//! point: the same brush does the same edit at any display resolution, at a cost that does not grow
//! with it, and the samples are as symmetric as the surface.

use charts::ChartPoint;
use charts::{MAX_RESOLUTION, Tessellation};

use crate::EmbeddingError;
use crate::spline_surface::{ControlId, Surface};
use crate::stencil::{ColumnIndex, Stencil};
use crate::surface::{Point3, SplineSettings, Vector3};

use super::{BrushSamples, outward};

/// Sample vertices per control point of the whole surface. A dab reaches a quarter to a half of
/// the surface through its control points' supports, so this gives its fit 16 to 32 samples per
/// moving control point, about as many as the viewer's own vertices gave at 10⁵ (where footprints
/// and each brush's effect had been measured), and the fit stays well determined.
pub const SAMPLES_PER_CONTROL_POINT: usize = 4;

/// At least this many samples, whatever the grid: a disc of the editor's smallest radius (1% of the
/// model's size) then still holds several on a plate or a sphere (whose area is about the square of
/// its diagonal), where a coarse grid's 4 per control point would leave it empty and the brush
/// would do nothing.
pub const MIN_SAMPLES: usize = 25_000;

/// A surface's brush samples: their chart points and triangles, their stencil and its column
/// index, and as of the last [`SurfaceSamples::refresh`] (or [`SurfaceSamples::controls_moved`])
/// their exact positions and tangents, their areas and the normals' orientation.
#[derive(Clone, Debug)]
pub struct SurfaceSamples {
    /// What the stencil was built for: a surface of another genus or spline settings needs new
    /// samples.
    genus: u32,
    settings: SplineSettings,
    points: Vec<ChartPoint>,
    triangles: Vec<[u32; 3]>,
    stencil: Stencil,
    columns: ColumnIndex,
    positions: Vec<Point3>,
    tangents: Vec<[Vector3; 2]>,
    areas: Vec<f64>,
    outward: f64,
}

impl SurfaceSamples {
    /// Tessellates `surface` for its brushes and evaluates the samples.
    pub fn new(surface: &Surface) -> Result<SurfaceSamples, EmbeddingError> {
        let control_count = surface.control_points().len();
        let t = resolution(surface.genus(), control_count);
        let tessellation = surface.atlas().tessellate(t, t)?;
        let stencil = Stencil::build_parallel(&surface.layout(), &tessellation.vertices);
        let columns = stencil.column_index(control_count);
        let n = stencil.rows();
        let mut samples = SurfaceSamples {
            genus: surface.genus(),
            settings: surface.settings(),
            points: tessellation.vertices,
            triangles: tessellation.triangles,
            stencil,
            columns,
            positions: vec![Point3::origin(); n],
            tangents: vec![[Vector3::zeros(); 2]; n],
            areas: Vec::new(),
            outward: 1.0,
        };
        samples.refresh(surface);
        Ok(samples)
    }

    /// Whether these samples were made for `surface`'s genus and spline settings (else make new
    /// ones).
    pub fn fits(&self, surface: &Surface) -> bool {
        self.genus == surface.genus() && self.settings == surface.settings()
    }

    /// Every sample's position, tangents and area, and the normals' orientation, anew.
    pub fn refresh(&mut self, surface: &Surface) {
        self.evaluate(surface.control_points(), 0..self.stencil.rows());
        self.areas = crate::fit::vertex_areas(&self.positions, &self.triangles);
        self.outward = outward(&self.positions, &self.tangents, &self.areas);
    }

    /// After `controls` moved: the positions and tangents of the samples they reach, exactly (the
    /// areas and orientation stay as they were at the last refresh: a stroke's dabs weight their
    /// samples alike).
    pub fn controls_moved(&mut self, surface: &Surface, controls: &[ControlId]) {
        let rows = self
            .stencil
            .rows_of_controls(&self.columns, controls.iter().map(|c| c.index()));
        self.evaluate(
            surface.control_points(),
            rows.into_iter().map(|r| r as usize),
        );
    }

    /// The positions and tangents of `rows` from `control`.
    fn evaluate(&mut self, control: &[Point3], rows: impl Iterator<Item = usize>) {
        for r in rows {
            (self.positions[r], self.tangents[r]) = self.stencil.position_and_tangents(control, r);
        }
    }

    /// The samples as a brush reads them, with `surface`'s layout and control points.
    pub fn view<'a>(&'a self, surface: &'a Surface) -> BrushSamples<'a> {
        BrushSamples {
            layout: surface.layout(),
            control: surface.control_points(),
            points: &self.points,
            stencil: &self.stencil,
            columns: &self.columns,
            positions: &self.positions,
            tangents: &self.tangents,
            areas: &self.areas,
            outward: self.outward,
        }
    }
}

/// The smallest t_e = t_r whose tessellation has [`SAMPLES_PER_CONTROL_POINT`] vertices per control
/// point, and [`MIN_SAMPLES`] at least (a closed triangle mesh has about half as many vertices as
/// triangles).
fn resolution(genus: u32, control_count: usize) -> u32 {
    let wanted = 2 * (SAMPLES_PER_CONTROL_POINT * control_count).max(MIN_SAMPLES) as u64;
    (4..MAX_RESOLUTION)
        .find(|&t| Tessellation::expected_triangles(genus, t, t) >= wanted)
        .unwrap_or(MAX_RESOLUTION)
}
