#!/bin/bash
# Peak memory and time per frame of `impactdic run` and `impactdic correlate` against the number
# of frames (docs/development.md "Memory", docs/dic_input.md "Long
# recordings and camera files"). Synthesises one impact sequence of COUNT frames of WIDTHxHEIGHT
# (8-bit PNG, ideal lens), then for each N given, as a child of /usr/bin/time:
#  - runs the whole pipeline on its first N frames (dic.last_frame = N + 1; analysed frames: from
#    the last one before the impact, found from the sensor record, to frame N + 1), one row of
#      analysed frames | peak RSS [MB] | growth [MB] | results [MB] | bound [MB] | wall [s] |
#      wall per analysed frame [s] | correlate per correlated frame [s]
#  - with -c SUBSET,STEP: correlates frames 0..N (frame 0 the reference) with
#    `correlate --subset SUBSET --step STEP -o DIR/correlateN.h5`, one row of
#      deformed frames | subsets | peak RSS [MB] | growth [MB] | results [MB] | bound [MB] |
#      wall [s] | wall per frame [s]
# growth: the peak above the first N's; results: the results' own size in memory, per subset and
# frame 40 bytes of correlation (u, v, ZNCC, three sigmas, iterations, status) and, for `run`,
# 48 bytes of kinematics (displacement, velocity, acceleration: 6 doubles), 88 in all; bound: what
# the streaming design allows the growth, the results' own size plus 10 %.
# A benchmark, not a test: the times depend on the machine and its load; the memory does not.
#
#   bench/streaming_memory.sh [-b BINARY] [-w WIDTH] [-h HEIGHT] [-d DIR] [-t THREADS]
#                             [-g RUN_STEP] [-a] [-c SUBSET,STEP] [-n] N1 N2 ...
#   bench/streaming_memory.sh 50 500        # 1920x1440: ~2.8 MB of PNG per frame in DIR
#   bench/streaming_memory.sh -w 4096 -h 3000 -d /tmp/bench4k -g 50 -c 25,50 20 80 500
#     (4096x3000: ~9 MB of PNG per frame; -g 50: run with dic.step 50 instead of the scene's 20,
#     -c 25,50: the issue's real-sand grid; -n: correlate only, no run; -a: the run without the
#     animation, whose H.264 encoder holds a lookahead of canvas frames, docs/architecture.md)
set -euo pipefail
binary="$(dirname "$0")/../build/release/src/cli/impactdic"
width=1920 height=1440 dir=/tmp/impactdic_streaming_bench threads=2 run_step="" grid="" run=1 animation=true
while getopts "b:w:h:d:t:g:c:na" opt; do
  case $opt in
    b) binary=$OPTARG ;; w) width=$OPTARG ;; h) height=$OPTARG ;; d) dir=$OPTARG ;;
    t) threads=$OPTARG ;; g) run_step=$OPTARG ;; c) grid=$OPTARG ;; n) run=0 ;;
    a) animation=false ;; *) exit 2 ;;
  esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || {
  echo "usage: $0 [-b BINARY] [-w W] [-h H] [-d DIR] [-t THREADS] [-g RUN_STEP] [-a] [-c SUBSET,STEP] [-n] N..." >&2
  exit 2
}
max=0
for n in "$@"; do [ "$n" -gt "$max" ] && max=$n; done
count=$((max + 2))  # 2 frames before the impact.
mkdir -p "$dir"
# -n (correlate only) needs the frames alone, e.g. frames of any other source in DIR/scene/frames.
if { [ "$run" = 1 ] && [ ! -f "$dir/scene/scene.yaml" ]; } ||
  [ "$(ls "$dir/scene/frames" 2>/dev/null | wc -l)" -lt "$((run == 1 ? count : max + 1))" ]; then
  cat > "$dir/spec.yaml" <<EOF
preset: small
name: streaming_bench
camera: {lens: ideal, width: $width, height: $height, mm_per_px: 0.25}
frames: {count: $count, before_impact: 2, supersampling: 1}
sensor: {tail_s: 0.05}
calibration: {render: false}
EOF
  "$binary" -q synth "$dir/spec.yaml" -o "$dir/scene" > /dev/null
