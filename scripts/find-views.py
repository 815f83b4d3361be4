#!/usr/bin/env python3
"""`deepfield find` on random shallow views near the Mandelbrot set's boundary, each answer
checked on its own terms.

Views: centres on the main cardioid's boundary (three in five) or anywhere in
[-2, 0.5] x [-1.2, 1.2], moved by up to 0.01, at zoom 1e2, 1e3, 1e4 or 1e6 (800x600). For
each minibrot found, the printed centre must lie in the disc searched (the view's
half-diagonal) and be a nucleus of exactly the printed period: iterated in Python's
decimal arithmetic at 80 digits (independent of the engine's big floats), z_p is below
1e-30 and no z_n of a proper divisor n of p is. Prints how many views found one, how many
answers failed the check, and how many views ended in an error (no minibrot in the view,
or none that Newton's method from the centre reaches).

With --misiurewicz, `find --misiurewicz` instead: each point printed must lie in the disc
and have exactly the printed preperiod k and period p, in the same arithmetic:
|z_(k+p) - z_k| below 1e-20 (the printed centre's own rounding, amplified by the repelling
cycle, stays far below that at these depths), and no pair (k', p') with k' <= k, p' <= p
other than (k, p) itself comes that close.

    scripts/find-views.py [--misiurewicz] [SEED] [COUNT] [DEEPFIELD]   # defaults: 11, 80, target/release/deepfield
"""
import cmath
import decimal
import math
import random
import re
import subprocess
import sys
import time

args = [a for a in sys.argv[1:] if a != "--misiurewicz"]
misiurewicz = len(args) < len(sys.argv) - 1
seed = int(args[0]) if len(args) > 0 else 11
count = int(args[1]) if len(args) > 1 else 80
binary = args[2] if len(args) > 2 else "target/release/deepfield"
decimal.getcontext().prec = 80
D = decimal.Decimal


def exact_period(re_text, im_text, period):
    """True when re + im i is a nucleus of exactly `period` (see the module doc)."""
    cr, ci = D(re_text), D(im_text)
    zr, zi = D(0), D(0)
    tiny = D("1e-30")
    for n in range(1, period + 1):
        zr, zi = zr * zr - zi * zi + cr, 2 * zr * zi + ci
        small = (zr * zr + zi * zi).sqrt() < tiny
        if n < period and period % n == 0 and small:
            return False
        if n == period:
            return small
        if zr * zr + zi * zi > 4:
            return False
    return False


def exact_type(re_text, im_text, preperiod, period):
    """True when re + im i has exactly that preperiod and period (see the module doc)."""
    cr, ci = D(re_text), D(im_text)
    orbit = [(D(0), D(0))]
    for _ in range(preperiod + period):
        zr, zi = orbit[-1]
        orbit.append((zr * zr - zi * zi + cr, 2 * zr * zi + ci))
    tiny = D("1e-20")

    def close(a, b):
        (ar, ai), (br, bi) = orbit[a], orbit[b]
        return ((ar - br) ** 2 + (ai - bi) ** 2).sqrt() < tiny

    if not close(preperiod + period, preperiod):
        return False
    return not any(
        close(k + p, k) for k in range(preperiod + 1) for p in range(1, period + 1) if (k, p) != (preperiod, period)
    )


rng = random.Random(seed)
found = bad = errors = 0
start = time.time()
for _ in range(count):
    if rng.random() < 0.6:
        t = rng.uniform(0, 2 * math.pi)
        c = cmath.exp(1j * t) / 2 - cmath.exp(2j * t) / 4
    else:
        c = complex(rng.uniform(-2, 0.5), rng.uniform(-1.2, 1.2))
    c += complex(rng.uniform(-1, 1), rng.uniform(-1, 1)) * 0.01
    zoom = rng.choice([1e2, 1e3, 1e4, 1e6])
    run = subprocess.run(
        [binary, "find", "--center", f"{c.real!r},{c.imag!r}", "--zoom", f"{zoom:g}"]
        + (["--misiurewicz"] if misiurewicz else []),
        capture_output=True,
        text=True,
    )
    if run.returncode != 0:
        errors += 1
        continue
    header = run.stdout.splitlines()[0]
    period = int(re.search(r"\bperiod (\d+)", header).group(1))
    m = re.search(r'center = \["([^"]+)", "([^"]+)"\]', run.stdout)
    point = complex(float(m.group(1)), float(m.group(2)))
    disc = 2 / zoom * math.sqrt(1 + (4 / 3) ** 2)
    if misiurewicz:
        preperiod = int(re.search(r"preperiod (\d+)", header).group(1))
        exact = exact_type(m.group(1), m.group(2), preperiod, period)
    else:
        exact = exact_period(m.group(1), m.group(2), period)
    ok = abs(point - c) <= disc * (1 + 1e-9) and exact
    if ok:
        found += 1
    else:
        bad += 1
        print(f"FAILED CHECK: centre {c.real!r},{c.imag!r} zoom {zoom:g}: {header}")
what = "Misiurewicz points" if misiurewicz else "minibrots"
print(f"{count} views (seed {seed}): {found} {what} found, {bad} failed the check, {errors} errors; {time.time() - start:.1f} s")
sys.exit(1 if bad else 0)
