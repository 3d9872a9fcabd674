#!/bin/bash
# Peak memory and time per frame of `impactdic run` against the number of frames (issue 13,
# item 5; docs/architecture.md "Memory"). Synthesises one impact sequence of COUNT frames of
# WIDTHxHEIGHT (8-bit PNG, ideal lens), then runs the whole pipeline on its first N frames
# (dic.last_frame = N + 1) for each N given, as a child of /usr/bin/time, and prints one table
# row per N (analysed frames: from the last one before the impact, found from the sensor record,
# to frame N + 1):
#   analysed frames | peak RSS [MB] | wall [s] | wall per analysed frame [s] |
#   correlate per correlated frame [s]
# A benchmark, not a test: the times depend on the machine and its load; the memory does not.
#
#   bench/streaming_memory.sh [-b BINARY] [-w WIDTH] [-h HEIGHT] [-d DIR] N1 N2 ...
#   bench/streaming_memory.sh 50 500        # 1920x1440: ~2.8 MB of PNG per frame in DIR
set -euo pipefail
binary="$(dirname "$0")/../build/release/src/cli/impactdic"
width=1920 height=1440 dir=/tmp/impactdic_streaming_bench threads=2
while getopts "b:w:h:d:t:" opt; do
  case $opt in
    b) binary=$OPTARG ;; w) width=$OPTARG ;; h) height=$OPTARG ;; d) dir=$OPTARG ;;
    t) threads=$OPTARG ;; *) exit 2 ;;
  esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || { echo "usage: $0 [-b BINARY] [-w W] [-h H] [-d DIR] [-t THREADS] N..." >&2; exit 2; }
max=0
for n in "$@"; do [ "$n" -gt "$max" ] && max=$n; done
count=$((max + 2))  # 2 frames before the impact.
mkdir -p "$dir"
if [ ! -f "$dir/scene/scene.yaml" ] || [ "$(ls "$dir/scene/frames" | wc -l)" -lt "$count" ]; then
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
echo "| analysed frames | peak RSS [MB] | wall [s] | wall per frame [s] | correlate per frame [s] |"
echo "|---|---|---|---|---|"
for n in "$@"; do
  sed "s/^dic:$/dic:\n  last_frame: $((n + 1))/" "$dir/scene/scene.yaml" > "$dir/scene/n$n.yaml"
  rm -rf "$dir/out$n"
  /usr/bin/time -f "%M %e" -o "$dir/time$n.txt" "$binary" run "$dir/scene/n$n.yaml" \
    -o "$dir/out$n" --threads "$threads" --allow-partial > "$dir/run$n.txt" 2>&1
  read -r rss_kb wall < "$dir/time$n.txt"
  correlate=$(awk '$1 == "correlate" && $3 == "s" {print $2}' "$dir/run$n.txt")
  analysed=$(awk '$1 == "frames" && $3 == "s" {print $4}' "$dir/run$n.txt")  # "frames 0.09 s 46 of 502 ..."
  awk -v n="$analysed" -v r="$rss_kb" -v w="$wall" -v c="$correlate" 'BEGIN {
    printf "| %d | %.0f | %.1f | %.3f | %.3f |\n", n, r / 1024, w, w / n, c / (n - 1) }'
done
