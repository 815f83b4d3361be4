#!/usr/bin/env python3
"""Would direct f64 iteration do after a sample's first rebase? A simulation, not the engine.

Perturbation costs about five times a direct f64 iteration per step between zoom 1e6 and
1e10, and by a sample's first rebase its orbit has left the reference's (near 1e6, 5% of
the steps come before it). This compares, on random escaping pixels of the seahorse-valley
descent, three ways of iterating z -> z^2 + c against mpmath at 200 bits:

  per  perturbation with rebasing (Zhuoran) all the way, as deepfield's engine does;
  hyb  perturbation up to the first rebase, then direct f64 from the full value;
  f64  direct f64 from the start.

Python floats (IEEE doubles) throughout; escape radius 100; N and the smooth count
NF = n + 1 - log2(ln|z|^2 / ln R^2). No pixel is left out as ill-conditioned (deepfield
compare does that), so the tails here are larger than compare's; compare the rows, not the
numbers with compare's.

    python3 scripts/direct-after-rebase.py ZOOM PIXELS     # e.g. 1e6 120 (minutes)
"""
import math
import random
import sys

import mpmath

mpmath.mp.prec = 200
ZOOM = float(sys.argv[1]) if len(sys.argv) > 1 else 1e6
COUNT = int(sys.argv[2]) if len(sys.argv) > 2 else 120
MAXI, R2 = 5000, 1e4
CR = mpmath.mpf("-0.743643887037158704752191506114774")
CI = mpmath.mpf("0.131825904205311970493132056385139")
C = mpmath.mpc(CR, CI)

# The reference orbit at the centre, rounded to doubles.
REF = [0j]
z = mpmath.mpc(0)
for _ in range(MAXI + 1):
    z = z * z + C
    REF.append(complex(z))
    if abs(z) ** 2 > R2:
        break


def smooth(n, zz):
    if n >= MAXI:
        return (MAXI, 0.0)
    return (n, n + 1 - math.log2(math.log(abs(zz) ** 2) / math.log(R2)))


def perturbed(dc, hybrid):
    d, m, n, direct = 0j, 0, 0, None
    cf = complex(C) + dc
    while n < MAXI:
        if direct is not None:
            if abs(direct) ** 2 > R2:
                return smooth(n, direct)
            direct = direct * direct + cf
            n += 1
            continue
        full = REF[m] + d
        if abs(full) ** 2 > R2:
            return smooth(n, full)
        if abs(full) < abs(d):
            if hybrid:
                direct = full
                continue
            d, m = full, 0
        d = (2 * REF[m] + d) * d + dc
        m += 1
        n += 1
        if m >= len(REF) - 1:
            d, m = REF[m] + d, 0
    return smooth(MAXI, 0)


def direct(cf):
    zz = 0j
    for n in range(MAXI):
        if abs(zz) ** 2 > R2:
            return smooth(n, zz)
        zz = zz * zz + cf
    return smooth(MAXI, 0)


def truth(dcr, dci):
    cc = mpmath.mpc(CR + dcr, CI + dci)
    zz = mpmath.mpc(0)
    for n in range(MAXI):
        if zz.real * zz.real + zz.imag * zz.imag > R2:
            return smooth(n, complex(zz))
        zz = zz * zz + cc
    return smooth(MAXI, 0)


def main():
    width = 4 / ZOOM
    random.seed(2)
    rows = {"per": [], "hyb": [], "f64": []}
    found = 0
    while found < COUNT:
        dcr = (random.random() - 0.5) * width
        dci = (random.random() - 0.5) * width * 0.75
        t = truth(mpmath.mpf(dcr), mpmath.mpf(dci))
        if t[0] >= MAXI:
            continue
        found += 1
        dc = complex(dcr, dci)
        got = {
            "per": perturbed(dc, False),
            "hyb": perturbed(dc, True),
            "f64": direct(complex(CR + mpmath.mpf(dcr), CI + mpmath.mpf(dci))),
        }
        for k, v in got.items():
            rows[k].append((v[0] != t[0], abs(v[1] - t[1])))
    for k, v in rows.items():
        errs = sorted(e for _, e in v)
        pick = lambda q: errs[min(len(errs) - 1, int(q * len(errs)))]
        wrong = sum(1 for w, _ in v if w)
        print(f"zoom {ZOOM:g} {k}: N wrong {wrong} of {len(v)}, NF p50 {pick(0.5):.2g} p99 {pick(0.99):.2g} max {errs[-1]:.2g}")


if __name__ == "__main__":
    main()
