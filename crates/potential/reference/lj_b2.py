#!/usr/bin/env python3
"""Second virial coefficient of the Lennard-Jones potential at 25 digits, two ways.

Run from this folder: `python3 lj_b2.py > lj_b2.txt` (needs mpmath; CI never runs it, the
output is committed).

B2*(T*) = B2/sigma^3 = -2 pi int_0^inf (exp(-u(r)/T*) - 1) r^2 dr,  u = 4 (r^-12 - r^-6),
by mpmath quadrature (tanh-sinh, split at the zero and the minimum of u), and by the classical
series (J. O. Hirschfelder, C. F. Curtiss and R. B. Bird, Molecular Theory of Gases and Liquids,
Wiley 1954, Eq. 3.6-9), in units of b0 = 2 pi sigma^3 / 3:

    B2/b0 = -sum_{j>=0} 2^(j + 1/2) / (4 j!) Gamma((2j - 1)/4) T*^(-(2j + 1)/4).

The script stops if the two differ by more than 1e-25. Output lines: T*, B2* (sigma^3),
B2/b0. HCB's Table I-B prints B2/b0 = -2.538 at T* = 1.00, which the T* = 1 line reproduces.
"""

from mpmath import mp, mpf, quad, exp, pi, inf, gamma, factorial

mp.dps = 50


def by_quadrature(t):
    u = lambda r: 4 * (r**-12 - r**-6)
    return -2 * pi * quad(lambda r: (exp(-u(r) / t) - 1) * r**2,
                          [0, 1, mpf(2) ** (mpf(1) / 6), 2, 4, inf])


def by_series(t):
    s = 0
    for j in range(200):
        term = mpf(2) ** (j + mpf(1) / 2) / (4 * factorial(j)) * gamma((2 * j - mpf(1)) / 4) \
            * t ** (-(2 * j + mpf(1)) / 4)
        s -= term
        if j > 10 and abs(term) < mpf(10) ** -40:
            break
    return s * 2 * pi / 3


for t in ["0.7", "1", "1.4", "2", "5"]:
    tt = mpf(t)
    a, b = by_quadrature(tt), by_series(tt)
    assert abs(a - b) < mpf(10) ** -25, (t, a, b)
    print(t, mp.nstr(a, 25), mp.nstr(a / (2 * pi / 3), 25))
