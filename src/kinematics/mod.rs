//! Machine kinematics: two-rotary-axis chains, inverse and forward kinematics, and
//! jerk-limited feed planning that predicts the feed the machine really reaches.
