//! Visibility V(P, Q) for scenes that can occlude.