fi
# One table row: the peak, its growth above the first row's, the results and the bound.
# Arguments: first columns, peak kB, subsets x frames of the results, bytes per subset and frame,
# then the last columns.
first_rss_kb=""
row() {
  local head=$1 rss_kb=$2 results=$3 bytes=$4 tail=$5
  [ -n "$first_rss_kb" ] || first_rss_kb=$rss_kb
  awk -v h="$head" -v r="$rss_kb" -v f="$first_rss_kb" -v n="$results" -v b="$bytes" -v t="$tail" \
    'BEGIN { printf "| %s | %.0f | %.0f | %.1f | %.1f | %s |\n", h, r / 1024, (r - f) / 1024,
      n * b / 1e6, 1.1 * n * b / 1e6, t }'
}
if [ "$run" = 1 ]; then
  echo "| analysed frames | peak RSS [MB] | growth [MB] | results [MB] | bound [MB] | wall [s] | wall per frame [s] | correlate per frame [s] |"
  echo "|---|---|---|---|---|---|---|---|"
  for n in "$@"; do
    step_edit=""  # The scene's dic.step is its only `step:` line.
    [ -z "$run_step" ] || step_edit="s/^  step: [0-9]*$/  step: $run_step/"
    sed -e "s/^dic:$/dic:\n  last_frame: $((n + 1))/" -e "$step_edit" \
      -e "s/^  animation: true$/  animation: $animation/" "$dir/scene/scene.yaml" > "$dir/scene/n$n.yaml"
    rm -rf "$dir/out$n"
    /usr/bin/time -f "%M %e" -o "$dir/time$n.txt" "$binary" run "$dir/scene/n$n.yaml" \
      -o "$dir/out$n" --threads "$threads" --allow-partial > "$dir/run$n.txt" 2>&1
    read -r rss_kb wall < "$dir/time$n.txt"
    correlate=$(awk '$1 == "correlate" && $3 == "s" {print $2}' "$dir/run$n.txt")
    analysed=$(awk '$1 == "frames" && $3 == "s" {print $4}' "$dir/run$n.txt")  # "frames 0.09 s 46 of 502 ..."
    results=$(awk '$1 == "correlate" && $3 == "s" {print $4 * $7}' "$dir/run$n.txt")  # "correlate 3.6 s 180 subsets x 48 frames"
    row "$analysed" "$rss_kb" "$results" 88 "$(awk -v n="$analysed" -v w="$wall" -v c="$correlate" \
      'BEGIN { printf "%.1f | %.3f | %.3f", w, w / n, c / (n - 1) }')"
  done
fi
if [ -n "$grid" ]; then
  first_rss_kb=""
  echo
  echo "| deformed frames | subsets | peak RSS [MB] | growth [MB] | results [MB] | bound [MB] | wall [s] | wall per frame [s] |"
  echo "|---|---|---|---|---|---|---|---|"
  mapfile -t frames < <(ls "$dir/scene/frames"/frame_*.png | sort)
  for n in "$@"; do
    rm -f "$dir/correlate$n.h5"
    /usr/bin/time -f "%M %e" -o "$dir/ctime$n.txt" "$binary" correlate --reference "${frames[0]}" \
      --deformed "${frames[@]:1:n}" --subset "${grid%,*}" --step "${grid#*,}" \
      --threads "$threads" -o "$dir/correlate$n.h5" > "$dir/correlate$n.txt" 2>&1
    read -r rss_kb wall < "$dir/ctime$n.txt"
    subsets=$(grep -o '[0-9]* subsets x' "$dir/correlate$n.txt" | head -1 | awk '{print $1}')
    row "$n | $subsets" "$rss_kb" "$((subsets * n))" 40 \
      "$(awk -v n="$n" -v w="$wall" 'BEGIN { printf "%.1f | %.3f", w, w / n }')"
  done
fi
