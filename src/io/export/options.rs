//! What an export is asked for beyond the mesh: encoding, up axis, size and units, texture
//! coordinate layout, the object's name; and each format's conventions for them.

use std::borrow::Cow;

use embedding::Vector3;

use super::{Encoding, ExportError, Format, SurfaceMesh};

/// Which axis points up in the file.
///
/// ntori's surfaces are plates whose thin axis is z: z is the model's own up. A Y-up file gets
/// every point and normal turned by −90° about the x axis, (x, y, z) → (x, z, −y): a rotation
/// (determinant +1), so triangles keep their winding and normals stay outward.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Up {
    /// +y up: glTF's convention (by its specification), and how Blender and most viewers read OBJ.
    Y,
    /// +z up, the model's own: how PLY, STL, 3MF and OFF are read (slicers, Blender's PLY and STL
    /// importers).
    Z,
}

impl Up {
    /// `v` in a file whose up axis is `self` (the model's up is z).
    pub fn apply(self, v: Vector3) -> Vector3 {
        match self {
            Up::Z => v,
            Up::Y => Vector3::new(v.x, v.z, -v.y),
        }
    }

    /// The model's vector for `v` read from a file whose up axis is `self` ([`Up::apply`]'s inverse).
    pub fn unapply(self, v: Vector3) -> Vector3 {
        match self {
            Up::Z => v,
            Up::Y => Vector3::new(v.x, -v.z, v.y),
        }
    }
}

/// A unit of length.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Units {
    /// Millimetres.
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Inches.
    In,
}

impl Units {
    /// The unit in metres.
    pub fn metres(self) -> f64 {
        match self {
            Units::Mm => 0.001,
            Units::Cm => 0.01,
            Units::M => 1.0,
            Units::In => 0.0254,
        }
    }

    /// The unit's symbol.
    pub fn symbol(self) -> &'static str {
        match self {
            Units::Mm => "mm",
            Units::Cm => "cm",
            Units::M => "m",
            Units::In => "in",
        }
    }
}

/// How the texture coordinates are laid out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum UvLayout {
    /// Each vertex's home chart coordinates moved into [0, 1]²: every chart uses the whole square,
    /// so the charts overlap, and a triangle whose corners have different home charts spans a seam.
    #[default]
    Chart,
    /// A packed atlas: each chart's region in its own tile of a grid in [0, 1]², vertices
    /// duplicated where triangles of different charts meet, so a texture can be painted and baked.
    Atlas,
}

/// What an export writes besides the mesh (see [`super::export_surface`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ExportOptions {
    /// Binary or text (PLY and STL only).
    pub encoding: Encoding,
    /// The file's up axis; `None`: the format's convention ([`Format::default_up`]).
    pub up: Option<Up>,
    /// One model unit becomes `scale` × `units`.
    pub scale: f64,
    pub units: Units,
    /// The texture coordinates' layout (formats that store them: OBJ, PLY, GLB).
    pub uv: UvLayout,
    /// The object's name in the file; `None`: "ntori genus-N surface".
    pub name: Option<String>,
}

/// The default size: a model unit is a centimetre, so a default genus-2 model (about 6 units
/// across) is a 6 cm object in every format: 0.06 in a glTF (metres), 60 in an STL or 3MF
/// (millimetres), and its own coordinates, unchanged, in OBJ, PLY and OFF.
pub const DEFAULT_UNITS: Units = Units::Cm;

/// The longest object name written (longer names are cut).
pub const MAX_NAME_CHARS: usize = 200;

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions {
            encoding: Encoding::Binary,
            up: None,
            scale: 1.0,
            units: DEFAULT_UNITS,
            uv: UvLayout::Chart,
            name: None,
        }
    }
}

impl Format {
    /// The unit a format's numbers are in by its specification or convention: glTF's are metres,
    /// 3MF declares millimetres (ntori writes `unit="millimeter"`), and STL, which has no field for
    /// it, is read as millimetres by slicers. OBJ, PLY and OFF have none.
    pub fn unit(self) -> Option<Units> {
        match self {
            Format::Glb => Some(Units::M),
            Format::Stl | Format::ThreeMf => Some(Units::Mm),
            Format::Obj | Format::Ply | Format::Off => None,
        }
    }

