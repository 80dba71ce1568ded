//! Reading recorded bags back ([`bag`]); `fcc-report` and `fcc-replay` (crate `fcc_report`) use it.

pub mod bag;
