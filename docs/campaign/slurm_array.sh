#!/bin/bash
# A campaign spread over a Slurm job array (docs/campaign.md, "A Slurm job array"): task I runs
# shard I/N (tests I, I+N, I+2N, ... of the campaign file, in plan order) into its own folder
# OUTPUT_DIR/shard-I-of-N; a last job, started after every task succeeded, merges them.
#
#   job=$(sbatch --parsable --array=1-9 docs/campaign/slurm_array.sh \
#           docs/campaign/table1_synthetic.yaml results/table1 9)
#   sbatch --dependency=afterok:$job --kill-on-invalid-dep=yes --wrap \
#     "impactdic campaign --merge results/table1/shard-*-of-9 -o results/table1/merged"
#
# N is an argument, not the array's size: a task that was cut off (time limit, preemption,
# scancel) is re-submitted alone, `sbatch --array=4 docs/campaign/slurm_array.sh ... 9`, and
# resumes: every test it completed is kept (recognised by its scene hash and tool version). Then
# submit the merge again, after the re-submitted task. Every task needs the same impactdic build
# (its version is compared when resuming and recorded in each row).
#SBATCH --job-name=impactdic-campaign
#SBATCH --cpus-per-task=2
#SBATCH --mem-per-cpu=1G
#SBATCH --time=00:30:00
#SBATCH --output=impactdic-campaign-%A_%a.log
set -euo pipefail

usage="usage: sbatch --array=1-N slurm_array.sh CAMPAIGN.yaml OUTPUT_DIR N"
campaign_file=${1:?$usage}
output=${2:?$usage}
count=${3:?$usage}
index=${SLURM_ARRAY_TASK_ID:?run it as a job array: $usage}
if ! [[ $count =~ ^[1-9][0-9]*$ ]] || ((index > count)); then
  echo "slurm_array.sh: array index ${index} and shard count '${count}': expected" \
    "1 <= index <= N (${usage})" >&2
  exit 2
fi

exec impactdic campaign "$campaign_file" \
  --shard "${index}/${count}" \
  --threads "${SLURM_CPUS_PER_TASK:-1}" \
  -o "${output}/shard-${index}-of-${count}"
