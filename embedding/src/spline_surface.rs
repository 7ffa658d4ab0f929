//! [`Surface`]: an owned, validated surface — the atlas, the spline settings and every control
//! point — built once (by loading a model or by a fit) and never checked again by its users.
//!
//! A [`Model`] is the serde document a file holds; a `Surface` is what the program works with. The
//! conversion checks everything a file can get wrong (format, version, genus, settings, the number
//! of control points, finiteness); after it, [`Surface::layout`] cannot fail, and every consumer —
//! export, the renderer, the editor — evaluates through [`evaluate`](crate::evaluate::evaluate).

use std::sync::Arc;

use charts::{Atlas, ChartPoint, Lft};

use crate::EmbeddingError;
use crate::model::{DISK_GRID_VERSION, Model, ModelHeader, ModelPin, PINS_VERSION};
use crate::surface::{Bases, Layout, Point3, SplineSettings, SurfaceJet};

/// A control point's index in [`Layout`] order (chart-major, then row-major in the chart's grid).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct ControlId(pub u32);

impl ControlId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// An owned, validated surface (see the module documentation), with its pins. Two surfaces are equal
/// when their genus, settings, control points and pins are.
#[derive(Clone, Debug)]
pub struct Surface {
    atlas: Arc<Atlas>,
    settings: SplineSettings,
    bases: Bases,
    control: Vec<Point3>,
    /// Surface points the editor holds in place (each inside its chart's domain).
    pins: Vec<ChartPoint>,
}

impl PartialEq for Surface {
    fn eq(&self, other: &Surface) -> bool {
        self.genus() == other.genus()
            && self.settings == other.settings
            && self.control == other.control
            && self.pins == other.pins
    }
}

impl Surface {
    /// A surface over `atlas` with `settings` and `control` points in layout order. Refuses
    /// unsupported settings, the wrong number of points and non-finite coordinates.
    pub fn new(
        atlas: Arc<Atlas>,
        settings: SplineSettings,
        control: Vec<Point3>,
    ) -> Result<Surface, EmbeddingError> {
        let bases = Layout::new(&atlas, settings)?.bases();
        let surface = Surface {
            atlas,
            settings,
            bases,
            control: Vec::new(),
            pins: Vec::new(),
        };
        surface.check_points(&control)?;
        Ok(Surface { control, ..surface })
    }

    /// The surface a model document describes, with every check a file needs (header, genus,
    /// settings, control point count, finiteness).
    pub fn from_model(model: &Model) -> Result<Surface, EmbeddingError> {
        ModelHeader {
            format: model.format.clone(),
            version: model.version,
        }
        .check()?;
        if !model.pins.is_empty() && model.version < PINS_VERSION {
            return Err(EmbeddingError::BadPin {
                index: 0,
                problem: format!(
                    "is in a version {} model; pins need version {PINS_VERSION}",
                    model.version
                ),
            });
        }
        if let Some(grid) = model.settings.disk_grid
            && model.version < DISK_GRID_VERSION
        {
            return Err(EmbeddingError::DiskGridVersion {
                grid,
                version: model.version,
            });
        }
        let atlas = Arc::new(Atlas::new(model.genus)?);
        let pins = model
            .pins
            .iter()
            .enumerate()
            .map(|(index, pin)| {
                let chart = Some(pin.chart)
                    .filter(|&c| (c as usize) < atlas.charts().len())
                    .ok_or_else(|| EmbeddingError::BadPin {
                        index,
                        problem: format!(
                            "names chart {}; this genus has charts 0 to {}",
                            pin.chart,
                            atlas.charts().len() - 1
                        ),
                    })?;
                Ok(ChartPoint::new(
                    charts::ChartId(chart),
                    num_complex::Complex64::new(pin.at[0], pin.at[1]),
                ))
            })
            .collect::<Result<Vec<_>, EmbeddingError>>()?;
        let mut surface = Surface::new(atlas, model.settings, model.points())?;
        surface.set_pins(pins)?;
        Ok(surface)
    }

    /// The model document of this surface, in the oldest version that holds it: 1 without pins
    /// or a disk grid (every build reads it), [`PINS_VERSION`] with pins,
    /// [`crate::model::DISK_GRID_VERSION`] with a disk grid.
    pub fn to_model(&self) -> Model {
        let mut model = Model::from_points(&self.layout(), &self.control);
        if !self.pins.is_empty() {
            model.version = model.version.max(PINS_VERSION);
            model.pins = self
                .pins
                .iter()
                .map(|p| ModelPin {
                    chart: p.chart.0,
                    at: [p.coords.re, p.coords.im],
                })
                .collect();
        }
        model
    }

    /// The pinned surface points.
    pub fn pins(&self) -> &[ChartPoint] {
        &self.pins
    }

