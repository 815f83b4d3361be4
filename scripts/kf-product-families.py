#!/usr/bin/env python3
"""Which of Kalles Fraktaler's refused formula types are products of two compositions.

Reads KF 2.15's formula definitions (`formula/formula.xml` in its public source, for
example the repository LegalizeAdulthood/kalles-fraktaler), evaluates each type's reference
lines (Xrn, Xin with c = 0) at random points, and compares them with the product forms
deepfield's docs give for them:

- Mothbrot a×b (types 54-68): z^a (|x| + i|y|)^b, a and b read from KF's name;
- SimonBrot 4th and 6th (33, 40): Mothbrot 2×2 and 3×3;
- SimonBrot2 4th (51): u (|Re u| + i|Im u|) with u = z².

Prints each type's largest relative difference over 2000 points in [-2, 2]²; the forms hold
when every line is at rounding level (about 1e-15).

    python3 scripts/kf-product-families.py PATH/TO/formula.xml
"""

import random
import re
import sys


def reference(xml, t):
    m = re.search(r'<group type="%d" name="([^"]*)"[^>]*>.*?<reference[^>]*>(.*?)</reference>' % t, xml, re.S)
    if not m:
        sys.exit(f"type {t}: no reference lines in the file")
    return m.group(1), m.group(2)


def kf_step(lines, z):
    """KF's reference step at z with c = 0: its lines are arithmetic on Xr, Xi, Xr2, Xi2."""
    env = {"Xr": z.real, "Xi": z.imag, "Xr2": z.real**2, "Xi2": z.imag**2, "Cr": 0.0, "Ci": 0.0, "abs": abs}
    out = {}
    for line in lines.split(";"):
        if "=" in line:
            name, expr = line.split("=", 1)
            out[name.strip()] = eval(expr, {"__builtins__": {}}, env)
    return complex(out["Xrn"], out["Xin"])


def fold(z):
    return complex(abs(z.real), abs(z.imag))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    xml = open(sys.argv[1], encoding="utf-8").read()
    forms = {33: (1, 2, 2), 40: (1, 3, 3), 51: (2, 1, 1)}
    for t in range(54, 69):
        name, _ = reference(xml, t)
        a, b = map(int, re.search(r"(\d)x(\d)", name).groups())
        forms[t] = (1, a, b)
    rng = random.Random(1)
    points = [complex(rng.uniform(-2, 2), rng.uniform(-2, 2)) for _ in range(2000)]
    for t, (pre, a, b) in sorted(forms.items()):
        name, lines = reference(xml, t)
        worst = 0.0
        for z in points:
            u = z**pre
            want = u**a * fold(u) ** b
            worst = max(worst, abs(kf_step(lines, z) - want) / (1 + abs(want)))
        form = f"u^{a} (|Re u| + i|Im u|)^{b}, u = z^{pre}" if pre > 1 else f"z^{a} (|x| + i|y|)^{b}"
        print(f"{t:3} {name:40} {form:40} {worst:.1e}")


if __name__ == "__main__":
    main()
