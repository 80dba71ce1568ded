//! Sensor drivers (embedded-hal 1.0).
