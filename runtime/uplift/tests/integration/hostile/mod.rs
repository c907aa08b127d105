//! The hostile-input corpus (issue 46): every case of hostile or careless input a new user was
//! found to trip on, run through the `uplift` binary with the outcome it must have — a clear
//! error naming the file and position or the parameter, an untouched folder, no read outside
//! the input's folder. Input files that are not built in the test live in `tests/hostile/`.

mod args;
mod outputs;
mod paths;
mod processes;
mod values;
