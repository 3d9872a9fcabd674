#!/usr/bin/env bash
# lsan_tracer_crashes_only.sh BUILD_DIR: after a failed `ctest` in BUILD_DIR, exits 0 when every
# failed test's output has LeakSanitizer's own crash ("LeakSanitizer has encountered a fatal
# error", its stop-the-world tracer dying at a process's exit) and 1 otherwise (no failed-test
# list, a test without that crash, or a real leak report "LeakSanitizer: detected memory leaks").
# Prints what it found. Used by scripts/test.sh to re-run only those tests once.
set -euo pipefail
build=${1:?usage: lsan_tracer_crashes_only.sh BUILD_DIR}
failed_list=$build/Testing/Temporary/LastTestsFailed.log
log=$build/Testing/Temporary/LastTest.log
if [ ! -s "$failed_list" ] || [ ! -f "$log" ]; then
  echo "lsan_tracer_crashes_only: no failed-test list in $build/Testing/Temporary" >&2
  exit 1
fi
status=0
while IFS= read -r line; do
  name=${line#*:}  # "174:Suite.Name"
  # The test's section of LastTest.log: from "N/M Test: NAME" to its "end time" line.
  output=$(awk -v name="$name" '
    $0 ~ /^[0-9]+\/[0-9]+ Test: / && substr($0, index($0, "Test: ") + 6) == name { on = 1 }
    on { print }
    on && index($0, "\"" name "\" end time:") == 1 { exit }' "$log")
  if [ -z "$output" ]; then
    echo "lsan_tracer_crashes_only: $name: no output in $log" >&2
    status=1
  elif grep -q "LeakSanitizer: detected memory leaks" <<< "$output"; then
    echo "lsan_tracer_crashes_only: $name: a leak report" >&2
    status=1
  elif grep -q "LeakSanitizer has encountered a fatal error" <<< "$output"; then
    echo "lsan_tracer_crashes_only: $name: LeakSanitizer's tracer crashed (not a finding)"
  else
    echo "lsan_tracer_crashes_only: $name: failed on its own" >&2
    status=1
  fi
done < "$failed_list"
exit $status
