#!/usr/bin/env python3
"""How far rayterm's 256- and 16-colour pictures are from its truecolor one.

Runs the TUI in a tmux pane (160x48 by default) once per colour mode, waits
until the render is done and the viewport no longer changes, captures the
pane with its colours (`capture-pane -e -p`), and reads back what every cell
of the viewport shows: its symbol and its foreground and background colours
(SGR 38;5 / 48;5, 38;2 / 48;2 and the 16 ANSI codes, the last with xterm's
default RGB). Each cell's sub-pixels are compared with those of the truecolor
capture: the mean absolute difference per channel on the 0-255 scale, of
the sub-pixels, and of the means of each cell and of each block of 2x2
cells in linear light (what the eye sees from a little further off). Also prints how many cells changed between the last two
captures of a mode (shimmer).

Needs tmux. Usage:
    scripts/color-error.py [--scene env] [--size 160x48] [--symbols half]
                           [--modes 256,16] [--rayterm target/release/rayterm]
"""

import argparse
import os
import re
import subprocess
import sys
import time

ANSI16 = [
    (0, 0, 0), (205, 0, 0), (0, 205, 0), (205, 205, 0),
    (0, 0, 238), (205, 0, 205), (0, 205, 205), (229, 229, 229),
    (127, 127, 127), (255, 0, 0), (0, 255, 0), (255, 255, 0),
    (92, 92, 255), (255, 0, 255), (0, 255, 255), (255, 255, 255),
]
CUBE = [0, 95, 135, 175, 215, 255]


