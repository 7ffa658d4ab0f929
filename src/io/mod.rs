//! Everything ntori reads from or writes to files: atomic writes ([`atomic`]), model files
//! ([`model_file`]) and mesh exports ([`export`], one file per format).
//!
//! Nothing here draws or edits; the formats' conventions live here and nowhere else.

pub mod atomic;
pub mod export;
pub mod model_file;
