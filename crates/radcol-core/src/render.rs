//! Rendering and per-vertex read-back of solutions.
