#!/bin/bash
# Time and peak memory per frame of `impactdic correlate` on a long sequence of real 4k frames
# (docs/dic.md "Speed", docs/dic_speed.md "Latest"). The sequence is made of the five frames of
# sand at rest in ../shared/data/real-sand/static (4096x3000 JPEG): IMG_1 as the reference, then
# IMG_2..IMG_5 over and over (copies: `correlate` refuses a link to a frame already in the
# sequence), so that no frame is the reference again and every frame pair is a real pair of the
# camera's. For each N given, correlates the first N + 1 frames with the issue's grid (subset 25,
# step 50, whole image, defaults otherwise) for each binary, alternating, RUNS times, and prints
#   binary | deformed frames | wall median (min) [s] | peak RSS [MB] | reference updates
# and, for two or more N, the marginal wall time per frame between the smallest and the largest N.
# A benchmark, not a test: the times depend on the machine and its load; compare within one run.
#
#   bench/real_sequence.sh [-r RUNS] [-t THREADS] [-d DIR] [-b BINARY]... N1 N2 ...
#   bench/real_sequence.sh -r 3 -b /tmp/old/impactdic -b build/release/src/cli/impactdic 19 39
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
data="${IMPACTDIC_SHARED_DATA:-$here/../../shared/data}/real-sand/static"
runs=3 threads=2 dir=/tmp/impactdic_real_sequence binaries=()
while getopts "r:t:d:b:" opt; do
  case $opt in
    r) runs=$OPTARG ;; t) threads=$OPTARG ;; d) dir=$OPTARG ;; b) binaries+=("$OPTARG") ;;
    *) exit 2 ;;
  esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || { echo "usage: $0 [-r RUNS] [-t THREADS] [-d DIR] [-b BINARY]... N..." >&2; exit 2; }
[[ "$runs" =~ ^[1-9][0-9]*$ ]] || { echo "$0: -r RUNS must be >= 1 (got $runs)" >&2; exit 2; }
for n in "$@"; do
  [[ "$n" =~ ^[1-9][0-9]*$ ]] || { echo "$0: N must be >= 1 (got $n)" >&2; exit 2; }
done
for tool in bc /usr/bin/time; do
  command -v "$tool" > /dev/null || { echo "$0: $tool is needed (Debian packages bc, time)" >&2; exit 1; }
done
[ ${#binaries[@]} -ge 1 ] || binaries=("$here/../build/release/src/cli/impactdic")
for k in 1 2 3 4 5; do
  [ -f "$data/IMG_$k.jpg" ] || { echo "$0: $data/IMG_$k.jpg missing (../shared/data)" >&2; exit 1; }
done
for n in "$@"; do
  rm -rf "$dir/seq$n" && mkdir -p "$dir/seq$n"
  cp "$data/IMG_1.jpg" "$dir/seq$n/f00000.jpg"
  for ((k = 1; k <= n; ++k)); do
    cp "$data/IMG_$(( (k - 1) % 4 + 2 )).jpg" "$dir/seq$n/$(printf 'f%05d.jpg' "$k")"
  done
done
printf '| binary | deformed frames | wall median (min) [s] | peak RSS [MB] | reference updates |\n'
printf '|---|---|---|---|---|\n'
declare -A median
for n in "$@"; do
  for i in "${!binaries[@]}"; do : > "$dir/times_${n}_$i"; done
  for ((r = 0; r < runs; ++r)); do
    for i in "${!binaries[@]}"; do
      b=${binaries[$i]}
      rm -f "$dir/out.h5"
      if ! /usr/bin/time -f '%e %M' -o "$dir/time" "$b" correlate --frames "$dir/seq$n/f*.jpg" \
        --subset 25 --step 50 --threads "$threads" -o "$dir/out.h5" > "$dir/log" 2>&1; then
        echo "$0: $b failed on $n frames:" >&2
        cat "$dir/log" >&2
        exit 1
      fi
      updates=$(grep -o '[0-9]* reference updates' "$dir/log" | head -1 | cut -d' ' -f1)
      echo "$(cat "$dir/time") ${updates:-?}" >> "$dir/times_${n}_$i"
    done
  done
  for i in "${!binaries[@]}"; do
    # The median of the wall times (the mean of the two middle ones for an even count), the
    # least, the largest peak RSS and the update counts seen (one number: the runs agree).
    read -r med mn rss upd < <(sort -n "$dir/times_${n}_$i" | awk '
      { t[NR] = $1; m = ($2 > m ? $2 : m); u[$3] = 1 }
      END {
        med = NR % 2 ? t[(NR + 1) / 2] : (t[NR / 2] + t[NR / 2 + 1]) / 2
        list = ""; for (k in u) list = list (list == "" ? "" : "/") k
        printf "%.3f %s %d %s\n", med, t[1], m / 1024, list
      }')
    median["${n}_$i"]=$med
    printf '| %s | %d | %s (%s) | %d | %s |\n' "${binaries[$i]}" "$n" "$med" "$mn" "$rss" "$upd"
  done
done
if [ $# -ge 2 ]; then
  lo=$1 hi=$1
  for n in "$@"; do
    if [ "$n" -lt "$lo" ]; then lo=$n; fi
    if [ "$n" -gt "$hi" ]; then hi=$n; fi
  done
  if [ "$lo" -lt "$hi" ]; then
    for i in "${!binaries[@]}"; do
      per=$(echo "scale=4; (${median[${hi}_$i]} - ${median[${lo}_$i]}) / ($hi - $lo)" | bc)
      echo "${binaries[$i]}: marginal wall per frame, $lo -> $hi frames: $per s"
    done
  fi
fi
