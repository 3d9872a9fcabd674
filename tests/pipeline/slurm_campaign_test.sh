#!/usr/bin/env bash
# The Slurm job array of docs/campaign.md under a real Slurm (ctest campaign_slurm_test, label
# slurm): a one-node cluster on this machine (munged, slurmctld, slurmd; a generated slurm.conf,
# loopback ports, every file in one temporary folder), stopped and removed at the end whatever
# happens. docs/campaign/slurm_array.sh is submitted as written.
#   1. A campaign as a job array plus the merge (--dependency=afterok) equals the same campaign run
#      on one machine: campaign.csv, regression.json and every test's summary.json and
#      summary.csv, except the records that time a run.
#   2. A task cancelled (scancel) after its first complete test: its merge is cancelled with it, the
#      task re-submitted alone resumes (the complete tests untouched) and the campaign completes,
#      equal to the one-machine run.
#   3. A task whose test fails: the others' results stand, the merge runs and reports the failure.
#   4. A task over its time limit: killed by Slurm, its complete tests kept.
# Slurm, munge or a daemon that does not start is a failure naming the cause (never a skip).
#
#   slurm_campaign_test.sh IMPACTDIC_BINARY SOURCE_DIR
# Environment: IMPACTDIC_SLURM_TIMEOUT_S (default 480) bounds every wait together;
# IMPACTDIC_SLURM_KEEP=1 keeps the temporary folder; IMPACTDIC_SLURM_CAMPAIGN=FILE and
# IMPACTDIC_SLURM_TASKS=N run part 1 alone on that campaign (the measurement of docs/campaign.md).
set -euo pipefail

usage="usage: slurm_campaign_test.sh IMPACTDIC_BINARY SOURCE_DIR"
impactdic=$(realpath "${1:?$usage}")
source_dir=$(realpath "${2:?$usage}")
array_script=$source_dir/docs/campaign/slurm_array.sh
timeout_s=${IMPACTDIC_SLURM_TIMEOUT_S:-480}
start_s=$SECONDS

log() { echo "slurm test [$((SECONDS - start_s)) s]: $*"; }
fail() {
  echo "slurm test: FAILED: $*" >&2
  exit 1
}

for tool in munged munge slurmctld slurmd sbatch squeue scontrol scancel python3; do
  command -v "$tool" > /dev/null ||
    fail "'$tool' is not installed: the Debian packages slurm-wlm and munge (scripts/install_deps.sh)"
done
[ -x "$impactdic" ] || fail "$impactdic is not an executable"
[ -f "$array_script" ] || fail "$array_script is missing"

# ---- The cluster ----------------------------------------------------------------------------
work=$(mktemp -d /tmp/impactdic-slurm.XXXXXX)
chmod 755 "$work"  # munged wants its socket's folders searchable by all, writable by the owner only.
state=$work/state
mkdir -p "$state/munge" "$state/ctld" "$state/spool" "$work/jobs"
export SLURM_CONF=$state/slurm.conf
# Every process of this cluster (daemons, job steps, jobs) carries this variable: the cleanup
# finds by it whatever the daemons left behind, and nothing else.
marker="IMPACTDIC_SLURM_TEST=$work"
daemon_pids=()

# The process ids whose environment holds $marker (not this shell's: it does not hold it).
marked_pids() {
  python3 - "$marker" << 'EOF'
import os, sys
marker = sys.argv[1].encode()
for pid in filter(str.isdigit, os.listdir("/proc")):
    try:
        with open(f"/proc/{pid}/environ", "rb") as f:
            if marker in f.read().split(b"\0"):
                print(pid)
    except OSError:
        pass
EOF
}

