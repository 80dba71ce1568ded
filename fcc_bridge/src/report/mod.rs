//! Flight bags recorded by `fcc-bridge --record`, read back: [`bag`] (reading an MCAP bag, the
//! odometry in NED), [`series`] (the time series decoded from its topics), [`figures`] (the
//! figures of a flight), [`plot`] (its PNG plots) and [`sysid`] (paper A's k1/k2 fit with the
//! wind). The `fcc-report` binary uses them all;
//! `fcc-replay` republishes or re-decodes a bag with [`bag`].

pub mod bag;
pub mod figures;
pub mod plot;
pub mod series;
pub mod sysid;