    /// The up axis readers of the format expect: y for glTF (its specification) and OBJ (Blender,
    /// most viewers), z for PLY, STL, 3MF and OFF.
    pub fn default_up(self) -> Up {
        match self {
            Format::Glb | Format::Obj => Up::Y,
            Format::Ply | Format::Stl | Format::ThreeMf | Format::Off => Up::Z,
        }
    }

    /// Whether the format stores texture coordinates (and so whether `--uv` means anything).
    pub fn has_uvs(self) -> bool {
        matches!(self, Format::Obj | Format::Ply | Format::Glb)
    }
}

impl ExportOptions {
    /// Refuses options that do not apply to `format`, and a scale that is not a finite positive
    /// number (zero would collapse the mesh, a negative one mirror it inside out).
    pub fn check(&self, format: Format) -> Result<(), ExportError> {
        if self.encoding == Encoding::Ascii && !format.has_encodings() {
            return Err(ExportError::NoEncodings(format));
        }
        if self.uv == UvLayout::Atlas && !format.has_uvs() {
            return Err(ExportError::NoUvs(format));
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(ExportError::Scale(self.scale));
        }
        Ok(())
    }

    /// The up axis of a `format` file.
    pub fn up_for(&self, format: Format) -> Up {
        self.up.unwrap_or(format.default_up())
    }

    /// The unit a `format` file's numbers are in: the format's own, or `units` where it has none.
    pub fn unit_for(&self, format: Format) -> Units {
        format.unit().unwrap_or(self.units)
    }

    /// What a model coordinate is multiplied by in a `format` file.
    pub fn factor_for(&self, format: Format) -> f64 {
        self.scale * self.units.metres() / self.unit_for(format).metres()
    }

    /// The object's name: the one given (control characters replaced by spaces, trimmed, at most
    /// [`MAX_NAME_CHARS`] characters), else "ntori genus-N surface".
    pub fn object_name(&self, genus: u32) -> String {
        let given: String = self
            .name
            .as_deref()
            .unwrap_or("")
            .chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .take(MAX_NAME_CHARS)
            .collect();
        let given = given.trim();
        if given.is_empty() {
            format!("ntori genus-{genus} surface")
        } else {
            given.to_owned()
        }
    }
}

impl SurfaceMesh {
    /// The mesh as a file with up axis `up` holds it, every coordinate multiplied by `factor`
    /// (positive): positions turned and scaled, normals turned. Winding and orientation are
    /// kept (the turn is a rotation). Borrowed when there is nothing to do.
    pub fn placed(&self, up: Up, factor: f64) -> Cow<'_, SurfaceMesh> {
        if up == Up::Z && factor == 1.0 {
            return Cow::Borrowed(self);
        }
        let mut mesh = self.clone();
        mesh.place(up, factor);
        Cow::Owned(mesh)
    }

    /// [`SurfaceMesh::placed`] in place.
    pub fn place(&mut self, up: Up, factor: f64) {
        if up == Up::Z && factor == 1.0 {
            return;
        }
        for p in &mut self.positions {
            p.coords = up.apply(p.coords) * factor;
        }
        for n in &mut self.normals {
            *n = up.apply(*n);
        }
    }
}

/// What a format writer needs besides the mesh.
#[derive(Clone, Debug)]
pub(super) struct FileInfo {
    /// The object's name ([`ExportOptions::object_name`]).
    pub name: String,
    /// The unit the numbers are in.
    pub unit: Units,
    pub up: Up,
    pub encoding: Encoding,
}

impl FileInfo {
    pub fn new(mesh: &SurfaceMesh, format: Format, options: &ExportOptions) -> FileInfo {
        FileInfo {
            name: options.object_name(mesh.genus),
            unit: options.unit_for(format),
            up: options.up_for(format),
            encoding: options.encoding,
        }
    }

    /// "+z up, millimetres", for comments.
    pub fn frame(&self) -> String {
        let axis = match self.up {
            Up::Y => "+y",
            Up::Z => "+z",
        };
        format!("{axis} up, units: {}", self.unit.symbol())
    }
}
