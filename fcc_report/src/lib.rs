//! Flight bags recorded by `fcc-bridge --record`: the figures of a flight ([`figures`]) and
//! its plots ([`plot`]), for the `fcc-report` binary; `fcc-replay` republishes a bag.

pub mod figures;
pub mod plot;
