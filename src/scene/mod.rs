//! Scene files (filled in by the scene module work).
