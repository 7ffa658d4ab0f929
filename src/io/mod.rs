//! Everything ntori reads from or writes to files: atomic writes ([`atomic`]), input files read
//! whole under a size cap ([`input`]), model files
//! ([`model_file`]), mesh exports ([`export`], one file per format) and users' meshes read and
//! checked for a fit ([`import`], one file per format).
//!
//! Nothing here draws or edits; the formats' conventions live here and nowhere else.

pub mod atomic;
pub mod export;
pub mod import;
pub mod input;
pub mod model_file;
