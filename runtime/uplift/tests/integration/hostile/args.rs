//! Hostile inputs: args (issue 46).
