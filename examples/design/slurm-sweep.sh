#!/usr/bin/env bash
# A sweep too big for one machine, as a Slurm job array: every array task evaluates one shard
# (scpkit sweep reads SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT), then one job merges.
#
#   jobid=$(sbatch --parsable examples/design/slurm-sweep.sh)
#   sbatch --dependency=afterok:$jobid --wrap \
#     "build/cli/scpkit merge sweep-shards/shard-*.csv -o bicep-sweep.csv"
#
#SBATCH --job-name=scpkit-sweep
#SBATCH --array=0-15
#SBATCH --cpus-per-task=2
#SBATCH --time=00:30:00
#SBATCH --output=sweep-shards/%x-%a.log
set -euo pipefail
mkdir -p sweep-shards
build/cli/scpkit sweep examples/design/bicep-sweep.toml \
  --threads "${SLURM_CPUS_PER_TASK:-2}" \
  -o "sweep-shards/shard-${SLURM_ARRAY_TASK_ID}.csv"