cleanup() {
  local code=$?
  trap - EXIT INT TERM
  set +e
  # Only this cluster's jobs ($SLURM_CONF); bounded: the Slurm commands retry for minutes when
  # slurmctld is gone.
  if [ -n "${slurm_up:-}" ] && kill -0 "$ctld_pid" 2> /dev/null; then
    timeout 10 scancel --quiet --full --user=root 2> /dev/null
    for _ in $(seq 20); do
      [ -z "$(timeout 5 squeue -h -o %i 2> /dev/null)" ] && break
      sleep 0.5
    done
  fi
  for pid in "${daemon_pids[@]}"; do kill "$pid" 2> /dev/null; done
  for pid in "${daemon_pids[@]}"; do wait "$pid" 2> /dev/null; done
  local left
  left=$(marked_pids)
  if [ -n "$left" ]; then
    echo "slurm test: killing processes left by the cluster: $left" >&2
    # shellcheck disable=SC2086
    kill -9 $left 2> /dev/null
  fi
  if [ "$code" -ne 0 ]; then
    for f in "$state"/*.log "$work"/jobs/*.log; do
      [ -f "$f" ] || continue
      echo "---- last lines of $f" >&2
      tail -n 15 "$f" >&2
    done
  fi
  if [ "${IMPACTDIC_SLURM_KEEP:-0}" = 1 ]; then
    echo "slurm test: kept $work" >&2
  else
    rm -rf "$work"
  fi
  exit "$code"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# Two free loopback ports (slurmctld's, slurmd's).
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
host=$(hostname -s)
# This machine's CPUs, memory and layout as slurmd detects them, under the name `host`.
node=$(slurmd -C | head -n 1)
[[ $node == NodeName=*\ CPUs=* ]] || fail "slurmd -C did not describe this node: $node"
node=${node#NodeName=* }

cat > "$SLURM_CONF" << EOF
# A one-node cluster for tests/pipeline/slurm_campaign_test.sh: loopback only, root daemons.
ClusterName=impactdic-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$state/munge/munge.socket
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=256
ReturnToService=2
KillWait=5
MinJobAge=3600
NodeName=$host NodeAddr=127.0.0.1 $node State=UNKNOWN
# Up to 4 jobs share a core (the OS divides it): the cases below run at the same time.
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE OverSubscribe=FORCE:4 State=UP
EOF

head -c 1024 /dev/urandom > "$state/munge/munge.key"
chmod 400 "$state/munge/munge.key"
env "$marker" munged --foreground --socket="$state/munge/munge.socket" \
  --key-file="$state/munge/munge.key" --pid-file="$state/munge/munged.pid" \
  --seed-file="$state/munge/munged.seed" --log-file="$state/munged.log" \
  > "$state/munged.out.log" 2>&1 &
daemon_pids+=($!)
for _ in $(seq 50); do
  [ -S "$state/munge/munge.socket" ] && break
  sleep 0.1
done
munge -S "$state/munge/munge.socket" -n < /dev/null | unmunge -S "$state/munge/munge.socket" \
  > /dev/null 2>&1 || fail "munged did not start: $(tail -n 3 "$state/munged.out.log")"

env "$marker" slurmctld -D -i > "$state/slurmctld.out.log" 2>&1 &
ctld_pid=$!
daemon_pids+=("$ctld_pid")
env "$marker" slurmd -D > "$state/slurmd.out.log" 2>&1 &
daemon_pids+=($!)
slurm_up=1
for _ in $(seq 60); do
  [ "$(sinfo -h -o %t 2> /dev/null)" = idle ] && break
  sleep 0.5
done
[ "$(sinfo -h -o %t 2> /dev/null)" = idle ] ||
  fail "the one-node cluster did not come up (node state: '$(sinfo -h -o %t 2>&1)');" \
    "slurmctld: $(grep -i -m 3 error "$state/slurmctld.log" 2> /dev/null)" \
    "slurmd: $(grep -i -m 3 -v pmix "$state/slurmd.log" 2> /dev/null | grep -i -m 3 error)"
log "cluster up: $host, slurmctld on 127.0.0.1:$ctld_port, slurmd on :$slurmd_port"

# ---- Jobs -----------------------------------------------------------------------------------
deadline=$((start_s + timeout_s))
jobs_dir=$work/jobs
bin_dir=$(dirname "$impactdic")

# sbatch from the jobs folder (the tasks' logs land there), impactdic on the PATH; prints the id.
submit() {
  (cd "$jobs_dir" && env "$marker" PATH="$bin_dir:$PATH" sbatch --parsable "$@") ||
    fail "sbatch $* was refused"
}

# Waits until none of the jobs (ids or id_task, comma-separated) is pending or running.
wait_jobs() {
  local queued
  while true; do
    queued=$(timeout 30 squeue -h -r -j "$1" -t PD,CF,R,CG,S -o %i) ||
      fail "squeue does not answer while waiting for $1: slurmctld died? $(tail -n 3 "$state/slurmctld.log")"
    [ -z "$queued" ] && return 0
    ((SECONDS < deadline)) ||
      fail "jobs ${queued//$'\n'/ } still queued or running after ${timeout_s} s" \
        "(IMPACTDIC_SLURM_TIMEOUT_S): $(squeue -r -j "$1" 2>&1)"
    sleep 1
  done
}

# expect_state JOB STATE: every task of JOB (an id or id_task) ended in STATE.
expect_state() {
  local states
  states=$(squeue -h -r -t all -j "$1" -o %T | sort -u | paste -sd ' ')
  [ "$states" = "$2" ] || fail "job $1 ended $states, expected $2: $(squeue -r -t all -j "$1" -o '%i %T %r' 2>&1)"
}

fingerprint() { (cd "$1" && find . -type f -printf '%p %i %s %T@\n' | sort); }

# complete_tests DIR: the test folders of a campaign output folder that are complete (their row
# and the generation marker in place), one name a line.
complete_tests() {
  local d
  for d in "$1"/*/; do
    [ -f "$d/campaign_row.csv" ] && [ -f "$d/.impactdic-output" ] && basename "$d"
  done
  return 0
}