def palette(i):
    if i < 16:
        return ANSI16[i]
    if i < 232:
        j = i - 16
        return (CUBE[j // 36], CUBE[j // 6 % 6], CUBE[j % 6])
    return (8 + 10 * (i - 232),) * 3


# Sub-pixel grids and the glyphs' coverage, for the symbol modes.
GRIDS = {"half": (1, 2), "quad": (2, 2), "sextant": (2, 3), "octant": (2, 4)}
QUADRANTS = " ▘▝▀▖▌▞▛▗▚▐▜▄▙▟█"


def sextant_mask(ch):
    c = ord(ch)
    if not 0x1FB00 <= c <= 0x1FB3B:
        return None
    m = c - 0x1FB00 + 1
    # Unicode leaves out the left and right halves (masks 21 and 42).
    if m >= 21:
        m += 1
    if m >= 42:
        m += 1
    return m


def octant_masks():
    """Octant glyphs by mask, as rayterm numbers them (bit 0 top left)."""
    elsewhere = {0b1, 0b10, 0b1000000, 0b10000000, 0b11, 0b111111, 0b10100,
                 0b101000, 0b11000000, 0b11111100, 0b1111, 0b11110000,
                 0b1010101, 0b10101010, 0b101, 0b1010, 0b1010000, 0b10100000,
                 0b10100101, 0b1011010, 0b1011111, 0b10101111, 0b11110101,
                 0b11111010}
    out, code = {}, 0x1CD00
    for m in range(1, 255):
        if m not in elsewhere:
            out[chr(code)] = m
            code += 1
    blocks = {"▂": 0b11000000, "▆": 0b11111100, "▀": 0b1111, "▄": 0b11110000,
              "▌": 0b1010101, "▐": 0b10101010, "▘": 0b101, "▝": 0b1010,
              "▖": 0b1010000, "▗": 0b10100000, "▚": 0b10100101,
              "▞": 0b1011010, "▛": 0b1011111, "▜": 0b10101111,
              "▙": 0b11110101, "▟": 0b11111010}
    out.update(blocks)
    return out


OCTANTS = octant_masks()


def coverage(symbols, ch):
    """The foreground's share of each sub-pixel, in rayterm's mask order."""
    gx, gy = GRIDS[symbols]
    n = gx * gy
    if ch == " ":
        return [0.0] * n
    if symbols == "half":
        return {"▀": [1.0, 0.0], "▄": [0.0, 1.0], "█": [1.0, 1.0]}.get(ch)
    if symbols == "sextant" and ch in "▀▄":
        top = [1.0, 1.0, 0.5, 0.5, 0.0, 0.0]
        return top if ch == "▀" else [1 - a for a in top]
    if symbols == "sextant" and ch in "▌▐":
        m = 0b010101 if ch == "▌" else 0b101010
    elif symbols == "quad":
        m = QUADRANTS.find(ch)
        m = None if m < 0 else m
    elif symbols == "sextant":
        m = sextant_mask(ch)
    else:
        m = OCTANTS.get(ch)
    if m is None:
        return None
    return [float(m >> j & 1) for j in range(n)]


SGR = re.compile(r"\x1b\[([0-9;:]*)m")


def parse(capture):
    """Rows of cells (char, fg, bg), colours as RGB or None (default)."""
    rows = []
    for line in capture.split("\n"):
        fg = bg = None
        cells = []
        pos = 0
        while pos < len(line):
            m = SGR.match(line, pos)
            if m:
                fg, bg = sgr(m.group(1), fg, bg)
                pos = m.end()
                continue
            if line[pos] == "\x1b":
                # Another escape (hyperlinks and the like): skip it.
                end = re.match(r"\x1b(\[[0-9;?]*[A-Za-z]|\][^\x07]*\x07|.)", line[pos:])
                pos += end.end() if end else 1
                continue
            cells.append((line[pos], fg, bg))
            pos += 1
        rows.append(cells)
    return rows


def sgr(params, fg, bg):
    p = [int(x) if x else 0 for x in params.replace(":", ";").split(";")]
    i = 0
    while i < len(p):
        v = p[i]
        if v == 0:
            fg = bg = None
        elif v in (38, 48) and i + 1 < len(p):
            if p[i + 1] == 5 and i + 2 < len(p):
                c = palette(p[i + 2])
                i += 2
            elif p[i + 1] == 2 and i + 4 < len(p):
                c = tuple(p[i + 2:i + 5])
                i += 4
            else:
                c = None
            if v == 38:
                fg = c
            else:
                bg = c
        elif 30 <= v <= 37:
            fg = ANSI16[v - 30]
        elif 90 <= v <= 97:
            fg = ANSI16[v - 90 + 8]
        elif 40 <= v <= 47:
            bg = ANSI16[v - 40]
        elif 100 <= v <= 107:
            bg = ANSI16[v - 100 + 8]
        elif v == 39:
            fg = None
        elif v == 49:
            bg = None
        i += 1
    return fg, bg


class Pane:
    def __init__(self, size, command):
        self.sock = f"rayterm-color-error-{os.getpid()}"
        w, h = size
        self.tmux("new-session", "-d", "-x", str(w), "-y", str(h), command)

    def tmux(self, *args):
        return subprocess.run(["tmux", "-L", self.sock, "-f", "/dev/null", *args],
                              capture_output=True, text=True).stdout

    def capture(self, colours=True):
        args = ["capture-pane", "-p", "-t", "0"] + (["-e"] if colours else [])
        return self.tmux(*args)

    def close(self):
        self.tmux("kill-server")


def viewport(capture, symbols):
    """The viewport's cells: its size in pixels is in its title line."""
    rows = parse(capture)
    title = "".join(c for c, _, _ in rows[0])
    m = re.search(r"(\d+)x(\d+) px", title)
    if not m:
        return None
    gx, gy = GRIDS[symbols]
    cols, lines = int(m.group(1)) // gx, int(m.group(2)) // gy
    return [row[:cols] for row in rows[1:1 + lines]]


def shown(cells, symbols):
    """Sub-pixel colours, as a dict (x, y) -> RGB floats."""
    gx, gy = GRIDS[symbols]
    px = {}
    for cy, row in enumerate(cells):
        for cx, (ch, fg, bg) in enumerate(row):
            cov = coverage(symbols, ch)
            if cov is None or bg is None:
                raise ValueError(f"cell ({cx}, {cy}): {ch!r} {fg} {bg}")
            f = fg or (0, 0, 0)
            for j, a in enumerate(cov):
                px[(cx * gx + j % gx, cy * gy + j // gx)] = tuple(
                    a * f[c] + (1 - a) * bg[c] for c in range(3))
    return px


def run(args, mode):
    cmd = f"{args.rayterm} tui {args.scene} --color {mode} --symbols {args.symbols} --graphics symbols"
    pane = Pane(args.size, cmd)
    try:
        start = time.time()
        while "(don" not in pane.capture(False):
            if time.time() - start > args.patience:
                sys.exit(f"color-error: {mode}: not done within {args.patience} s")
            time.sleep(0.2)
        last = None
        changed = 0
        while True:
            time.sleep(1.0)
            cells = viewport(pane.capture(), args.symbols)
            if cells is not None and cells == last:
                return cells, changed
            if last is not None and cells is not None:
                changed = sum(a != b for ra, rb in zip(cells, last) for a, b in zip(ra, rb))
            last = cells
    finally:
        pane.close()


def lin(v):
    v /= 255.0
    return v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4


def blurred(px, w, h, gx, gy, cells=2):
    """Means over blocks of `cells` x `cells` cells, in linear light."""
    out = {}
    bw, bh = cells * gx, cells * gy
    for by in range(h // bh):
        for bx in range(w // bw):
            s = [0.0, 0.0, 0.0]
            for y in range(by * bh, by * bh + bh):
                for x in range(bx * bw, bx * bw + bw):
                    for c in range(3):
                        s[c] += lin(px[(x, y)][c])
            out[(bx, by)] = s
    k = bw * bh
    return {p: tuple(255 * (v / k) ** (1 / 2.2) for v in s) for p, s in out.items()}


def mae(a, b):
    keys = a.keys() & b.keys()
    return sum(abs(a[k][c] - b[k][c]) for k in keys for c in range(3)) / (3 * len(keys))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default="env")
    ap.add_argument("--size", default="160x48")
    ap.add_argument("--symbols", default="half", choices=list(GRIDS))
    ap.add_argument("--modes", default="256,16")
    ap.add_argument("--rayterm", default="target/release/rayterm")
    ap.add_argument("--patience", type=float, default=120.0)
    args = ap.parse_args()
    args.size = tuple(int(v) for v in args.size.split("x"))
    truth, _ = run(args, "truecolor")
    ref = shown(truth, args.symbols)
    gx, gy = GRIDS[args.symbols]
    w, h = len(truth[0]) * gx, len(truth) * gy
    print(f"{args.scene} at {args.size[0]}x{args.size[1]}, {args.symbols}: viewport {w}x{h} px")
    for mode in args.modes.split(","):
        cells, changed = run(args, mode)
        px = shown(cells, args.symbols)
        per = [mae(blurred(px, w, h, gx, gy, k), blurred(ref, w, h, gx, gy, k)) for k in (1, 2)]
        print(f"{mode:>3} colours: mean absolute error per sub-pixel {mae(px, ref):.2f}, "
              f"per cell {per[0]:.2f}, per 2x2 cells {per[1]:.2f} (0-255); "
              f"cells changed between the last two captures: {changed}")


if __name__ == "__main__":
    main()
