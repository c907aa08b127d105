//! Hostile inputs: paths (issue 46).
