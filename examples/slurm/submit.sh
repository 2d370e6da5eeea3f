#!/usr/bin/env bash
# Queues a split render on a Slurm cluster: an array of N parts, then the
# merge once every part has ended (it names the parts that failed).
#   examples/slurm/submit.sh [N]      (default 8; SCENE, SIZE, SPP, OUTPUT,
#                                      RAYTERM, PARTS_DIR as in the scripts)
# CPUS (default 2) is each task's CPUs; its memory is what
# `rayterm render --dry-run` says the render will take at most, and a
# quarter more.
set -euo pipefail

N=${1:-8}
CPUS=${CPUS:-2}
RAYTERM=${RAYTERM:-rayterm}
export SCENE=${SCENE:-cornell-area} SIZE=${SIZE:-1920x1080} SPP=${SPP:-1024}
# Each task is part K of N, also when one is queued again on its own.
export PARTS=$N
here=$(dirname "$0")
peak=$("$RAYTERM" render "$SCENE" --size "$SIZE" --spp "$SPP" --part "1/$N" \
  --checkpoint estimate.ckpt.exr --dry-run -o estimate.exr |
  sed -n 's/.*peak memory.*(\([0-9]*\) bytes.*/\1/p')
mem=$(( peak * 5 / 4 / 1048576 + 1 ))
array=$(sbatch --parsable --export=ALL --array="1-$N" --cpus-per-task="$CPUS" \
  --mem="${mem}M" "$here/render.sbatch")
array=${array%%;*}
merge=$(sbatch --parsable --export=ALL --dependency="afterany:$array" "$here/merge.sbatch")
echo "parts: job $array (array 1-$N, $CPUS CPUs and ${mem} MB each); merge: job ${merge%%;*} after them"
