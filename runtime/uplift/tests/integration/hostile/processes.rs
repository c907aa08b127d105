//! Hostile inputs: processes (issue 46).
