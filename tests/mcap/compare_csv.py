#!/usr/bin/env python3
"""fcc-report's figures of a bag vs the flight core's own log of the same flight (fcc-sitl --csv:
50 Hz, MCU time t_s). Needs the bridge run with clock_source:=mcu (bag stamps = MCU time = t_s).
  compare_csv.py REPORT_DIR/summary.json FLIGHT.csv [--tol 0.02] [--sitl-out SITL_STDOUT]

* Cross-track: the report's legs (bag state/odom, ENU → NED) vs est_n_m/est_e_m of the CSV over
  the same leg windows, same formula as fcc_sim::metrics::leg_tracks/track_summary;
  |diff| ≤ --tol.
* Hover box (paper A Fig. 16), the definition of metrics::hover_box / the flight core's hover
  test: the window is the MCU in HOLD while armed (here: the CSV's own mode column, the longest
  run), the hold point is the estimate where the hold began (first row of the run), the box is
  max |est − hold point| per axis N, E, alt. The report found its window from the bag alone
  (status + the commands that caused the mode changes). The window edges must agree within one
  CSV period T (20 ms; the mode change lies inside the CSV row before the first HOLD row) plus
  30 ms of command latency (15 ms wall at sim speed 2) — plus a status period (0.1 s) for an
  edge the report had from `status` only. Tolerance per axis, from the sample times: the two
  hold points are estimates ≤ e0 = |Δt0| + 10 ms apart in time (the bag's odometry comes every
  10 ms), samples in one window and not the other lie ≤ e = max(e0, |Δt1|) from the edge, and
  the largest deviation of the 10 ms series is ≤ T/2 from a CSV row, so
  tol = v_max·(e0 + e + T/2) + 0.2 mm (CSV rounding), v_max = the largest |estimated velocity|
  on that axis in the CSV over both windows. Then the same check is run on a box
  perturbed by 2·tol on each axis in turn, and must fail (the check can fail).
* Observer (Fig. 13): the report's ratio of high-pass σ must be < 0.3 (the flight core's
  threshold, there on est − truth); printed beside the flight core's own figure (--sitl-out).
"""
import csv, json, math, re, sys

def cross_track(p, a, b):
    d = (b[0] - a[0], b[1] - a[1]); n = max(math.hypot(*d), 1e-9)
    return ((p[0] - a[0]) * d[1] - (p[1] - a[1]) * d[0]) / n

def rms(v): return math.sqrt(sum(x * x for x in v) / len(v))

def arg(name, default=None):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default

summ = json.load(open(sys.argv[1]))
tol = float(arg("--tol", 0.02))
rows = list(csv.DictReader(open(sys.argv[2])))
ok = True

# --- cross-track -------------------------------------------------------------------------
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
xt_ok = not bad and abs(tr - summ["cross_track_rms_m"]) <= tol
print(f"ROW|report cross-track RMS vs flight core|{summ['cross_track_rms_m']:.3f} m|{tr:.3f} m|goal |diff| ≤ {tol} m|{'met' if xt_ok else 'NOT met'}")
ok &= xt_ok

# --- hover box ---------------------------------------------------------------------------
def csv_hover(rows):
    """Longest run of rows in HOLD while armed → (rows of the run, index after it)."""
    best, i = None, 0
    while i < len(rows):
        if rows[i]["mode"] == "Hold" and rows[i]["armed"] == "1":
            j = i
            while j + 1 < len(rows) and rows[j + 1]["mode"] == "Hold" and rows[j + 1]["armed"] == "1":
                j += 1
            if best is None or j - i > best[1] - best[0]:
                best = (i, j)
            i = j + 1
        else:
            i += 1
    return best

