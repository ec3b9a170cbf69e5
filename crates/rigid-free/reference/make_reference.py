#!/usr/bin/env python3
"""High-precision reference data for the rigid-free propagators.

Run from this folder: `python3 make_reference.py > propagator-reference.txt` (needs mpmath from
PyPI; CI never runs it, the output is committed). Takes a few minutes.

For every case (principal moments I, body angular velocity w0 as exact binary64 numbers, and
A(0) = identity) it prints, at 40 significant digits, the body angular velocity w(t) and the
propagator P(t) = A(t) A(0)^T, row-major, at the listed times.

The method is deliberately different from the crate's: w(t) comes from mpmath's own Jacobi
functions (ellipfun) and incomplete integral (ellipf); the rotation angle psi about L comes from
numerical quadrature (mpmath.quad) of
    dpsi/dt = L (I1 w1^2 + I2 w2^2) / (L1^2 + L2^2),
using the periodicity of the integrand, instead of the theta series and the closed-form secular
rate the crate uses. Both are then checked against a direct Taylor integration (mpmath.odefun) of
Euler's equations and dA/dt = -W(w) A over a short time; the script stops if they differ by more
than 1e-25.
"""

import sys
from mpmath import mp, mpf, matrix, sqrt, atan2, ellipfun, ellipf, ellipk, quad, linspace
from mpmath import cos, sin, tanh, cosh, asinh, odefun, floor

mp.dps = 40


def mat_rows(rows):
    return matrix([[mpf(x) for x in r] for r in rows])


def t_matrix(L):
    l1, l2, l3 = L[0], L[1], L[2]
    ln = sqrt(l1 * l1 + l2 * l2 + l3 * l3)
    lp = sqrt(l1 * l1 + l2 * l2)
    return matrix([[l1 * l3 / (lp * ln), l2 * l3 / (lp * ln), -lp / ln],
                   [-l2 / lp, l1 / lp, 0],
                   [l1 / ln, l2 / ln, l3 / ln]])


def r3(psi):
    c, s = cos(psi), sin(psi)
    return matrix([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def ordering(I, w):
    """Proper signed permutation Pi (rows) putting the intermediate moment on axis 2 and the
    axis circled by L on axis 3 (sign of Delta2 = L^2 - 2E I_mid)."""
    idx = sorted(range(3), key=lambda k: I[k])
    lo, mid, hi = idx
    d2 = I[lo] * w[lo] ** 2 * (I[lo] - I[mid]) + I[hi] * w[hi] ** 2 * (I[hi] - I[mid])
    order = [lo, mid, hi] if d2 >= 0 else [hi, mid, lo]
    even = tuple(order) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)]
    signs = [1, 1 if even else -1, 1]
    P = matrix(3, 3)
    for k in range(3):
        P[k, order[k]] = signs[k]
    return P


