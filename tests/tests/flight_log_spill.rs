//! The simulator's flight log spilled to a scratch file while it flies (what `fcc-sitl
//! --link-pty` does for flat memory) is the same log once the run is closed: same samples, same
//! range readings, same summary and CSV, byte for byte.

mod common;

use fcc_sim::{log, metrics, sim::Sim};

fn csv_bytes(l: &log::FlightLog, name: &str) -> Vec<u8> {
    let p = std::env::temp_dir().join(format!("fcc-spill-test-{}-{name}.csv", std::process::id()));
    log::write_csv(l, &p).expect("csv");
    let b = std::fs::read(&p).expect("csv back");
    let _ = std::fs::remove_file(&p);
    b
}

#[test]
fn spilled_log_reads_back_identical() {
    // The square: legs, a hold, both rangefinders, a landing (every plan phase and mode).
    let mut sc = common::load("square");
    sc.duration_s = sc.duration_s.min(90.0);
    let mut kept = Sim::new(sc.clone()).expect("scenario");
    kept.run();
    let mut spilled = Sim::new(sc).expect("scenario");
    spilled
        .spill_log(&std::env::temp_dir())
        .expect("scratch file");
    while !spilled.finished() {
        spilled.tick();
        // While it flies, memory holds nothing of the log.
        assert!(spilled.log.samples.is_empty() && spilled.log.ranges.is_empty());
    }
    spilled.finish();
    let (a, b) = (&kept.log, &spilled.log);
    println!(
        "{} samples, {} range readings spilled and read back",
        b.samples.len(),
        b.ranges.len()
    );
    assert!(a.samples.len() > 1000 && !a.ranges.is_empty());
    assert_eq!(a.samples.len(), b.samples.len());
    assert_eq!(a.ranges.len(), b.ranges.len());
    // Debug prints every field (floats in full, shortest round-trip form).
    assert_eq!(format!("{:?}", a.samples), format!("{:?}", b.samples));
    assert_eq!(format!("{:?}", a.ranges), format!("{:?}", b.ranges));
    assert_eq!(metrics::summary(a), metrics::summary(b));
    assert_eq!(csv_bytes(a, "kept"), csv_bytes(b, "spilled"));
}