def hover_check(h, rows, quiet=False):
    say = (lambda *a: None) if quiet else print
    run = csv_hover(rows)
    if run is None:
        say("FAIL hover: the flight core's log has no HOLD period"); return False
    i, j = run
    w = rows[i:j + 1]
    T = (float(rows[-1]["t_s"]) - float(rows[0]["t_s"])) / (len(rows) - 1)   # CSV period
    t0c = float(w[0]["t_s"]); t1c = float(rows[j + 1]["t_s"]) if j + 1 < len(rows) else float(w[-1]["t_s"]) + T
    keys = ("est_n_m", "est_e_m", "est_d_m"); vkeys = ("est_vn_mps", "est_ve_mps", "est_vd_mps")
    hold = [float(w[0][k]) for k in keys]
    box = [max(abs(float(r[k]) - hold[n]) for r in w) for n, k in enumerate(keys)]
    vmax = [max(abs(float(r[k])) for r in w) for k in vkeys]
    status_edges = [h["start_from"], h["end_from"]].count("status")
    d0, d1 = h["t0_s"] - t0c, h["t1_s"] - t1c
    e0 = abs(d0) + 0.010
    # v_max over both windows (the bag's may start or end a little outside the CSV's).
    near = [r for r in rows if t0c - e0 - T <= float(r["t_s"]) < t1c + max(d1, 0.0) + T]
    vmax = [max(abs(float(r[k])) for r in near) for k in vkeys]
    tau = e0 + max(e0, abs(d1)) + T / 2
    tols = [v * tau + 2e-4 for v in vmax]
    edge_tol = T + 0.030 + (h["status_period_s"] if status_edges else 0.0)
    say(f"hover window: report (bag: {h['start_from']} → {h['end_from']}) {h['t0_s']:.3f}–{h['t1_s']:.3f} s | "
        f"flight core log (mode Hold, armed) {t0c:.3f}–{t1c:.3f} s | edges differ {d0*1e3:+.0f} / {d1*1e3:+.0f} ms (≤ {edge_tol*1e3:.0f} ms)")
    good = abs(d0) <= edge_tol and abs(d1) <= edge_tol and (t1c - t0c) >= 10.0
    rb = h["box_m"]
    for n, axis in enumerate(("N", "E", "alt")):
        d = abs(rb[n] - box[n])
        say(f"hover box {axis}: report (bag odom) {rb[n]:.4f} m | flight core log {box[n]:.4f} m | diff {d*1e3:.1f} mm "
            f"(tol {tols[n]*1e3:.1f} mm = v_max {vmax[n]:.2f} m/s × {tau*1e3:.0f} ms + 0.2 mm)")
        good &= d <= tols[n]
    say(f"ROW|report hover box vs flight core ({t1c - t0c:.0f} s HOLD)|N {rb[0]:.3f} E {rb[1]:.3f} alt {rb[2]:.3f} m|"
        f"N {box[0]:.3f} E {box[1]:.3f} alt {box[2]:.3f} m|goal |diff| ≤ v_max·{tau*1e3:.0f} ms per axis|{'met' if good else 'NOT met'}")
    return good, tols

h = summ.get("hover")
if h is None:
    print("FAIL the report found no hover in the bag"); ok = False
else:
    r = hover_check(h, rows)
    good, tols = r if isinstance(r, tuple) else (r, None)
    ok &= good
    if tols:
        # The check must be able to fail: the same comparison on a box off by 2·tol per axis.
        for n in range(3):
            p = dict(h); p["box_m"] = list(h["box_m"]); p["box_m"][n] += 2 * tols[n]
            if hover_check(p, rows, quiet=True)[0]:
                print(f"FAIL the hover check accepts a box {2*tols[n]*1e3:.1f} mm off on axis {n}"); ok = False
        print("hover check rejects a box off by 2·tol on any axis: yes" if ok else "")

# --- observer (Fig. 13) --------------------------------------------------------------------
o = summ.get("observer")
core_ratio = None
if arg("--sitl-out"):
    m = re.search(r"acceleration observer: std\(est − truth\) ([\d.]+) m/s² vs raw accelerometer ([\d.]+) m/s² \(ratio ([\d.]+)\)",
                  open(arg("--sitl-out")).read())
    core_ratio = float(m.group(3)) if m else None
if o is None:
    print("FAIL the report has no observer figure (accel/observer, accel/measured missing?)"); ok = False
else:
    good = o["ratio"] < 0.3
    print(f"ROW|report observer/measured high-pass σ ratio|{o['ratio']:.3f}|flight core std(est−truth) ratio "
          f"{core_ratio if core_ratio is not None else 'n/a'}|goal < 0.3|{'met' if good else 'NOT met'}")
    ok &= good
sys.exit(0 if ok else 1)
