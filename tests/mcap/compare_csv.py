#!/usr/bin/env python3
"""fcc-report's cross-track figures (from the bag's state/odom, ENU → NED) vs the flight core's
own log of the same flight (fcc-sitl --csv: est_n_m/est_e_m at 50 Hz, MCU time t_s), over the
same leg windows and with the same formula as fcc_firmware::sitl::metrics::leg_tracks /
track_summary. Needs the bridge run with clock_source:=mcu (bag stamps = MCU time = t_s).
  compare_csv.py REPORT_DIR/summary.json FLIGHT.csv [--tol 0.02]
"""
import csv, json, math, sys

def cross_track(p, a, b):
    d = (b[0] - a[0], b[1] - a[1]); n = max(math.hypot(*d), 1e-9)
    return ((p[0] - a[0]) * d[1] - (p[1] - a[1]) * d[0]) / n

def rms(v): return math.sqrt(sum(x * x for x in v) / len(v))

summ = json.load(open(sys.argv[1]))
tol = float(sys.argv[sys.argv.index("--tol") + 1]) if "--tol" in sys.argv else 0.02
rows = list(csv.DictReader(open(sys.argv[2])))
legs = summ["legs"]
if len(legs) < 4:
    print(f"FAIL only {len(legs)} legs in the report"); sys.exit(1)
bad = 0; core = []
for l in legs:
    a, b = l["from_ned_m"], l["to_ned_m"]
    e = [cross_track((float(r["est_n_m"]), float(r["est_e_m"])), a, b)
         for r in rows if l["t0_s"] <= float(r["t_s"]) < l["t1_s"]]
    c = rms(e); core.append((c, max(abs(x) for x in e)))
    d = abs(c - l["est_rms_m"])
    print(f"leg {l['index']}: cross-track RMS report (bag odom) {l['est_rms_m']:.3f} m | flight core log {c:.3f} m | diff {d:.3f} m")
    bad += d > tol
tr = math.sqrt(sum(c[0] ** 2 for c in core) / len(core))
print(f"all legs: cross-track RMS report {summ['cross_track_rms_m']:.3f} m | flight core log {tr:.3f} m; "
      f"max report {summ['cross_track_max_m']:.3f} m | flight core {max(c[1] for c in core):.3f} m")
ok = not bad and abs(tr - summ["cross_track_rms_m"]) <= tol
print(f"ROW|report cross-track RMS vs flight core|{summ['cross_track_rms_m']:.3f} m|{tr:.3f} m|goal |diff| ≤ {tol} m|{'met' if ok else 'NOT met'}")
sys.exit(0 if ok else 1)
