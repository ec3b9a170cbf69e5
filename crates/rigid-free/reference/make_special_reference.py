#!/usr/bin/env python3
"""40-digit values of the complete integral of the third kind and of Carlson's R_C, for the
arguments where they are hardest in binary64 (large negative characteristic, m near 0 and 1,
R_C with y << x). Run from this folder:
    python3 make_special_reference.py > special-reference.txt
Inputs are exact binary64 numbers (printed with repr); m is given through m_c = 1 - m."""
from mpmath import mp, mpf, ellippi, elliprc

mp.dps = 40
print("# pi n m_c Pi(n | 1 - m_c)")
for n in [-2e8, -1e4, -47.65221267760365, -5.0, -1.0, -0.3, -1e-9, 0.0, 0.3, 0.9]:
    for m_c in [1.0, 0.8, 0.5, 0.05, 1e-6, 3e-14]:
        v = ellippi(mpf(n), 1 - mpf(m_c))
        print("pi %r %r %s" % (n, m_c, mp.nstr(v, 30)))
print("# rc x y R_C(x, y)")
for x, y in [(9.186335080572777, 0.001), (1.0, 1e-300), (1.0, 1e-10), (1.0, 0.5), (0.5, 1.0),
             (1.0, 1.0000001), (1.0, 0.9999999), (0.0, 2.0), (1e-10, 1.0)]:
    print("rc %r %r %s" % (x, y, mp.nstr(elliprc(mpf(x), mpf(y)), 30)))
