#!/usr/bin/env bash
# rayterm over a slow link: the TUI runs in a 160x48 tmux pane with its
# output throttled by pv (default 32 kB/s), and this measures how long the
# first full picture takes to appear and how long `q` takes to act.
# The TUI gets --color 256 unless the extra options name a --color.
# Block symbols only: pixel graphics need a real terminal, which
# scripts/slow-link-x.py runs on a virtual X display.
# Needs tmux, pv and script (util-linux). Usage:
#   scripts/slow-link.sh [RATE] [SCENE] [extra rayterm tui options...]
set -eu
rate=${1:-32k}
scene=${2:-cornell}
shift $(($# < 2 ? $# : 2))
bin=${RAYTERM:-target/release/rayterm}
for tool in tmux pv script; do
    command -v "$tool" >/dev/null || { echo "slow-link: needs $tool" >&2; exit 2; }
done
[ -x "$bin" ] || { echo "slow-link: build first (cargo build --release)" >&2; exit 2; }
sock=rayterm-slow-$$
cleanup() { tmux -L "$sock" kill-server 2>/dev/null || true; }
trap cleanup EXIT
now() { date +%s.%N; }
screen() { tmux -L "$sock" capture-pane -p -t 0 2>/dev/null || true; }
color="--color 256"
for a in "$@"; do
    case "$a" in --color | --color=*) color="" ;; esac
done
cmd="$bin tui $scene $color $*"
start=$(now)
tmux -L "$sock" new-session -d -x 160 -y 48 \
    "script -qfec '$cmd' /dev/null | pv -qL $rate; sleep 60"
# The first full picture: the Render panel says when the terminal had
# taken all of it ("view shown in X s", measured from the view's start by
# the terminal's answers); the panel line itself comes a sweep later.
shown=""
while [ -z "$shown" ]; do
    shown=$(screen | grep -o 'view shown in [0-9.]* m\?s' | head -1 || true)
    if [ "$(echo "$(now) - $start > 30" | bc)" = 1 ]; then
        echo "slow-link: no picture within 30 s" >&2
        exit 1
    fi
    sleep 0.05
done
seen=$(echo "$(now) - $start" | bc)
echo "first full picture: $shown (by the terminal's answers); the line read at $seen s after launch"
# q three seconds after launch, just after a camera move, so that a whole
# new picture is on its way.
wait=$(echo "3 - ($(now) - $start)" | bc)
if [ "$(echo "$wait > 0" | bc)" = 1 ]; then sleep "$wait"; fi
tmux -L "$sock" send-keys -t 0 Left
sleep 0.2
typed=$(now)
tmux -L "$sock" send-keys -t 0 q
while screen | grep -q 'Render'; do
    if [ "$(echo "$(now) - $typed > 30" | bc)" = 1 ]; then
        echo "slow-link: q had no effect within 30 s" >&2
        exit 1
    fi
    sleep 0.02
done
echo "q took effect after $(echo "$(now) - $typed" | bc) s"
