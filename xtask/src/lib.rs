//! The parts of xtask that its tests and the fuzz targets under `fuzz/` share: loading and
//! checking the files a user writes: scenario files (`scenario_file`), and tracker
//! configurations, MOTChallenge text, HMM models and media through one entry function per fuzz
//! target (`inputs`). The command runner itself is the `xtask` binary (`src/main.rs`).

pub mod inputs;
pub mod scenario_file;
