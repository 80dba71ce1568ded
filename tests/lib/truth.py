"""The simulator's truth log (fcc-sitl --csv), quaternion helpers and the check counter, shared
by the peers: the rclpy peer (tests/ros2, ROS 2 venv) and the Cyclone DDS peers (tests/dds,
tests/e2e). Plain Python (no DDS or ROS import), so every venv can import it."""
import bisect
import csv
import math


class Checks:
    """PASS/FAIL lines, then the closing 'N passed, N failed' line."""

    def __init__(self):
        self.passed = 0
        self.failed = 0
        self.failed_names = []

    def check(self, name, ok, detail=""):
        ok = bool(ok)
        self.passed += ok
        self.failed += not ok
        if not ok:
            self.failed_names.append(name)
        print(f"{'PASS' if ok else 'FAIL'} {name}{(': ' + str(detail)) if detail != '' else ''}", flush=True)
        return ok

    def done(self):
        for n in self.failed_names:
            print(f"  failed: {n}", flush=True)
        print(f"{self.passed} passed, {self.failed} failed", flush=True)
        return 0 if self.failed == 0 else 1


def t_of(stamp):
    """A builtin_interfaces/Time (rclpy's or Cyclone's: fields sec, nanosec) in seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def stamp_of(msg):
    """A message's stamp, s: its header's, a Clock's, or a TFMessage's first transform's; None."""
    if hasattr(msg, "header"):
        return t_of(msg.header.stamp)
    if hasattr(msg, "clock"):
        return t_of(msg.clock)
    if hasattr(msg, "transforms") and msg.transforms:
        return t_of(msg.transforms[0].header.stamp)
    return None


def load_csv(path):
    """Every column as floats (non-numeric ones, e.g. mode, as strings)."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    out = {}
    for k in rows[0].keys():
        try:
            out[k] = [float(r[k]) for r in rows]
        except ValueError:
            out[k] = [r[k] for r in rows]
    return out


def interp(log, col, t):
    """The column linearly interpolated at sim time t, or None outside the log."""
    ts = log["t_s"]
    i = bisect.bisect_left(ts, t)
    if i <= 0 or i >= len(ts):
        return None
    a = (t - ts[i - 1]) / (ts[i] - ts[i - 1])
    return log[col][i - 1] * (1 - a) + log[col][i] * a


def nearest(log, t):
    """Index of the row nearest in time to t, or None outside the log."""
    ts = log["t_s"]
    i = bisect.bisect_left(ts, t)
    if i <= 0 or i >= len(ts):
        return None
    return i if ts[i] - t < t - ts[i - 1] else i - 1


def pct(v, q):
    v = sorted(v)
    return v[min(len(v) - 1, int(q * len(v)))] if v else float("nan")


def est_enu(log, t):
    """The MCU's position estimate at sim time t in ENU (x east, y north, z up), or None."""
    n, e, d = (interp(log, k, t) for k in ("est_n_m", "est_e_m", "est_d_m"))
    return None if n is None else (e, n, -d)


def true_enu(log, t):
    n, e, d = (interp(log, k, t) for k in ("true_n_m", "true_e_m", "true_d_m"))
    return None if n is None else (e, n, -d)


def qmul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def qrot(q, v):
    """v rotated by the unit quaternion q = (w, x, y, z)."""
    p = qmul(qmul(q, (0.0, *v)), (q[0], -q[1], -q[2], -q[3]))
    return p[1:]


def compose(t1, t2):
    """Transforms as (translation, quaternion wxyz): parent→a then a→child = parent→child."""
    (p1, q1), (p2, q2) = t1, t2
    r = qrot(q1, p2)
    return (tuple(a + b for a, b in zip(p1, r)), qmul(q1, q2))


def dist(a, b):
    return math.dist(a, b)
