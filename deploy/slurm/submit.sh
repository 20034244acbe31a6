#!/usr/bin/env bash
# Submit a campaign as a Slurm array of N shards plus the merge that waits for all of them.
#   deploy/slurm/submit.sh [PIPELINE] [N]        (from the project folder)
set -euo pipefail
PIPELINE=${1:-pipelines/demo.toml}
N=${2:-8}
here=$(dirname "$0")
array=$(sbatch --parsable --array="1-${N}" --export="ALL,PIPELINE=${PIPELINE}" "$here/shard.sbatch")
# afterany: a shard whose tests failed still wrote its results; the merge checks completeness.
sbatch --parsable --dependency="afterany:${array}" --export="ALL,PIPELINE=${PIPELINE}" "$here/merge.sbatch"
