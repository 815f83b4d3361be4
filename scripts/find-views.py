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

    scripts/find-views.py [SEED] [COUNT] [DEEPFIELD]   # defaults: 11, 80, target/release/deepfield
"""
import cmath
import decimal
import math
import random
import re
import subprocess
import sys
import time

seed = int(sys.argv[1]) if len(sys.argv) > 1 else 11
count = int(sys.argv[2]) if len(sys.argv) > 2 else 80
binary = sys.argv[3] if len(sys.argv) > 3 else "target/release/deepfield"
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
        [binary, "find", "--center", f"{c.real!r},{c.imag!r}", "--zoom", f"{zoom:g}"],
        capture_output=True,
        text=True,
    )
    if run.returncode != 0:
        errors += 1
        continue
    header = run.stdout.splitlines()[0]
    period = int(re.search(r"period (\d+)", header).group(1))
    m = re.search(r'center = \["([^"]+)", "([^"]+)"\]', run.stdout)
    nucleus = complex(float(m.group(1)), float(m.group(2)))
    disc = 2 / zoom * math.sqrt(1 + (4 / 3) ** 2)
    ok = abs(nucleus - c) <= disc * (1 + 1e-9) and exact_period(m.group(1), m.group(2), period)
    if ok:
        found += 1
    else:
        bad += 1
        print(f"FAILED CHECK: centre {c.real!r},{c.imag!r} zoom {zoom:g}: {header}")
print(f"{count} views (seed {seed}): {found} minibrots found, {bad} failed the check, {errors} errors; {time.time() - start:.1f} s")
sys.exit(1 if bad else 0)
