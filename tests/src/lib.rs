//! Shared helpers for the scenario tests live in `tests/tests/*.rs`; this library is empty on purpose.