class Asymmetric:
    def __init__(self, I, w0):
        self.Pi = ordering(I, w0)
        Iv = self.Pi * matrix(I)
        self.I = [abs(Iv[k]) for k in range(3)]
        wv = self.Pi * matrix(w0)
        w = [wv[k] for k in range(3)]
        I1, I2, I3 = self.I
        L2 = sum((self.I[k] * w[k]) ** 2 for k in range(3))
        E2 = sum(self.I[k] * w[k] ** 2 for k in range(3))
        d1, d2, d3 = L2 - E2 * I1, L2 - E2 * I2, L2 - E2 * I3
        self.sep = (d2 == 0)
        self.m = d3 * (I2 - I1) / (d1 * (I2 - I3))
        s1 = -1 if w[0] < 0 else 1
        s3 = -1 if w[2] < 0 else 1
        self.amp = [s1 * sqrt(d3 / (I1 * (I1 - I3))), -s1 * sqrt(d3 / (I2 * (I2 - I3))),
                    s3 * sqrt(d1 / (I3 * (I3 - I1)))]
        self.wp = s3 * (I2 - I3) * sqrt(d1 / (I1 * I2 * I3 * (I3 - I2)))
        sn0, cn0 = w[1] / self.amp[1], w[0] / self.amp[0]
        if self.sep:
            self.eps = asinh(sn0 / cn0)
        else:
            self.eps = ellipf(atan2(sn0, cn0), self.m)
        self.L = sqrt(L2)
        self.T0 = t_matrix([self.I[k] * w[k] for k in range(3)])
        if not self.sep:
            # Period of the integrand (w1^2, w2^2 have period 2K in u).
            self.tau = 2 * ellipk(self.m) / abs(self.wp)
            self.psi_tau = self._quad(0, self.tau)

    def omega_ordered(self, t):
        u = self.wp * t + self.eps
        if self.sep:
            return [self.amp[0] / cosh(u), self.amp[1] * tanh(u), self.amp[2] / cosh(u)]
        return [self.amp[0] * ellipfun('cn', u, m=self.m), self.amp[1] * ellipfun('sn', u, m=self.m),
                self.amp[2] * ellipfun('dn', u, m=self.m)]

    def psidot(self, t):
        w = self.omega_ordered(t)
        I1, I2 = self.I[0], self.I[1]
        return self.L * (I1 * w[0] ** 2 + I2 * w[1] ** 2) / ((I1 * w[0]) ** 2 + (I2 * w[1]) ** 2)

    def _quad(self, a, b):
        if b == a:
            return mpf(0)
        return quad(self.psidot, linspace(a, b, 25))

    def psi(self, t):
        if self.sep:
            # Not periodic: integrate over pieces that grow geometrically.
            edges = [mpf(0)]
            step = mpf(1) / 16
            while edges[-1] + step < t:
                edges.append(edges[-1] + step)
                step *= 1.5
            edges.append(t)
            return quad(self.psidot, edges)
        n = floor(t / self.tau)
        return n * self.psi_tau + self._quad(0, t - n * self.tau)

    def state(self, t):
        w = self.omega_ordered(t)
        L = [self.I[k] * w[k] for k in range(3)]
        P = self.Pi.T * t_matrix(L).T * r3(self.psi(t)) * self.T0 * self.Pi
        wc = self.Pi.T * matrix(w)
        return [wc[k] for k in range(3)], P


