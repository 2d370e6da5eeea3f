#!/usr/bin/env python3
"""Makes docs/tui.png, the picture of the TUI at the top of the README.

Runs rayterm in kitty on a virtual X display (Xvfb), so that the viewport is
a picture in the kitty graphics protocol, waits until the render has some
samples, clicks a pixel (the same mouse report a real click sends), steps
the pixel overlay to its first view (`o`: the pixel's rays drawn into the
viewport), and grabs the window with xwd. The XWD dump is read here and
written as PNG.

Needs kitty, Xvfb and xwd (Debian and Ubuntu: apt-get install kitty xvfb
x11-apps), Python 3 with Pillow (pip install pillow), and a release build
(cargo build --release). Usage, from the repository's root:

    scripts/tui-picture.py [--out docs/tui.png] [--scene mirrors]
                           [--cells 160x48] [--font-size 9] [--pixel 322,255]
                           [--spp 16] [--rayterm target/release/rayterm]

The font is kitty's default monospace font on the machine (DejaVu Sans Mono
where fontconfig has it); 160x48 cells of 7x15 pixels make a picture of
1121x721 pixels.
"""

import argparse
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time

from PIL import Image

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TITLE = "rayterm-picture"


def read_xwd(path):
    """An XWD dump (ZPixmap, 24 or 32 bits a pixel) as a Pillow image."""
    with open(path, "rb") as f:
        d = f.read()

    def field(i):
        return struct.unpack(">I", d[i * 4:i * 4 + 4])[0]

    header, fmt, w, h = field(0), field(2), field(4), field(5)
    byte_order, bpp, line = field(7), field(11), field(12)
    colours = field(19)
    if fmt != 2 or bpp not in (24, 32):
        sys.exit("tui-picture: XWD format %d at %d bits a pixel" % (fmt, bpp))
    raw = d[header + colours * 12:][:line * h]
    mode = {(0, 32): "BGRX", (1, 32): "XRGB", (0, 24): "BGR", (1, 24): "RGB"}[(byte_order, bpp)]
    return Image.frombytes("RGB", (w, h), raw, "raw", mode, line)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(REPO, "docs", "tui.png"))
    ap.add_argument("--rayterm", default=os.path.join(REPO, "target", "release", "rayterm"))
    ap.add_argument("--scene", default="mirrors")
    ap.add_argument("--cells", default="160x48", help="the terminal's size, COLUMNSxROWS")
    ap.add_argument("--font-size", default="9", help="kitty's font size, in points")
    ap.add_argument("--pixel", default="322,255",
                    help="the viewport pixel to select (the left mirror sphere, where it "
                         "reflects the red one)")
    ap.add_argument("--spp", type=float, default=16,
                    help="wait until the Render panel shows this mean spp")
    args = ap.parse_args()

    for tool in ("kitty", "Xvfb", "xwd"):
        if shutil.which(tool) is None:
            sys.exit("tui-picture: needs %s (apt-get install kitty xvfb x11-apps)" % tool)
    if not os.access(args.rayterm, os.X_OK):
        sys.exit("tui-picture: no %s: build first (cargo build --release)" % args.rayterm)
    cols, rows = (int(v) for v in args.cells.split("x"))
    px, py = (int(v) for v in args.pixel.split(","))

    tmp = tempfile.mkdtemp(prefix="rayterm-picture-")
    sock = "unix:" + os.path.join(tmp, "kitty.sock")
    children = []
    try:
        # Xvfb picks a free display and writes its number on the pipe.
        xvfb = subprocess.Popen(
            ["Xvfb", "-displayfd", "1", "-screen", "0", "1920x1200x24", "-nolisten", "tcp"],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        children.append(xvfb)
        display = ":" + xvfb.stdout.readline().decode().strip()
        env = dict(os.environ, DISPLAY=display)
        for var in ("TMUX", "TERM_PROGRAM", "LC_TERMINAL", "COLORTERM"):
            env.pop(var, None)
        kitty = subprocess.Popen(
            ["kitty", "--config", "NONE", "--title", TITLE,
             "-o", "font_size=" + args.font_size,
             "-o", "remember_window_size=no",
             "-o", "initial_window_width=%dc" % cols,
             "-o", "initial_window_height=%dc" % rows,
             "-o", "window_padding_width=0",
             "-o", "placement_strategy=top-left",
             "-o", "allow_remote_control=yes", "--listen-on", sock,
             "-e", args.rayterm, args.scene],
            env=env, cwd=tmp, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        children.append(kitty)

        def remote(*words):
            return subprocess.run(["kitty", "@", "--to", sock] + list(words),
                                  env=env, capture_output=True, text=True)

        def screen():
            return remote("get-text", "--match", "all").stdout

        def wait_for(what, seconds):
            end = time.time() + seconds
            while time.time() < end:
                text = screen()
                found = what(text)
                if found:
                    return found
                time.sleep(0.3)
            sys.exit("tui-picture: waited %d s; the screen shows:\n%s" % (seconds, screen()))

        # The cell size, from the status line ("kitty graphics, cells 7x15 px").
        cell = wait_for(lambda t: re.search(r"cells (\d+)x(\d+) px", t), 30)
        cw, ch = int(cell.group(1)), int(cell.group(2))
        wait_for(lambda t: any(float(m) >= args.spp
                               for m in re.findall(r"([\d.]+) spp", t)), 120)
        # A click on the pixel's cell: the viewport starts at the second row.
        col, row = px // cw + 1, py // ch + 2
        remote("send-text", "--match", "all", "\x1b[<0;%d;%dM\x1b[<0;%d;%dm" % (col, row, col, row))
        picked = wait_for(lambda t: re.search(r"Ray tree: pixel \((\d+), (\d+)\)", t), 20)
        remote("send-text", "--match", "all", "o")
        wait_for(lambda t: "rays by kind" in t, 20)
        time.sleep(3)
        shot = os.path.join(tmp, "shot.xwd")
        subprocess.run(["xwd", "-name", TITLE, "-silent", "-out", shot], env=env, check=True)
        image = read_xwd(shot)
        image.save(args.out, optimize=True)
        remote("send-text", "--match", "all", "q")
        print("%s: %dx%d pixels, %d bytes; pixel (%s, %s) selected, cells %dx%d px"
              % (args.out, image.width, image.height, os.path.getsize(args.out),
                 picked.group(1), picked.group(2), cw, ch))
    finally:
        for c in reversed(children):
            c.terminate()
            try:
                c.wait(timeout=5)
            except subprocess.TimeoutExpired:
                c.kill()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
