#!/usr/bin/env python3
"""Finds widgets of volvis-gui in a screenshot (for the GUI tests; no PIL needed).

  locate.py timeline SHOT.png   prints "LEFT TOP RIGHT BOTTOM" of the Animator
                                page's timeline (its background is RGB 31,42,51,
                                TIMELINE_R/G/B in apps/volvis-gui/vv-animator-page.c)
  locate.py sidebar SHOT.png    prints "X Y" per page entry of the side bar,
                                top to bottom (the centre of each line of text)
  locate.py count R,G,B SHOT.png [X0 Y0 X1 Y1]
                                prints how many pixels (in the box) have that colour

Exits 1 when nothing is found.
"""
import subprocess
import sys


def load(path):
    size = subprocess.run(["identify", "-format", "%w %h", path], capture_output=True,
                          text=True, check=True).stdout.split()
    w, h = int(size[0]), int(size[1])
    rgb = subprocess.run(["convert", path, "-depth", "8", "rgb:-"], capture_output=True,
                         check=True).stdout
    return w, h, rgb


def px(img, x, y):
    w, _, rgb = img
    i = 3 * (y * w + x)
    return rgb[i], rgb[i + 1], rgb[i + 2]


def timeline(img):
    w, h, _ = img
    xs, ys = [], []
    for y in range(0, h, 2):
        for x in range(0, w, 2):
            r, g, b = px(img, x, y)
            if abs(r - 31) <= 1 and abs(g - 42) <= 1 and abs(b - 51) <= 1:
                xs.append(x)
                ys.append(y)
    if len(xs) < 200:
        return None
    return min(xs), min(ys), max(xs) + 1, max(ys) + 1


def sidebar(img):
    """The side bar starts where the scene view's background ends on the top
    row; its entries are the bands of dark text pixels in its first 120 px."""
    w, h, _ = img
    bg = px(img, 2, 2)
    x0 = next((x for x in range(w // 4, w) if px(img, x, 2) != bg), None)
    if x0 is None:
        return []
    bands, start = [], None
    for y in range(h):
        dark = any(sum(px(img, x, y)) < 300 for x in range(x0 + 8, min(x0 + 120, w)))
        if dark and start is None:
            start = y
        elif not dark and start is not None:
            bands.append((start, y))
            start = None
    return [(x0 + 50, (a + b) // 2) for a, b in bands if b - a >= 5]


def main():
    what = sys.argv[1]
    if what == "count":
        rgb = tuple(int(c) for c in sys.argv[2].split(","))
        img = load(sys.argv[3])
        w, h, _ = img
        x0, y0, x1, y1 = (int(v) for v in sys.argv[4:8]) if len(sys.argv) >= 8 else (0, 0, w, h)
        print(sum(1 for y in range(max(y0, 0), min(y1, h)) for x in range(max(x0, 0), min(x1, w))
                  if px(img, x, y) == rgb))
        return
    path = sys.argv[2]
    img = load(path)
    if what == "timeline":
        box = timeline(img)
        if not box:
            sys.exit(1)
        print(*box)
    elif what == "sidebar":
        entries = sidebar(img)
        if not entries:
            sys.exit(1)
        for x, y in entries:
            print(x, y)
    else:
        sys.exit(f"locate.py: unknown '{what}'")


if __name__ == "__main__":
    main()