class Symmetric:
    """I[j] distinct: w precesses about e_j at (1 - Is/Ip) w_j; P = R_s(wp t) exp(-(t/Ip) W(L))."""

    def __init__(self, I, w0):
        j = [k for k in range(3) if I[k] != I[(k + 1) % 3] and I[k] != I[(k + 2) % 3]][0]
        self.j, self.k, self.l = j, (j + 1) % 3, (j + 2) % 3
        self.Ip = I[self.k]
        self.wp = (1 - I[j] / self.Ip) * w0[j]
        self.w0 = w0
        self.L = [I[k] * w0[k] for k in range(3)]

    def state(self, t):
        c, s = cos(self.wp * t), sin(self.wp * t)
        Rs = matrix(3, 3)
        Rs[self.j, self.j] = 1
        Rs[self.k, self.k], Rs[self.k, self.l] = c, s
        Rs[self.l, self.k], Rs[self.l, self.l] = -s, c
        Ln = sqrt(sum(x * x for x in self.L))
        n = [x / Ln for x in self.L]
        th = -Ln * t / self.Ip  # exp(-(t/Ip) W(L)) = rotation by -|L| t / Ip about n
        cth, sth = cos(th), sin(th)
        W = matrix([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
        nn = matrix([[n[a] * n[b] for b in range(3)] for a in range(3)])
        Rot = cth * mp.eye(3) + sth * W + (1 - cth) * nn
        w = Rs * matrix(self.w0)
        return [w[k] for k in range(3)], Rs * Rot


def taylor_check(I, w0, t_end, model):
    """Euler's equations plus dA/dt = -W(w) A by mpmath's Taylor integrator."""
    def f(t, y):
        w = y[:3]
        A = [y[3:6], y[6:9], y[9:12]]
        L = [I[k] * w[k] for k in range(3)]
        wd = [(L[1] * w[2] - L[2] * w[1]) / I[0], (L[2] * w[0] - L[0] * w[2]) / I[1],
              (L[0] * w[1] - L[1] * w[0]) / I[2]]
        # (W(w) A) column by column: w x (column of A)
        Ad = [[0] * 3 for _ in range(3)]
        for c in range(3):
            col = [A[0][c], A[1][c], A[2][c]]
            cr = [w[1] * col[2] - w[2] * col[1], w[2] * col[0] - w[0] * col[2],
                  w[0] * col[1] - w[1] * col[0]]
            for r in range(3):
                Ad[r][c] = -cr[r]
        return wd + Ad[0] + Ad[1] + Ad[2]
    y0 = list(w0) + [1, 0, 0, 0, 1, 0, 0, 0, 1]
    sol = odefun(f, 0, [mpf(v) for v in y0])
    y = sol(t_end)
    w, P = model.state(t_end)
    err = max(abs(y[k] - w[k]) for k in range(3))
    err = max(err, max(abs(y[3 + 3 * r + c] - P[r, c]) for r in range(3) for c in range(3)))
    return err


CASES = [
    # name, moments, omega, time scale, description
    ("generic", [1.3, 1.9, 2.6], [0.7, -1.1, 1.9], 1.0, "generic asymmetric, no swap"),
    ("swapped", [1.3, 1.9, 2.6], [2.5, 0.4, 0.3], 1.0, "L circles the smallest axis: axes 1 and 3 swapped"),
    ("omega3-negative", [1.3, 1.9, 2.6], [0.7, 1.1, -1.9], 1.0, "omega3 < 0"),
    ("descending", [2.6, 1.9, 1.3], [1.9, -1.1, 0.7], 1.0, "moments given in descending order"),
    ("near-separatrix", [1.0, 2.0, 3.0], None, 1.0, "m_c about 3e-14"),
    ("near-largest-axis", [1.0, 2.0, 3.0], [1e-6, 1e-6, 1.0], 1.0, "spin near the largest-moment axis, m about 7e-13"),
    ("near-smallest-axis", [1.0, 2.0, 3.0], [1.0, 1e-6, 1e-6], 1.0, "spin near the smallest-moment axis, m about 1e-12"),
    ("near-symmetric", [1.0, 1.00000001, 2.0], [0.6, 0.8, 1.2], 1.0, "I2 - I1 = 1e-8"),
    ("near-symmetric-oblate", [1.0, 2.0, 2.00000001], [1.2, 0.8, 0.6], 1.0, "I3 - I2 = 1e-8"),
    ("fast-spin", [1.3, 1.9, 2.6], [700.0, -1100.0, 1900.0], 1e-3, "omega 1000 times the generic one, times 1000 times shorter"),
    ("flat", [1.0, 2.0, 3.0], [0.9, 0.4, -0.6], 1.0, "planar body, I3 = I1 + I2"),
    ("separatrix", [1.0, 2.5, 3.0], [0.5, 0.3, 0.5], 1.0, "exactly on the separatrix (Delta2 = 0 in binary64)"),
    ("symmetric", [1.0, 1.0, 1.7], [0.4, -0.9, 1.3], 1.0, "symmetric top"),
]

TIMES = [0.25, 1.0, 10.0, 100.0, 1000.0, 10000.0]


def near_separatrix_omega():
    # Delta2 = -w1^2 + 3 w3^2 = 1e-13 with w3 = 1, w2 = 0.5.
    return [float(sqrt(mpf(3) - mpf('1e-13'))), 0.5, 1.0]


def main():
    out = sys.stdout
    out.write("# Reference propagator data, written by make_reference.py (mpmath %s, %d digits).\n" % (mp.__version__ if hasattr(mp, '__version__') else '', mp.dps))
    out.write("# case <name> I1 I2 I3 w1 w2 w3 (exact binary64 inputs, A(0) = identity)\n")
    out.write("# <t> w1 w2 w3 P00 P01 P02 P10 P11 P12 P20 P21 P22\n")
    for name, I, w0, scale, desc in CASES:
        if w0 is None:
            w0 = near_separatrix_omega()
        Im = [mpf(x) for x in I]
        wm = [mpf(x) for x in w0]
        distinct = len(set(I)) == 3
        model = Asymmetric(Im, wm) if distinct else Symmetric(Im, wm)
        info = ""
        if distinct:
            info = " m=%s m_c=%s" % (mp.nstr(model.m, 6), mp.nstr(1 - model.m, 6))
        err = taylor_check(Im, wm, mpf(0.7) * scale, model)
        sys.stderr.write("%s: Taylor check %s%s\n" % (name, mp.nstr(err, 3), info))
        if err > mpf('1e-25'):
            sys.exit("reference model disagrees with the Taylor integration for " + name)
        out.write("# %s%s; Taylor check at t=%s: %s\n" % (desc, info, 0.7 * scale, mp.nstr(err, 3)))
        out.write("case %s %s %s\n" % (name, " ".join(repr(x) for x in I), " ".join(repr(x) for x in w0)))
        for t in TIMES:
            tt = t * scale
            w, P = model.state(mpf(tt))
            vals = [w[k] for k in range(3)] + [P[r, c] for r in range(3) for c in range(3)]
            out.write("%r %s\n" % (tt, " ".join(mp.nstr(v, 40, min_fixed=-5, max_fixed=5) for v in vals)))
        out.flush()


if __name__ == "__main__":
    main()
