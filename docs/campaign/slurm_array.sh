#!/bin/bash
# A campaign spread over a Slurm job array (docs/campaign.md, "Sharding"): task I of N runs
# shard I/N (tests I, I+N, I+2N, ... of the campaign file, in plan order) into its own folder;
# a last job, started after all tasks succeeded, merges them into one campaign.
#
#   sbatch --array=1-9 docs/campaign/slurm_array.sh docs/campaign/table1_synthetic.yaml results/table1
#   sbatch --dependency=afterok:<ARRAY_JOB_ID> --wrap \
#     "impactdic campaign --merge results/table1/shard-*-of-9 -o results/table1/merged"
#
# A task that is cut off (time limit, preemption) keeps every test it completed: re-submitting the
# same array index resumes it (complete tests are recognised by their scene hash and tool
# version). Every task needs the same impactdic build (its version is compared when resuming and
# recorded in each row).
#SBATCH --job-name=impactdic-campaign
#SBATCH --cpus-per-task=2
#SBATCH --mem-per-cpu=1G
#SBATCH --time=00:30:00
#SBATCH --output=impactdic-campaign-%A_%a.log
set -euo pipefail

campaign_file=${1:?usage: slurm_array.sh CAMPAIGN.yaml OUTPUT_DIR}
output=${2:?usage: slurm_array.sh CAMPAIGN.yaml OUTPUT_DIR}
index=${SLURM_ARRAY_TASK_ID:?run it as a job array: sbatch --array=1-N}
count=${SLURM_ARRAY_TASK_COUNT:?run it as a job array: sbatch --array=1-N}

impactdic campaign "$campaign_file" \
  --shard "${index}/${count}" \
  --threads "${SLURM_CPUS_PER_TASK:-1}" \
  -o "${output}/shard-${index}-of-${count}"
