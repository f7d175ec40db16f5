//! Synthetic tool paths with contact data for known surfaces (plane, extruded parabola,
//! hyperbolic paraboloid, blade-like patch), with the stepover from a scallop height by the
//! exact swept-envelope method (model.md §7).
