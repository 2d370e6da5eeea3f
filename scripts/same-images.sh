#!/usr/bin/env bash
# Renders every built-in scene, each debug view and the inspector's output
# with two rayterm binaries and says whether every file is byte-identical:
# the check a change that should not change behaviour must pass.
#
#   scripts/same-images.sh OLD_BINARY NEW_BINARY [WORK_DIR]
#
# Prints one line per differing file and exits 1 if any differ.
set -euo pipefail
old=${1:?usage: same-images.sh OLD_BINARY NEW_BINARY [WORK_DIR]}
new=${2:?usage: same-images.sh OLD_BINARY NEW_BINARY [WORK_DIR]}
work=${3:-$(mktemp -d)}
mkdir -p "$work/old" "$work/new" "$work/bin-old" "$work/bin-new"
# The same file name for both, since help texts print it.
cp "$old" "$work/bin-old/rayterm" && old=$work/bin-old/rayterm
cp "$new" "$work/bin-new/rayterm" && new=$work/bin-new/rayterm

# name|arguments (the output file name is NAME with its extension)
cases=(
  "cornell.png|render cornell --size 96x96 --spp 4"
  "cornell.exr|render cornell --size 96x96 --spp 4"
  "cornell-area.exr|render cornell-area --size 96x96 --spp 8"
  "cornell-area-adaptive.exr|render cornell-area --size 64x64 --target-error 0.05"
  "cube-textured.png|render cube-textured --size 96x72 --spp 4"
  "mirrors.exr|render mirrors --size 96x72 --spp 4"
  "teapot.png|render teapot:8 --size 96x72 --spp 2"
  "env.exr|render env --size 96x54 --spp 4"
  "env-sky.png|render env --env 0.4,0.6,1.0 --size 96x54 --spp 2"
  "cornell-path.exr|render cornell --integrator path --size 64x64 --spp 8"
  "cornell-area-path.exr|render cornell-area --integrator path --max-depth 4 --size 64x64 --spp 8"
  "mirrors-path.exr|render mirrors --integrator path --size 64x48 --spp 8"
  "env-path.exr|render env --integrator path --size 64x36 --spp 8"
  "cornell-noshadow.png|render cornell --size 96x96 --spp 2 --no shadows --no reflections"
  "cornell-median.png|render cornell --size 96x96 --spp 2 --builder median --threads 1"
  "cornell.hdr|render cornell --size 64x64 --spp 2"
  "bvh-level.png|render teapot --size 96x72 --debug bvh-level:4"
  "bvh-leaves.png|render cornell --size 96x96 --debug bvh-leaves"
  "bvh-heat.png|render teapot:16 --size 96x72 --debug bvh-heat"
  "bvh-heat-tests.png|render teapot:16 --size 96x72 --debug bvh-heat:tests"
  "traversal.png|render cornell --size 200x200 --debug ray:100,125:traversal"
  "traversal-shadow.png|render cornell --size 200x200 --debug ray:100,125:traversal:1"
  "normals.png|render mirrors --size 160x120 --debug ray:80,83:normals"
  "texel.png|render cube-textured --size 160x120 --debug ray:80,50:texture"
  "environment.png|render env --size 160x90 --debug ray:83,48:environment"
  "samples.png|render cornell-area --size 100x100 --spp 16 --debug samples:50,83"
  "bloom.png|render cornell --size 96x96 --spp 2 --debug bloom"
  "aov.exr|render cornell --size 48x48 --spp 2 --aov albedo,normal,depth"
)
texts=(
  "inspect.txt|inspect cornell --pixel 400,300"
  "inspect-area.txt|inspect cornell-area --pixel 150,600 --expand"
  "inspect.json|inspect mirrors --pixel 400,300 --json"
  "inspect-path.txt|inspect cornell --integrator path --pixel 400,300"
  "explain.txt|render cornell --explain --dry-run -o $work/unused.png"
  "help.txt|--help"
  "help-tui.txt|tui --help"
  "help-render.txt|render --help"
  "help-inspect.txt|inspect --help"
  "help-converge.txt|converge --help"
  "help-bench.txt|bench --help"
  "help-bench-rays.txt|bench rays --help"
  "help-stability.txt|stability --help"
  "help-merge.txt|merge --help"
)

status=0
run() { # BINARY DIR NAME ARGS...
  local bin=$1 dir=$2 name=$3
  shift 3
  # shellcheck disable=SC2086
  "$bin" $* -o "$dir/$name" --progress none >/dev/null 2>"$dir/$name.err" ||
    { echo "FAILED: $bin $* (see $dir/$name.err)"; status=1; }
}
for c in "${cases[@]}"; do
  name=${c%%|*} args=${c#*|}
  run "$old" "$work/old" "$name" $args
  run "$new" "$work/new" "$name" $args
done
for c in "${texts[@]}"; do
  name=${c%%|*} args=${c#*|}
  "$old" $args >"$work/old/$name" 2>/dev/null || true
  "$new" $args >"$work/new/$name" 2>/dev/null || true
done

same=0
for f in "$work"/old/*; do
  [ -f "$f" ] || continue
  b=$(basename "$f")
  case $b in *.err) continue ;; esac
  if cmp -s "$f" "$work/new/$b"; then
    same=$((same + 1))
  else
    echo "DIFFERS: $b"
    status=1
  fi
done
echo "$same files byte-identical (in $work)"
exit $status
