#!/usr/bin/env python3
"""rayterm over a slow link in a real terminal on a virtual X display.

Pixel graphics need a real terminal to draw them, so
`scripts/slow-link.sh` (tmux) measures block symbols only; this runs the TUI
in xterm (`-ti vt340`: sixel), kitty (kitty graphics, software OpenGL) or
mlterm (sixel) on Xvfb, with rayterm's output throttled by `pv -L` on its
way to the terminal (the answers come back unthrottled, as over a slow
download link). It reads the stream as it arrives and prints the Render
panel's `view shown in` (the first full picture, by the terminal's answers)
and when that line arrived after launch; `--shot` saves a screenshot then.

Needs Xvfb, xwd, pv, script (util-linux), the terminal, and Python 3 with
Pillow for `--shot`. Usage, from the repository's root, after
`cargo build --release`:

    scripts/slow-link-x.py [--rate 32k] [--terminal xterm|kitty|mlterm]
                           [--scene cornell] [--cells 160x48] [--shot FILE.png]
                           [--shot-after SECONDS] [-- TUI OPTIONS]

The TUI gets `--color 256` unless the options name a `--color` (as in
slow-link.sh), and the terminal's default: `--graphics auto`.
"""

import argparse
import os
import re
import shlex
import shutil
import struct
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# CSI sequences (cursor moves and colours), kitty APC and sixel DCS images.
ESCAPES = re.compile(rb"\x1b\[[0-9;?>]*[ -/]*[@-~]|\x1b[_P][^\x1b]*\x1b\\")
SHOWN = re.compile(rb"view shown in ([0-9.]+ m?s)")


def terminal(name, cols, rows, inner):
    if name == "xterm":
        return ["xterm", "-ti", "vt340", "-fa", "DejaVu Sans Mono", "-fs", "8",
                "-geometry", "%dx%d+0+0" % (cols, rows), "-e", "sh", "-c", inner]
    if name == "kitty":
        return ["kitty", "-o", "font_size=8", "-o", "remember_window_size=no",
                "-o", "initial_window_width=%dc" % cols,
                "-o", "initial_window_height=%dc" % rows,
                "-o", "placement_strategy=top-left", "-o", "window_padding_width=0",
                "-e", "sh", "-c", inner]
    if name == "mlterm":
        return ["mlterm", "--geometry", "%dx%d+0+0" % (cols, rows), "-w", "10",
                "-e", "sh", "-c", inner]
    sys.exit("slow-link-x: unknown terminal %s" % name)


def screenshot(display, path):
    from PIL import Image
    raw = subprocess.run(["xwd", "-root", "-silent"], env=dict(os.environ, DISPLAY=display),
                         capture_output=True, check=True).stdout

    def field(i):
        return struct.unpack(">I", raw[i * 4:i * 4 + 4])[0]

    header, w, h = field(0), field(4), field(5)
    byte_order, bpp, line, colours = field(7), field(11), field(12), field(19)
    mode = {(0, 32): "BGRX", (1, 32): "XRGB", (0, 24): "BGR", (1, 24): "RGB"}[(byte_order, bpp)]
    data = raw[header + colours * 12:][:line * h]
    Image.frombytes("RGB", (w, h), data, "raw", mode, line).save(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rate", default="32k", help="pv -L's rate (bytes per second)")
    ap.add_argument("--terminal", default="xterm", choices=["xterm", "kitty", "mlterm"])
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--cells", default="160x48", help="the terminal's size, COLUMNSxROWS")
    ap.add_argument("--shot", help="a screenshot when the first full picture is in")
    ap.add_argument("--shot-after", type=float, default=0.5, metavar="SECONDS",
                    help="how long after it")
    ap.add_argument("--rayterm", default=os.environ.get(
        "RAYTERM", os.path.join(REPO, "target", "release", "rayterm")))
    ap.add_argument("options", nargs="*", help="more TUI options (after --)")
    args = ap.parse_args()
    for tool in ("Xvfb", "xwd", "pv", "script", args.terminal):
        if shutil.which(tool) is None:
            sys.exit("slow-link-x: needs %s" % tool)
    if not os.access(args.rayterm, os.X_OK):
        sys.exit("slow-link-x: build first (cargo build --release)")
    cols, rows = (int(v) for v in args.cells.split("x"))
    options = list(args.options)
    if not any(o == "--color" or o.startswith("--color=") for o in options):
        options = ["--color", "256"] + options
    for _ in range(3):
        if measure(args, cols, rows, options):
            return
    sys.exit("slow-link-x: the terminal would not start")


def measure(args, cols, rows, options):
    """One run; false when the terminal could not start."""
    tmp = tempfile.mkdtemp(prefix="rayterm-slow-x-")
    log = os.path.join(tmp, "out")
    cmd = shlex.join([args.rayterm, "tui", args.scene] + options)
    pidfile = os.path.join(tmp, "pid")
    # script's pid is kept: ending it hangs up rayterm's terminal.
    # (An asynchronous command's input is /dev/null unless redirected from
    # a copy.)
    inner = ("exec 3<&0; (script -qfec %s /dev/null <&3 3<&- & echo $! > %s; wait) "
             "| pv -qL %s | tee %s; sleep 60") % (
        shlex.quote(cmd), shlex.quote(pidfile), shlex.quote(args.rate), shlex.quote(log))
    # A display number of its own: another Xvfb may start meanwhile.
    n = next(n for n in range(150, 400) if not os.path.exists("/tmp/.X%d-lock" % n))
    display = ":%d" % n
    xvfb = subprocess.Popen(["Xvfb", display, "-screen", "0", "1600x1000x24",
                             "-nolisten", "tcp"], stderr=subprocess.DEVNULL)
    for _ in range(100):
        if os.path.exists("/tmp/.X11-unix/X%d" % n) or xvfb.poll() is not None:
            break
        time.sleep(0.05)
    env = dict(os.environ, DISPLAY=display, LIBGL_ALWAYS_SOFTWARE="1")
    # The display number comes before the display takes clients.
    time.sleep(1.5)
    term = None
    try:
        start = time.monotonic()
        term = subprocess.Popen(terminal(args.terminal, cols, rows, inner), env=env,
                                stdout=subprocess.DEVNULL, start_new_session=True)
        shown = None
        while shown is None:
            if time.monotonic() - start > 60:
                sys.exit("slow-link-x: no picture within 60 s")
            if term.poll() is not None:
                # A display another Xvfb took meanwhile, now and then.
                print("slow-link-x: %s ended (status %s) on display %s; again"
                      % (args.terminal, term.returncode, display), file=sys.stderr)
                return False
            time.sleep(0.02)
            try:
                with open(log, "rb") as f:
                    text = ESCAPES.sub(b" ", f.read())
            except FileNotFoundError:
                continue
            text = re.sub(rb" +", b" ", text)
            m = SHOWN.search(text)
            if m:
                shown = m.group(1).decode()
        seen = time.monotonic() - start
        size = os.path.getsize(log)
        print("%s, %s: first full picture: view shown in %s (by the terminal's answers); "
              "the line arrived %.2f s after launch, %d bytes in"
              % (args.terminal, " ".join(options), shown, seen, size))
        if args.shot:
            time.sleep(args.shot_after)
            screenshot(display, args.shot)
        return True
    finally:
        try:
            with open(pidfile) as f:
                os.kill(int(f.read()), 15)
        except (OSError, ValueError):
            pass
        if term is not None and term.poll() is None:
            os.killpg(term.pid, 15)
            term.wait()
        xvfb.terminate()
        xvfb.wait()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
