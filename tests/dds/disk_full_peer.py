#!/usr/bin/env python3
"""The independent Cyclone DDS peer of run_disk_full.sh: watches /rosout for the recorder's
error and checks the bridge keeps publishing after it (imu/data_raw, status).
Run ONLY inside a loopback-only network namespace (run_disk_full.sh does that)."""
import argparse
import sys
import time

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

import ros_srv_types as st
import ros_types as rt


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=25.0, help="give up after this long")
    ap.add_argument("--after", type=float, default=3.0, help="watch this long after the error")
    a = ap.parse_args()
    rel = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(1000))
    dp = DomainParticipant(0)
    rosout = DataReader(dp, Topic(dp, "rt/rosout", st.Log), qos=rel)
    imu = DataReader(dp, Topic(dp, "rt/fcc/imu/data_raw", rt.Imu), qos=rel)
    status = DataReader(dp, Topic(dp, "rt/fcc/status", rt.Status), qos=rel)
    t0 = time.time()
    err_at = None
    errors = []
    # The IMU's rate after the error is counted on the MCU's stamps, not on the arrival times:
    # a loaded machine delays the samples (the peer drains them late), it does not lose them.
    imu_stamps_after = []
    status_after = 0
    drain_s = 2.0
    while time.time() - t0 < a.seconds:
        now = time.time()
        for m in rosout.take(N=1000):
            if type(m).__name__ != "InvalidSample" and "recording to" in m.msg and "stopped" in m.msg:
                errors.append(m)
                err_at = err_at or now
        imus = [s for s in imu.take(N=1000) if type(s).__name__ != "InvalidSample"]
        n_st = sum(1 for s in status.take(N=100) if type(s).__name__ != "InvalidSample")
        if err_at is not None and now > err_at + 0.2:
            imu_stamps_after += [s.header.stamp.sec + 1e-9 * s.header.stamp.nanosec for s in imus]
            status_after += n_st
            if now > err_at + 0.2 + a.after + drain_s:
                break
        time.sleep(0.01)
    ok = True

    def check(what, cond, detail=""):
        nonlocal ok
        ok &= bool(cond)
        print(f"{'PASS' if cond else 'FAIL'} {what}{': ' + str(detail) if detail != '' else ''}", flush=True)
    check("/rosout: the recorder's error, level ERROR (40)", errors and errors[0].level == 40,
          f"after {err_at - t0:.1f} s: {errors[0].msg!r}" if errors else "none")
    check("/rosout: exactly one such line", len(errors) == 1, len(errors))
    if errors:
        check("/rosout: the line names the cause and says the bridge keeps running",
              ("No space left" in errors[0].msg or "File too large" in errors[0].msg)
              and "keeps running" in errors[0].msg and "\n" not in errors[0].msg)
    s0 = min(imu_stamps_after, default=0.0)
    rate = sum(1 for t in imu_stamps_after if s0 <= t < s0 + a.after) / a.after
    check(f"the bridge keeps publishing after the error (imu/data_raw ≥ 150 Hz of the MCU's 200 by "
          f"their stamps, status > 0, over {a.after:.0f} s)",
          rate >= 150 and status_after > 0, f"imu {rate:.0f} Hz, status {status_after}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
