#!/usr/bin/env python3
"""Lower bound on the dead-reckoned velocity error of a GPS-lost landing, for the campaign's
`gps_loss` family (fcc_sim::campaign, OPEN_CHECKS): the steady-state Kalman filter that an
optimal estimator would run on this airframe's sensors while the GPS is healthy, then its
velocity error predicted T seconds after the last fix (dead reckoning, nothing observing the
ground speed). No tuning of ours can do better on average with these sensors.

Per horizontal axis, error states  x = [v (m/s), d (rad, the tilt error that reads as g*d),
b (rad/s, gyro rate bias), ba (m/s^2, accelerometer bias)]:

    dv/dt = g*d + ba + w_a      dd/dt = b + w_g      db/dt = w_b      dba/dt = w_ba
    z = v + n   at the GPS rate (Doppler velocity)

with the simulator's datasheet figures (fcc_firmware/sim/src/sensor_models.rs): accelerometer
300 ug/sqrt(Hz), gyro 0.01 deg/s/sqrt(Hz), gyro bias random walk 0.003 deg/s/sqrt(s),
accelerometer bias random walk 0.0005 m/s^2/sqrt(s), u-blox M8 velocity 0.05 m/s at 5 Hz.
Horizontal speed at touchdown is the norm of two such axes (Rayleigh): the chance that the
estimation error alone exceeds r is exp(-r^2 / (2 sigma^2)).

usage: scripts/gps_loss_bound.py [T_s ...]     (pure Python, no dependencies)
"""
import math
import sys

G = 9.80665
DT = 0.2                               # GPS period, s (5 Hz)
ARW = math.radians(0.01)               # gyro noise density, rad/s/sqrt(Hz)
RRW = math.radians(0.003)              # gyro bias random walk, rad/s/sqrt(s)
VRW = 300e-6 * G                       # accelerometer noise density, m/s^2/sqrt(Hz)
BARW = 0.0005                          # accelerometer bias random walk, m/s^2/sqrt(s)
SIGMA_V = 0.05                         # GPS velocity noise, m/s
N = 4


def mat(r, c, f=0.0):
    return [[f for _ in range(c)] for _ in range(r)]


def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(len(b))) for j in range(len(b[0]))]
            for i in range(len(a))]


def add(a, b):
    return [[a[i][j] + b[i][j] for j in range(len(a[0]))] for i in range(len(a))]


def tr(a):
    return [list(r) for r in zip(*a)]


def eye(n):
    m = mat(n, n)
    for i in range(n):
        m[i][i] = 1.0
    return m


def expm(a):
    """Matrix exponential by its series (the blocks here are nilpotent or tiny)."""
    r, t = eye(len(a)), eye(len(a))
    for k in range(1, 40):
        t = [[x / k for x in row] for row in mul(t, a)]
        r = add(r, t)
    return r


def discretise():
    """Van Loan: the transition and the process noise over one GPS period."""
    f = mat(N, N)
    f[0][1], f[0][3], f[1][2] = G, 1.0, 1.0
    qc = mat(N, N)
    for i, q in enumerate([VRW ** 2, ARW ** 2, RRW ** 2, BARW ** 2]):
        qc[i][i] = q
    m = mat(2 * N, 2 * N)
    for i in range(N):
        for j in range(N):
            m[i][j] = -f[i][j] * DT
            m[i][N + j] = qc[i][j] * DT
            m[N + i][N + j] = f[j][i] * DT
    e = expm(m)
    phi = tr([row[N:] for row in e[N:]])
    q = mul(phi, [row[N:] for row in e[:N]])
    return phi, q


def steady_state():
    phi, q = discretise()
    p = mat(N, N)
    for i, v in enumerate([1.0, 1e-4, 1e-6, 0.1]):
        p[i][i] = v
    for _ in range(20000):
        p = add(mul(mul(phi, p), tr(phi)), q)
        s = p[0][0] + SIGMA_V ** 2
        k = [p[i][0] / s for i in range(N)]
        p = [[p[i][j] - k[i] * p[0][j] for j in range(N)] for i in range(N)]
    return p, k


def main():
    ts = [float(a) for a in sys.argv[1:]] or [4.0, 5.5, 6.8, 7.8]
    p, k = steady_state()
    print("steady-state Kalman gains per fix: v %.3f, tilt %.2e rad/(m/s), gyro bias %.2e, "
          "accel bias %.1e" % tuple(k))
    c = [0.0, G, 0.0, 1.0]
    s_acc = math.sqrt(sum(c[i] * p[i][j] * c[j] for i in range(N) for j in range(N)))
    print("at the loss: velocity sigma %.3f m/s, (g*tilt + accel bias) sigma %.4f m/s^2, "
          "gyro bias sigma %.4f deg/s" % (math.sqrt(p[0][0]), s_acc,
                                          math.degrees(math.sqrt(p[2][2]))))
    print("T after the last fix | velocity error sigma per axis | P(|v_NE| > 0.3 m/s)")
    for t in ts:
        a = [1.0, G * t, 0.5 * G * t * t, t]
        var = sum(a[i] * p[i][j] * a[j] for i in range(N) for j in range(N))
        # Noise while dead-reckoning: the bias walk's triple integral dominates.
        var += (G * RRW) ** 2 * t ** 5 / 20 + (G * ARW) ** 2 * t ** 3 / 3 + VRW ** 2 * t
        sig = math.sqrt(var)
        print("%5.1f s | %.3f m/s | %.1e" % (t, sig, math.exp(-0.09 / (2 * sig * sig))))


if __name__ == "__main__":
    main()
