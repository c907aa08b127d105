//! Hostile inputs: values (issue 46).
