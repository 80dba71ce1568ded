//! Flight bags recorded by `fcc-bridge --record`: the figures of a flight ([`figures`]), its
//! plots ([`plot`]) and paper A's system identification with the wind ([`sysid`]), for the
//! `fcc-report` binary; `fcc-replay` republishes a bag.

pub mod figures;
pub mod plot;
pub mod sysid;
