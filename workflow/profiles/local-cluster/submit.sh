#!/usr/bin/env bash
# A stand-in for a batch scheduler's submit command, for the cluster-generic executor:
# starts the job script as a separate background process and prints its id (the PID).
# Without a status command, Snakemake learns the outcome from the job's marker files.
# Used by tests/test_cluster.py to prove that stages share nothing but files.
set -euo pipefail
jobscript="${@: -1}"
logdir=".snakemake/local-cluster"
mkdir -p "$logdir"
nohup bash "$jobscript" > "$logdir/$(basename "$jobscript").out" 2>&1 &
echo $!
