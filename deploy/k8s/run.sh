#!/usr/bin/env bash
# Start the shards, wait for all of them, then merge.
#   deploy/k8s/run.sh [TIMEOUT]       (kubectl configured for the cluster; default 2h)
set -euo pipefail
here=$(dirname "$0")
timeout=${1:-2h}
kubectl delete job cablab-shards cablab-merge --ignore-not-found
kubectl apply -f "$here/shards-job.yaml"
kubectl wait --for=condition=complete --timeout="$timeout" job/cablab-shards
kubectl apply -f "$here/merge-job.yaml"
kubectl wait --for=condition=complete --timeout=30m job/cablab-merge
kubectl logs job/cablab-merge
