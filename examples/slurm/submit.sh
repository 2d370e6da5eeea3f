#!/usr/bin/env bash
# Queues a split render on a Slurm cluster: an array of N parts, then the
# merge once all of them have succeeded.
#   examples/slurm/submit.sh [N]      (default 8; SCENE, SIZE, SPP, OUTPUT,
#                                      RAYTERM, PARTS_DIR as in the scripts)
set -euo pipefail

N=${1:-8}
here=$(dirname "$0")
array=$(sbatch --parsable --export=ALL --array="1-$N" "$here/render.sbatch")
array=${array%%;*}
merge=$(sbatch --parsable --export=ALL --dependency="afterok:$array" "$here/merge.sbatch")
echo "parts: job $array (array 1-$N); merge: job ${merge%%;*} after them"
