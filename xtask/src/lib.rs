//! The parts of xtask that its tests and the fuzz targets under `fuzz/` share: loading and
//! checking the files a user writes (scenario files, tracker configurations, MOTChallenge
//! text, HMM models), with one entry function per fuzz target. The command runner itself is
//! the `xtask` binary (`src/main.rs`).

pub mod inputs;