# compare_campaigns ONE MERGED SHARDS...: ONE's campaign.csv, regression.json and each test's
# results/summary.json and summary.csv equal MERGED's and those of the test in its shard, except
# the columns that time a run (wall_time_s, dic_subsets_per_s; the run's timing.json is not
# compared).
compare_campaigns() {
  python3 - "$@" << 'EOF_PY'
import csv, json, os, sys

one, merged, shards = sys.argv[1], sys.argv[2], sys.argv[3:]
TIMING_COLUMNS = {"wall_time_s", "dic_subsets_per_s"}
problems = []

def table(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    keep = [i for i, name in enumerate(rows[0]) if name not in TIMING_COLUMNS]
    return [[r[i] for i in keep] for r in rows]

def same(what, a, b):
    if a != b:
        problems.append(f"{what} differs")

a, b = table(f"{one}/campaign.csv"), table(f"{merged}/campaign.csv")
if len(a) < 2:
    problems.append(f"{one}/campaign.csv has no tests")
same("campaign.csv (without the timing columns)", a, b)
for r1, r2 in zip(a, b):
    if r1 != r2:
        problems.append("  one machine: " + ",".join(r1) + "\n  merged:      " + ",".join(r2))
with open(f"{one}/regression.json") as f1, open(f"{merged}/regression.json") as f2:
    same("regression.json", json.load(f1), json.load(f2))

names = [r[0] for r in a[1:]]
for name in names:
    holders = [s for s in shards if os.path.isdir(f"{s}/{name}")]
    if len(holders) != 1:
        problems.append(f"test {name}: in {len(holders)} shard folders")
        continue
    for summary in ("summary.json", "summary.csv"):
        p1, p2 = f"{one}/{name}/results/{summary}", f"{holders[0]}/{name}/results/{summary}"
        if not os.path.isfile(p1) or not os.path.isfile(p2):
            problems.append(f"test {name}: {summary} missing")
        elif summary.endswith(".json"):
            with open(p1) as f1, open(p2) as f2:  # No timing in it (they are in timing.json).
                same(f"test {name}: {summary}", json.load(f1), json.load(f2))
        else:
            same(f"test {name}: {summary}", table(p1), table(p2))
if problems:
    print("\n".join(problems))
    sys.exit(1)
print(f"{len(names)} tests equal")
EOF_PY
}

# A synthesised campaign of tiny tests (docs/campaign.md; 12 frames each, the sensor record
# running 50 ms on): MATRIX is its synthesise keys.
write_campaign() {
  cat > "$jobs_dir/$1" << EOF_YAML
synthesise:
$2
  added_mass_noise: 0.05
  seed: 1
  spec:
    frames:
      count: ${3:-12}
    sensor:
      tail_s: 0.05
outputs:
  animation: false
  figures: false
EOF_YAML
}

if [ -n "${IMPACTDIC_SLURM_CAMPAIGN:-}" ]; then
  campaign=$(realpath "$IMPACTDIC_SLURM_CAMPAIGN")
  tasks=${IMPACTDIC_SLURM_TASKS:?IMPACTDIC_SLURM_TASKS: the array size for IMPACTDIC_SLURM_CAMPAIGN}
else
  # 8 tests (2 x 2 x 2): enough for the Eq. 4 fit (at least 5), over 4 tasks of 2 tests.
  campaign=small.yaml
  write_campaign "$campaign" "  mass_kg: [7, 13]
  drop_height_m: [0.2, 1.2]
  width_m: [0.10, 0.20]"
  tasks=4
fi
cases=${IMPACTDIC_SLURM_CAMPAIGN:+main}
cases=${cases:-all}

# Case 4 first (its time limit, 1 min, is the longest wait): 64 tests at 1 CPU, far more than a
# minute of work on any machine; Slurm checks time limits every 30 s, so the kill comes 60-90 s
# after the start.
if [ "$cases" = all ]; then
  write_campaign long.yaml "  mass_kg: [7, 9, 11, 13]
  drop_height_m: [0.2, 0.5, 0.8, 1.2]
  width_m: [0.10, 0.13, 0.16, 0.20]" 0
  limited=$(submit --array=1 --time=1 --cpus-per-task=1 "$array_script" long.yaml limited 1)
  log "case 4: task $limited (time limit 1 min) submitted"
fi

# Case 1: the campaign as a job array and its merge, as docs/campaign.md submits them.
array=$(submit --array=1-"$tasks" "$array_script" "$campaign" results "$tasks")
merge=$(submit --dependency=afterok:"$array" --kill-on-invalid-dep=yes --job-name=merge \
  --output=merge-%j.log --wrap "impactdic campaign --merge results/shard-*-of-$tasks -o results/merged")
log "case 1: array $array ($tasks tasks) and merge $merge submitted"

if [ "$cases" = all ]; then
  # Case 2: the same campaign in 2 tasks, task 1 to be cancelled after its first complete test.
  cut=$(submit --array=1-2 "$array_script" "$campaign" cut 2)
  cut_merge=$(submit --dependency=afterok:"$cut" --kill-on-invalid-dep=yes --job-name=merge \
    --output=merge-%j.log --wrap "impactdic campaign --merge cut/shard-*-of-2 -o cut/merged")
  log "case 2: array $cut (2 tasks) and merge $cut_merge submitted"

  # Case 3: test 1 a scene whose accelerometer record is empty (its run fails after the scene
  # loaded), tests 2 and 3 synthesised; one test per task.
  cat > "$jobs_dir/bad_spec.yaml" << EOF_YAML
preset: tiny
frames:
  count: 12
EOF_YAML
  (cd "$jobs_dir" && "$impactdic" -q synth bad_spec.yaml -o bad > synth.log 2>&1) ||
    fail "impactdic synth of the failing case's scene: $(tail -n 5 "$jobs_dir/synth.log")"
  echo "time_s,accel_g,exposure" > "$jobs_dir/bad/sensor.csv"
  write_campaign failing.yaml "  mass_kg: [10]
  drop_height_m: [0.7]
  width_m: [0.10, 0.20]"
  sed -i '1i scenes: [bad/scene.yaml]' "$jobs_dir/failing.yaml"
  failing=$(submit --array=1-3 "$array_script" failing.yaml failing 3)
  failing_merge=$(submit --dependency=afterok:"$failing" --kill-on-invalid-dep=yes \
    --job-name=merge --output=merge-%j.log \
    --wrap "impactdic campaign --merge failing/shard-*-of-3 -o failing/merged")
  log "case 3: array $failing (3 tasks) and merge $failing_merge submitted"
fi

# The same campaign on one machine, meanwhile.
one_start=$SECONDS
(cd "$jobs_dir" && "$impactdic" campaign "$campaign" -o one --threads 2 > one.log 2>&1) &
one_pid=$!

if [ "$cases" = all ]; then
  # Case 2: cancel task 1 as soon as one of its tests is complete.
  while [ -z "$(complete_tests "$jobs_dir/cut/shard-1-of-2" 2> /dev/null)" ]; do
    ((SECONDS < deadline)) || fail "case 2: task ${cut}_1 completed no test in time"
    [ -n "$(squeue -h -j "${cut}_1" -t PD,CF,R,CG -o %i)" ] ||
      fail "case 2: task ${cut}_1 ended before it could be cancelled"
    sleep 0.2
  done
  scancel "${cut}_1"
  wait_jobs "${cut}_1"
  expect_state "${cut}_1" CANCELLED
  kept=$(complete_tests "$jobs_dir/cut/shard-1-of-2")
  log "case 2: task ${cut}_1 cancelled with $(wc -l <<< "$kept") complete tests: ${kept//$'\n'/ }"
  [ ! -e "$jobs_dir/cut/shard-1-of-2/campaign.csv" ] ||
    fail "case 2: task ${cut}_1 had finished before the scancel: nothing was cut off"
  before=$(for t in $kept; do fingerprint "$jobs_dir/cut/shard-1-of-2/$t"; done)
  wait_jobs "$cut_merge"
  expect_state "$cut_merge" CANCELLED  # afterok on a cancelled task: never satisfied.
  [ ! -e "$jobs_dir/cut/merged" ] || fail "case 2: the merge ran although task 1 was cancelled"
  # Re-submitted alone (the shard count is the script's argument, not the array's size), and the
  # merge again, after it and task 2.
  resumed=$(submit --array=1 "$array_script" "$campaign" cut 2)
  cut_merge=$(submit --dependency=afterok:"$resumed":"${cut}_2" --kill-on-invalid-dep=yes \
    --job-name=merge --output=merge-%j.log \
    --wrap "impactdic campaign --merge cut/shard-*-of-2 -o cut/merged")
  log "case 2: task 1 re-submitted ($resumed), merge $cut_merge"
fi

# Case 1.
wait_jobs "$array,$merge"
expect_state "$array" COMPLETED
expect_state "$merge" COMPLETED
log "case 1: array and merge done"
wait "$one_pid" || fail "the campaign on one machine failed: $(tail -n 5 "$jobs_dir/one.log")"
log "the same campaign on one machine: $((SECONDS - one_start)) s"
shards=()
for i in $(seq "$tasks"); do shards+=("$jobs_dir/results/shard-$i-of-$tasks"); done
out=$(compare_campaigns "$jobs_dir/one" "$jobs_dir/results/merged" "${shards[@]}") ||
  fail "case 1: the merged campaign differs from the one-machine run:"$'\n'"$out"
log "case 1: merged = one machine: $out"
grep -q "tests to run (0 resumed, shard 2/$tasks)" "$jobs_dir/impactdic-campaign-${array}_2.log" ||
  fail "case 1: task 2's log does not say it ran shard 2/$tasks"

if [ "$cases" = all ]; then
  # Case 2: the re-submitted task resumed the kept tests, untouched, and completed the campaign.
  wait_jobs "$resumed,$cut_merge"
  expect_state "$resumed" COMPLETED
  expect_state "$cut_merge" COMPLETED
  n_kept=$(wc -l <<< "$kept")
  grep -q "($n_kept resumed" "$jobs_dir/impactdic-campaign-${resumed}_1.log" ||
    fail "case 2: the re-submitted task did not resume the $n_kept complete tests:" \
      "$(grep -m 3 -i 'campaign:' "$jobs_dir/impactdic-campaign-${resumed}_1.log")"
  after=$(for t in $kept; do fingerprint "$jobs_dir/cut/shard-1-of-2/$t"; done)
  [ "$before" = "$after" ] || fail "case 2: the resumed task rewrote its complete tests"
  out=$(compare_campaigns "$jobs_dir/one" "$jobs_dir/cut/merged" "$jobs_dir"/cut/shard-{1,2}-of-2) ||
    fail "case 2: the campaign completed after the cancel differs from the one-machine run:"$'\n'"$out"
  log "case 2: resumed $n_kept tests; merged = one machine: $out"

  # Case 3: the failing test's task ends normally (its failure is a row), the others' results
  # stand, the merge runs and reports the failure.
  wait_jobs "$failing,$failing_merge"
  expect_state "$failing" COMPLETED
  expect_state "$failing_merge" COMPLETED
  merge_log=$jobs_dir/merge-$failing_merge.log
  grep -q "1 failed" "$merge_log" || fail "case 3: the merge does not report 1 failed test: $(head -n 3 "$merge_log")"
  grep -q "error: .*sensor.csv" "$merge_log" ||
    fail "case 3: the merge does not report the failed test's error: $(cat "$merge_log")"
  statuses=$(python3 -c '
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print(" ".join(r["status"] for r in rows))' "$jobs_dir/failing/merged/campaign.csv")
  [ "$statuses" = "failed ok ok" ] || fail "case 3: merged statuses '$statuses', expected 'failed ok ok'"
  for i in 2 3; do
    [ "$(complete_tests "$jobs_dir/failing/shard-$i-of-3" | wc -l)" = 1 ] ||
      fail "case 3: task $i's test is not complete"
  done
  log "case 3: test 1 failed, tests 2 and 3 ok, the merge reports the failure"

  # Case 4: killed at its time limit (SIGTERM, then SIGKILL after KillWait), its complete tests
  # kept, no temporaries, no campaign.csv.
  wait_jobs "$limited"
  expect_state "$limited" TIMEOUT
  shard=$jobs_dir/limited/shard-1-of-1
  n_done=$(complete_tests "$shard" | wc -l)
  ((n_done >= 1 && n_done < 64)) || fail "case 4: $n_done of 64 tests complete at the time limit"
  [ ! -e "$shard/campaign.csv" ] || fail "case 4: the task finished before its time limit"
  temporaries=$(find "$jobs_dir/limited" -name '.*.tmp-*' -o -name '.*.bak-*')
  [ -z "$temporaries" ] || fail "case 4: temporaries left by the killed task: $temporaries"
  for t in $(complete_tests "$shard"); do
    grep -q ",ok," "$shard/$t/campaign_row.csv" || fail "case 4: kept test $t is not ok"
  done
  log "case 4: killed at its time limit with $n_done complete tests kept"
fi
log "passed"
