#!/usr/bin/env python3
"""Reference values of the Gay-Berne potential, its force and both torques, at 40 digits.

Run from this folder: `python3 gay_berne.py > gay_berne.txt` (needs mpmath from PyPI; CI never
runs it, the output is committed). Takes a few seconds.

The potential is GB(kappa, kappa', mu, nu) as in J. G. Gay and B. J. Berne, J. Chem. Phys. 74,
3316 (1981), written out independently of the crate from the textbook form

    U     = 4 eps (rho^12 - rho^6),  rho = s0 / (r - sigma + s0)
    sigma = s0 [1 - chi/2 ((a+b)^2/(1+chi c) + (a-b)^2/(1-chi c))]^(-1/2)
    eps   = e0 [1 - chi^2 c^2]^(-nu/2) [1 - chi'/2 ((a+b)^2/(1+chi' c) + (a-b)^2/(1-chi' c))]^mu

with a = rhat.s_i, b = rhat.s_j, c = s_i.s_j. Unlike the crate, forces and torques are NOT
derived analytically: the force is minus the gradient of U with respect to r_ij and the torque
on body i is minus the derivative of U with respect to rotating s_i about each lab axis, both by
mpmath's numerical differentiation at 40 digits. The inputs are binary64 numbers (printed with
repr), so the Rust test evaluates exactly the same geometry.

Output: one line per case, whitespace-separated:
    name kappa kappa' mu nu  rx ry rz  six siy siz  sjx sjy sjz  U  Fx Fy Fz  tix tiy tiz  tjx tjy tjz
"""

from mpmath import mp, mpf, sqrt, diff, cos, sin

mp.dps = 40


def gb(params, r, si, sj):
    kappa, kappap, mu, nu = [mpf(x) for x in params]
    s0, e0 = mpf(1), mpf(1)
    chi = (kappa**2 - 1) / (kappa**2 + 1)
    kp = kappap ** (1 / mu)
    chip = (kp - 1) / (kp + 1)
    rr = sqrt(sum(x * x for x in r))
    a = sum(x * y for x, y in zip(r, si)) / rr
    b = sum(x * y for x, y in zip(r, sj)) / rr
    c = sum(x * y for x, y in zip(si, sj))
    h = (a + b) ** 2 / (1 + chi * c) + (a - b) ** 2 / (1 - chi * c)
    hp = (a + b) ** 2 / (1 + chip * c) + (a - b) ** 2 / (1 - chip * c)
    sigma = s0 / sqrt(1 - chi / 2 * h)
    eps = e0 * (1 - chi**2 * c**2) ** (-nu / 2) * (1 - chip / 2 * hp) ** mu
    rho = s0 / (rr - sigma + s0)
    return 4 * eps * (rho**12 - rho**6)


def rotate(v, axis, t):
    # Rotation of v by angle t about lab axis 0, 1 or 2 (right-handed).
    x, y, z = v
    c, s = cos(t), sin(t)
    if axis == 0:
        return [x, c * y - s * z, s * y + c * z]
    if axis == 1:
        return [c * x + s * z, y, -s * x + c * z]
    return [c * x - s * y, s * x + c * y, z]


def case(name, params, r, si, sj):
    r = [mpf(float(x)) for x in r]
    si = [mpf(float(x)) for x in si]
    sj = [mpf(float(x)) for x in sj]
    u = gb(params, r, si, sj)
    force = []
    for k in range(3):
        def f(t, k=k):
            rr = list(r)
            rr[k] += t
            return gb(params, rr, si, sj)
        force.append(-diff(f, 0))
    ti = [-diff(lambda t, k=k: gb(params, r, rotate(si, k, t), sj), 0) for k in range(3)]
    tj = [-diff(lambda t, k=k: gb(params, r, si, rotate(sj, k, t)), 0) for k in range(3)]
    inputs = [repr(float(x)) for x in list(params) + r + si + sj]
    outputs = [mp.nstr(x, 30) for x in [u] + force + ti + tj]
    print(name, " ".join(inputs), " ".join(outputs))


def unit(v):
    n = sum(x * x for x in v) ** 0.5
    return [x / n for x in v]


GB3521 = (3.0, 5.0, 2.0, 1.0)
OBLATE = (0.5, 0.2, 1.0, 3.0)
r0 = 2 ** (1 / 6)  # shifted-LJ minimum offset + 1
for p, tag in [(GB3521, "gb3521"), (OBLATE, "oblate")]:
    for d in [0.95, r0, 1.6]:
        case(f"{tag}-side-by-side-{d:.3f}", p, [d, 0, 0], [0, 0, 1], [0, 0, 1])
        case(f"{tag}-crossed-{d:.3f}", p, [d, 0, 0], [0, 0, 1], [0, 1, 0])
    for d in [2.3, 2.6, 3.2]:
        case(f"{tag}-T-{d:.3f}", p, [d, 0, 0], [1, 0, 0], [0, 0, 1])
    for d in [2.9, 3.2, 4.0]:
        case(f"{tag}-end-to-end-{d:.3f}", p, [d, 0, 0], [1, 0, 0], [1, 0, 0])
    # Generic geometries (no symmetry): fixed numbers, unit axes in binary64.
    case(f"{tag}-generic-1", p, [1.3, -0.7, 0.9], unit([0.3, 0.5, -0.8]), unit([-0.6, 0.2, 0.4]))
    case(f"{tag}-generic-2", p, [-0.4, 2.1, 1.7], unit([0.9, -0.1, 0.3]), unit([0.2, 0.7, 0.7]))
    case(f"{tag}-generic-3", p, [3.1, 0.2, -0.5], unit([0.7, 0.7, 0.1]), unit([0.68, 0.72, 0.12]))
    case(f"{tag}-tilted-4", p, [0.2, 1.4, 0.3], unit([1.0, 0.05, 0.0]), unit([0.0, 0.1, 1.0]))
