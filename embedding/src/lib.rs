//! # embedding: the surface layer of ntori
//!
//! Will hold the spline patch per chart, the blend functions forming a partition of unity, the
//! surface S(p) with its derivatives, the stencils, the initial fit and the edit solver (issues 4, 5).
//! It builds on [`charts`] and nothing in `charts` depends on it.

pub use charts;
