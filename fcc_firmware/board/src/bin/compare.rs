//! Host tool: compare the QEMU image's printed motor commands (`M <tick> <8 × hex f32>` lines)
//! with the host build's outputs (`expected.bin` from `record`).
//!
//!   compare QEMU_OUTPUT EXPECTED_BIN [TOLERANCE]   (default tolerance 1e-5)
//!
//! Exits 0 when every tick is present and every command is within the tolerance.
use fcc_board::replay::OutputStream;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 3 {
        eprintln!("usage: compare QEMU_OUTPUT EXPECTED_BIN [TOLERANCE]");
        std::process::exit(2);
    }
    let text = std::fs::read_to_string(&a[1]).expect("QEMU output");
    let exp = std::fs::read(&a[2]).expect("expected.bin");
    let tol: f32 = a.get(3).map_or(1e-5, |s| s.parse().expect("TOLERANCE"));
    let expected: Vec<[f32; 8]> = OutputStream::new(&exp).expect("expected.bin header").collect();
    let mut got: Vec<Option<[f32; 8]>> = vec![None; expected.len()];
    for line in text.lines().filter(|l| l.starts_with("M ")) {
        let mut it = line.split_whitespace().skip(1);
        let Some(i) = it.next().and_then(|s| s.parse::<usize>().ok()) else { continue };
        let mut m = [f32::NAN; 8];
        for v in &mut m {
            *v = it.next().and_then(|s| u32::from_str_radix(s, 16).ok()).map_or(f32::NAN, f32::from_bits);
        }
        if let Some(slot) = got.get_mut(i) {
            *slot = Some(m);
        }
    }
    let (mut max_diff, mut at, mut missing, mut identical) = (0.0f32, 0usize, 0usize, 0usize);
    for (i, (e, g)) in expected.iter().zip(&got).enumerate() {
        let Some(g) = g else {
            missing += 1;
            continue;
        };
        if e.iter().zip(g).all(|(x, y)| x.to_bits() == y.to_bits()) {
            identical += 1;
        }
        for (x, y) in e.iter().zip(g) {
            let d = (x - y).abs();
            if d.is_nan() || d > max_diff {
                max_diff = if d.is_nan() { f32::INFINITY } else { d };
                at = i;
            }
        }
    }
    let ok = missing == 0 && !expected.is_empty() && max_diff <= tol;
    println!(
        "compare: {} ticks expected, {} missing, {} bit-identical; max abs diff {:e} (tick {}), tolerance {:e}: {}",
        expected.len(),
        missing,
        identical,
        max_diff,
        at,
        tol,
        if ok { "MATCH" } else { "MISMATCH" }
    );
    std::process::exit(if ok { 0 } else { 1 });
}
