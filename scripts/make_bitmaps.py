#!/usr/bin/env python3
"""Writes the small RGBA PNGs the project uses, with the Python standard library only.

    python3 scripts/make_bitmaps.py

Outputs (paths relative to the repository root, which is found from this file):

- scenes/bitmaps/star.png: 64x64 five-pointed star for the bitmap orbit trap scene.
  Opaque (alpha 255) inside the star, with a radial gradient from pale yellow at the
  centre to deep orange at the tips; fully transparent (0, 0, 0, 0) outside, including
  a transparent border, because the trap clamps texture coordinates to the edge texels.
- scenes/bitmaps/sprites.png: 192x48 sprite sheet for the animated bitmap trap (Inigo Quilez's
  variant): 4 frames of 48x48 side by side, a five-pointed star turning by 18 degrees a
  frame and shifting from gold to rose; transparent outside the star.
- tests/fixtures/trap.png: 16x16 test fixture; the left 8 columns are opaque red
  (255, 0, 0, 255), the right 8 columns are fully transparent (0, 0, 0, 0).

The output is deterministic: running the script again writes byte-identical files.
"""

import math
import struct
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def write_png_rgba(path, width, height, pixels):
    """Writes an 8-bit RGBA PNG; `pixels` is a row-major list of (r, g, b, a) tuples."""
    assert len(pixels) == width * height

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    raw = bytearray()
    for y in range(height):
        raw.append(0)  # filter type: none
        for r, g, b, a in pixels[y * width : (y + 1) * width]:
            raw += bytes((r, g, b, a))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)  # 8 bits, colour type 6 (RGBA)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b"")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)


def star_polygon(cx, cy, r_outer, r_inner, points=5):
    """Vertices of a star, first tip pointing straight up (image y grows downwards)."""
    verts = []
    for i in range(2 * points):
        r = r_outer if i % 2 == 0 else r_inner
        a = -math.pi / 2 + i * math.pi / points
        verts.append((cx + r * math.cos(a), cy + r * math.sin(a)))
    return verts


def inside(poly, x, y):
    """Even-odd point-in-polygon test."""
    hit = False
    n = len(poly)
    for i in range(n):
        x1, y1 = poly[i]
        x2, y2 = poly[(i + 1) % n]
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            hit = not hit
    return hit


def lerp(a, b, t):
    return round(a + (b - a) * t)


def star_png(size=64):
    c = (size - 1) / 2.0
    r_outer = size * 0.46  # leaves a transparent border of at least one texel
    poly = star_polygon(c, c + size * 0.03, r_outer, r_outer * 0.42)
    centre = (255, 250, 200)  # pale yellow
    tips = (255, 120, 0)  # deep orange
    pixels = []
    for y in range(size):
        for x in range(size):
            if inside(poly, x, y):
                t = min(1.0, math.hypot(x - c, y - c) / r_outer)
                pixels.append((lerp(centre[0], tips[0], t), lerp(centre[1], tips[1], t), lerp(centre[2], tips[2], t), 255))
            else:
                pixels.append((0, 0, 0, 0))
    return size, size, pixels


def sprite_sheet(frame=48, frames=4):
    """Frames side by side: the star turned by 18 degrees per frame, gold turning rose."""
    c = (frame - 1) / 2.0
    r_outer = frame * 0.45
    colours = [((255, 240, 170), (230, 150, 20)), ((255, 225, 190), (235, 110, 60)),
               ((255, 215, 215), (220, 70, 110)), ((250, 210, 240), (190, 60, 160))]
    pixels = [(0, 0, 0, 0)] * (frame * frames * frame)
    for k in range(frames):
        poly = star_polygon(c, c, r_outer, r_outer * 0.42)
        a = math.radians(18 * k)
        poly = [(c + (x - c) * math.cos(a) - (y - c) * math.sin(a), c + (x - c) * math.sin(a) + (y - c) * math.cos(a)) for x, y in poly]
        centre, tips = colours[k]
        for y in range(frame):
            for x in range(frame):
                if inside(poly, x, y):
                    t = min(1.0, math.hypot(x - c, y - c) / r_outer)
                    pixels[y * frame * frames + k * frame + x] = (
                        lerp(centre[0], tips[0], t), lerp(centre[1], tips[1], t), lerp(centre[2], tips[2], t), 255)
    return frame * frames, frame, pixels


def trap_fixture():
    w = h = 16
    pixels = [(255, 0, 0, 255) if x < w // 2 else (0, 0, 0, 0) for y in range(h) for x in range(w)]
    return w, h, pixels


def main():
    outputs = {
        ROOT / "scenes" / "bitmaps" / "star.png": star_png(),
        ROOT / "scenes" / "bitmaps" / "sprites.png": sprite_sheet(),
        ROOT / "tests" / "fixtures" / "trap.png": trap_fixture(),
    }
    for path, (w, h, pixels) in outputs.items():
        write_png_rgba(path, w, h, pixels)
        print(f"wrote {path.relative_to(ROOT)} ({w}x{h} RGBA)")


if __name__ == "__main__":
    main()
