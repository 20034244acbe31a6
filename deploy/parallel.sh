#!/usr/bin/env bash
# A campaign in N shards with GNU parallel, then the merge.
#
#   deploy/parallel.sh [PIPELINE] [N] [JOBS_PER_SHARD]
#
# Runs from the project folder. Shards run N at a time on this machine by default; to spread them
# over machines that mount the same project folder, pass parallel's own options, e.g.
#   PARALLEL_OPTS="-S node1,node2 --workdir /shared/project" deploy/parallel.sh pipelines/x.toml 8 4
# CABLAB names the executable (default: cablab on PATH); RUN_OPTS adds options to every shard's
# run (e.g. RUN_OPTS=--no-diagnosis).
set -euo pipefail
PIPELINE=${1:-pipelines/demo.toml}
N=${2:-4}
JOBS=${3:-1}
CABLAB=${CABLAB:-cablab}
# Exit 1 = the shard was written but one of its tests failed: the merge reports it. Anything else
# (2 = bad input, a crash) stops here with the shard named in parallel's --halt message.
# shellcheck disable=SC2086
seq 1 "$N" | parallel ${PARALLEL_OPTS:-} --jobs "$N" --halt soon,fail=1 --line-buffer --tag \
  "$CABLAB run '$PIPELINE' --shard {}/$N --jobs $JOBS --quiet ${RUN_OPTS:-} || [ \$? -eq 1 ]"
"$CABLAB" merge "$PIPELINE"
