#!/usr/bin/env python3
"""Rays per second of every progressive path against one-shot renders.

For each scene and size: `render --spp 64` (one pass), then each
progressive path (`--time` uniform and adaptive, `--target-error`, the TUI's
passes through `bench tui`) with the rate of the same samples traced again
in one pass, each pixel's together, as `render --spp N` would
(`--compare-one-shot`, `one_shot_mrays_per_s`). Rounds repeat the runs; the
table gives medians of the rates and of the ratios. Usage:

    scripts/progressive-speed.py [--rounds R] [--bin PATH] [--time S]
                                 [--scene SCENE ...] [--size WxH ...]

Needs a release build (`cargo build --release`); the bunny needs
`../shared/data/meshes` and is left out without it.
"""
import argparse
import json
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

SCENES = ["teapot:256", "teapot", "../shared/data/meshes/bunny.obj", "mirrors"]
SIZES = ["160x96", "1024x768"]
# The TUI's terminal for a size (two pixels a cell) and the target error.
TERMINAL = {"160x96": "160x48", "1024x768": "1024x384"}
ERROR = {"160x96": "0.003", "1024x768": "0.01"}


def rate(text):
    m = re.search(r"([0-9.]+) ([kMG]?)rays/s", text)
    return float(m.group(1)) * {"k": 1e-3, "M": 1.0, "G": 1e3, "": 1e-6}[m.group(2)]


def render(binary, out, scene, size, *args):
    """Mrays/s, mean spp and, with --compare-one-shot, the one-pass rate."""
    r = subprocess.run(
        [binary, "render", scene, "--size", size, *args, "-o", out],
        capture_output=True,
        text=True,
    )
    if r.returncode != 0:
        sys.exit(f"render {scene} {size} {' '.join(args)}: {r.stderr.strip()}")
    lines = r.stdout.strip().splitlines()
    summary = next(l for l in lines if " -> " in l)
    # "N spp" or, adaptive, "A / B / C spp" (min / mean / max).
    m = re.search(r"/ ([0-9.]+) / [0-9]+ spp", summary) or re.search(r"([0-9]+) spp", summary)
    once = [rate(l.split(";")[0]) for l in lines if l.startswith("the same samples")]
    return rate(summary), float(m.group(1)), once[0] if once else None


def tui(binary, scene, size):
    passes = "40" if size == "160x96" else "20"
    r = subprocess.run(
        [binary, "bench", "tui", scene, "--terminal", TERMINAL[size], "--passes", passes],
        capture_output=True,
        text=True,
    )
    if r.returncode != 0:
        sys.exit(f"bench tui {scene}: {r.stderr.strip()}")
    d = json.loads(r.stdout)
    return d["mrays_per_s"], d["spp_mean"], d["one_shot_mrays_per_s"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--bin", default="target/release/rayterm")
    ap.add_argument("--time", default="3")
    ap.add_argument("--scene", action="append")
    ap.add_argument("--size", action="append")
    a = ap.parse_args()
    scenes = a.scene or [s for s in SCENES if "/" not in s or Path(s).exists()]
    sizes = a.size or SIZES
    if len(scenes) < len(SCENES) and not a.scene:
        print("# the bunny is left out: ../shared/data/meshes is not here", file=sys.stderr)
    modes = {
        "--time uniform": ["--time", a.time, "--uniform"],
        "--time adaptive": ["--time", a.time],
        "--target-error": None,
        "TUI passes": "tui",
    }
    rates, ratios, spp = {}, {}, {}
    with tempfile.TemporaryDirectory() as d:
        out = str(Path(d) / "p.png")
        for _ in range(a.rounds):
            for scene in scenes:
                for size in sizes:
                    one, _, _ = render(a.bin, out, scene, size, "--spp", "64")
                    rates.setdefault((scene, size, "--spp 64"), []).append(one)
                    for mode, args in modes.items():
                        if args == "tui":
                            got, n, once = tui(a.bin, scene, size)
                        else:
                            args = args or ["--target-error", ERROR[size]]
                            got, n, once = render(
                                a.bin, out, scene, size, *args, "--compare-one-shot"
                            )
                        key = (scene, size, mode)
                        rates.setdefault(key, []).append(got)
                        spp.setdefault(key, []).append(n)
                        ratios.setdefault(key, []).append((got / one, got / once))
                    print(f"# {scene} {size} done", file=sys.stderr, flush=True)
    med = statistics.median
    print("| scene | size | `--spp 64` Mrays/s | path | Mrays/s | mean spp | x `--spp 64` | x one pass |")
    print("| --- | --- | ---: | --- | ---: | ---: | ---: | ---: |")
    for scene in scenes:
        for size in sizes:
            one = med(rates[(scene, size, "--spp 64")])
            for mode in modes:
                k = (scene, size, mode)
                r64 = med([r[0] for r in ratios[k]])
                rn = med([r[1] for r in ratios[k]])
                name = Path(scene).name if "/" in scene else scene
                print(
                    f"| {name} | {size} | {one:.2f} | {mode} | {med(rates[k]):.2f} | "
                    f"{med(spp[k]):.1f} | {r64:.2f} | {rn:.2f} |"
                )


if __name__ == "__main__":
    main()
