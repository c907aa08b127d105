//! Hostile inputs: outputs (issue 46).