    /// Replaces the pins; each must lie in its chart's domain, with finite coordinates (on error
    /// nothing changes).
    pub fn set_pins(&mut self, pins: Vec<ChartPoint>) -> Result<(), EmbeddingError> {
        for (index, p) in pins.iter().enumerate() {
            let bad = |problem: String| EmbeddingError::BadPin { index, problem };
            let chart =
                self.atlas.charts().get(p.chart.index()).ok_or_else(|| {
                    bad(format!("names chart {}, which does not exist", p.chart.0))
                })?;
            if !(p.coords.re.is_finite() && p.coords.im.is_finite()) {
                return Err(bad("has a coordinate that is not a finite number".into()));
            }
            if !chart.domain().contains(p.coords) {
                return Err(bad(format!(
                    "at ({}, {}) lies outside chart {}'s domain",
                    p.coords.re, p.coords.im, p.chart.0
                )));
            }
        }
        self.pins = pins;
        Ok(())
    }

    /// The same atlas and settings with other control points (checked like [`Surface::new`]).
    pub fn with_control_points(&self, control: Vec<Point3>) -> Result<Surface, EmbeddingError> {
        self.check_points(&control)?;
        Ok(Surface {
            atlas: Arc::clone(&self.atlas),
            settings: self.settings,
            bases: self.bases,
            control,
            pins: self.pins.clone(),
        })
    }

    /// Replaces the control points (checked like [`Surface::new`]; on error nothing changes).
    pub fn set_control_points(&mut self, control: Vec<Point3>) -> Result<(), EmbeddingError> {
        self.check_points(&control)?;
        self.control = control;
        Ok(())
    }

    /// Sets some control points to new positions (checked: on error nothing changes).
    pub fn set_control_points_at(
        &mut self,
        updates: impl IntoIterator<Item = (ControlId, Point3)> + Clone,
    ) -> Result<(), EmbeddingError> {
        for (id, p) in updates.clone() {
            if id.index() >= self.control.len() {
                return Err(EmbeddingError::ControlCount {
                    found: id.index() + 1,
                    expected: self.control.len(),
                });
            }
            if !p.iter().all(|x| x.is_finite()) {
                return Err(EmbeddingError::NotFinite(id.index()));
            }
        }
        for (id, p) in updates {
            self.control[id.index()] = p;
        }
        Ok(())
    }

    pub fn genus(&self) -> u32 {
        self.atlas.genus()
    }
    pub fn atlas(&self) -> &Atlas {
        &self.atlas
    }
    /// The shared atlas, for another surface of the same genus.
    pub fn shared_atlas(&self) -> Arc<Atlas> {
        Arc::clone(&self.atlas)
    }
    pub fn settings(&self) -> SplineSettings {
        self.settings
    }
    /// The control points in layout order.
    pub fn control_points(&self) -> &[Point3] {
        &self.control
    }

    /// The layout of the control points over the atlas. Cannot fail: the settings were checked.
    pub fn layout(&self) -> Layout<'_> {
        Layout::from_checked(&self.atlas, self.bases, self.settings)
    }

    /// S and its first and second derivatives at `p`, in `p.chart`'s coordinates.
    pub fn eval(&self, p: ChartPoint) -> SurfaceJet {
        self.layout().eval(&self.control, p)
    }

    /// [`Surface::eval`] at a point already located: `reps` is what
    /// [`charts::Atlas::locate_with_transitions`] gives for `p`.
    pub(crate) fn eval_located(&self, p: ChartPoint, reps: &[(ChartPoint, Lft)]) -> SurfaceJet {
        self.layout().eval_located(&self.control, p, reps)
    }

    /// S at `p` (no derivatives: cheaper than [`Surface::eval`]).
    pub fn position(&self, p: ChartPoint) -> Point3 {
        self.layout().position(&self.control, p)
    }

    /// The diagonal of the control points' bounding box: the scale derivatives in chart units have.
    pub fn control_net_size(&self) -> f64 {
        crate::fit::diagonal(&self.control)
    }

    /// Whether the surface has no extent to speak of: its control points coincide (to 1e-12 of their
    /// magnitude), so no point of it has a normal. Export and rendering refuse such a surface.
    pub fn is_degenerate(&self) -> bool {
        let size = self.control_net_size();
        let largest = self
            .control
            .iter()
            .fold(0.0f64, |m, p| m.max(p.coords.amax()));
        size.is_nan() || size <= 1e-12 * largest
    }

    fn check_points(&self, control: &[Point3]) -> Result<(), EmbeddingError> {
        let expected = self.layout().control_count();
        if control.len() != expected {
            return Err(EmbeddingError::ControlCount {
                found: control.len(),
                expected,
            });
        }
        match control
            .iter()
            .position(|p| !p.coords.iter().all(|x| x.is_finite()))
        {
            Some(i) => Err(EmbeddingError::NotFinite(i)),
            None => Ok(()),
        }
    }
}
