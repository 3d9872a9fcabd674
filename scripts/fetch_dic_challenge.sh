#!/usr/bin/env bash
# Downloads and unpacks DIC Challenge 1.0 (2D) Samples 3 and 14 for bench/dic_challenge.py
# (issue 13, items 1-2; docs/dic.md "DIC Challenge 1.0"). The images are never committed.
#
#   scripts/fetch_dic_challenge.sh [DIR]
#   bench/dic_challenge.py [DIR]
#
# DIR (default ${XDG_CACHE_HOME:-~/.cache}/impactdic/dic_challenge) receives Sample3.zip,
# Sample14.zip, their unpacked folders Sample3/ and Sample14/, Sample14_command.csv (the truth of
# Sample 14) and SHA256SUMS.
#
# Sources. The challenge (SEM / iDICs, https://idics.org/challenge/) publishes its 2D 1.0 images
# as a Google Drive folder: https://drive.google.com/drive/folders/1tNUKPJ7UJOm23JhERtkrIy5gSBiwV3Dj
# (sem.org/dic-challenge no longer serves them). Drive file ids of the archives:
#   Sample14.zip  13lG8piOhYXqMdvIFmmmRq9wzodoCAXhX  (as listed in that folder; recorded in the
#                 public repository 9997433-bit/HL3, benchmarks/challenge/manifest.json)
#   Sample3.zip   no id known to this script: it is looked up in the folder's public listing
#                 (best effort: parses the page as gdown does); if that fails, the message says how
#                 to give the link (--sample3-url, or the archive dropped into DIR by hand).
#   Sample14_command.csv  the commanded u of Sample 14 per pixel column for L1, L3, L5 (x, u_L1,
#                 exx_L1, u_L3, exx_L3, u_L5, exx_L5; exx in microstrain), as Sandia's DICe keeps it
#                 in tests/regression/dic_challenge_14_nlvc/command.csv (github.com/dicengine/dice,
#                 pinned to commit 27a780753c561c8518eddd2b675929795a1661d0).
# Override any source with DIC_CHALLENGE_SAMPLE3_URL / DIC_CHALLENGE_SAMPLE14_URL or the options
# --sample3-url / --sample14-url (a Drive "file/d/ID/view" link or any direct URL of the zip).
#
# Verification: no checksums are published with the challenge. The script checks that each
# download is a zip archive (not Drive's HTML interstitial), that it unpacks, and that it holds
# the expected images (Sample 3: the reference and 11 shifted images "Sample3-NNN X.. Y.. ...";
# Sample 14: the reference and at least one "Sample14 L<k> Amp<A>" image). It records the
# SHA-256 of each archive in DIR/SHA256SUMS; a later run with a different archive under the same
# name fails (delete the line to accept the new one).
#
# Exit status: 0 both samples present; 1 a download, check or unpacking failed (the message
# names the URL or file); 2 bad arguments; 3 no source for Sample3.zip (see the message).
set -euo pipefail

FOLDER_URL="https://drive.google.com/drive/folders/1tNUKPJ7UJOm23JhERtkrIy5gSBiwV3Dj"
SAMPLE14_ID="13lG8piOhYXqMdvIFmmmRq9wzodoCAXhX"
TRUTH14_URL="https://raw.githubusercontent.com/dicengine/dice/27a780753c561c8518eddd2b675929795a1661d0/tests/regression/dic_challenge_14_nlvc/command.csv"

dir=""
sample3_url="${DIC_CHALLENGE_SAMPLE3_URL:-}"
sample14_url="${DIC_CHALLENGE_SAMPLE14_URL:-}"
while [ $# -gt 0 ]; do
  case "$1" in
    --sample3-url) sample3_url="${2:?--sample3-url needs a URL}"; shift 2 ;;
    --sample14-url) sample14_url="${2:?--sample14-url needs a URL}"; shift 2 ;;
    -h|--help) sed -n '2,30p' "$0"; exit 0 ;;
    -*) echo "fetch_dic_challenge: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) [ -z "$dir" ] || { echo "fetch_dic_challenge: one DIR only (got '$dir' and '$1')" >&2; exit 2; }
       dir="$1"; shift ;;
  esac
done
dir="${dir:-${XDG_CACHE_HOME:-$HOME/.cache}/impactdic/dic_challenge}"
mkdir -p "$dir"

die() { echo "fetch_dic_challenge: error: $*" >&2; exit 1; }
for tool in curl python3 sha256sum; do
  command -v "$tool" > /dev/null || die "$tool is not installed (scripts/install_deps.sh installs it)"
done

# A Drive share link (".../file/d/ID/..." or "...?id=ID") -> the direct download URL.
direct_url() {
  local url="$1" id=""
  if [[ "$url" =~ drive\.google\.com/file/d/([A-Za-z0-9_-]+) ]]; then id="${BASH_REMATCH[1]}"
  elif [[ "$url" =~ drive\.google\.com/.*[?\&]id=([A-Za-z0-9_-]+) ]]; then id="${BASH_REMATCH[1]}"
  fi
  if [ -n "$id" ]; then
    echo "https://drive.usercontent.google.com/download?id=$id&export=download&confirm=t"
  else
    echo "$url"
  fi
}

# curl with a message per failure class; the file appears under its name only when complete.
download() {
  local url="$1" out="$2" rc=0
  echo "fetch_dic_challenge: downloading $url"
  curl -fL --retry 2 --connect-timeout 20 -sS -o "$out.part" "$url" || rc=$?
  if [ $rc -ne 0 ]; then
    rm -f "$out.part"
    case $rc in
      5|6) die "cannot resolve the host of $url (curl exit $rc): no network or no DNS on this machine?" ;;
      7|28) die "cannot connect to $url (curl exit $rc): no network, or a firewall?" ;;
      22) die "the server refused $url (HTTP error; curl exit 22): the link may have moved" ;;
      *) die "download of $url failed (curl exit $rc)" ;;
    esac
  fi
  if [ "${3:-zip}" = zip ] && [ "$(head -c 4 "$out.part" | od -An -tx1 | tr -d ' \n')" != "504b0304" ]; then
    rm -f "$out.part"
    die "$url did not return a zip archive (Google Drive's HTML page: quota or confirmation?); download it in a browser into $dir/$(basename "$out") and rerun"
  fi
  mv "$out.part" "$out"
}

# The id of NAME in the public listing of the folder (best effort).
lookup_in_folder() {
  local name="$1" page
  page="$(curl -fsSL --connect-timeout 20 "$FOLDER_URL" 2>/dev/null)" || return 1
  printf '%s' "$page" | python3 -c '
import re, sys
page, name = sys.stdin.read(), sys.argv[1]
for m in re.finditer(r"\\x22([-\w]{25,})\\x22,\[\\x22[-\w]+\\x22\],\\x22([^\\]+?)\\x22", page):
    if m.group(2) == name:
        print(m.group(1)); break
else:
    sys.exit(1)' "$name"
}

check_sums() {
  local zip="$1" name sum recorded
  name="$(basename "$zip")"
  sum="$(sha256sum "$zip" | cut -d' ' -f1)"
  recorded="$(awk -v n="$name" '$2 == n {print $1}' "$dir/SHA256SUMS" 2>/dev/null || true)"
  if [ -n "$recorded" ] && [ "$recorded" != "$sum" ]; then
    die "$zip: SHA-256 $sum differs from the $recorded recorded in $dir/SHA256SUMS (a different archive; delete its line to accept it)"
  fi
  [ -n "$recorded" ] || echo "$sum  $name" >> "$dir/SHA256SUMS"
  echo "fetch_dic_challenge: $name sha256 $sum"
}

unpack() {
  local zip="$1" target="$2"
  rm -rf "$target.part"
  python3 -m zipfile -e "$zip" "$target.part" || { rm -rf "$target.part"; die "cannot unpack $zip"; }
  rm -rf "$target"
  mv "$target.part" "$target"
}

count() { find "$1" -type f -iname "$2" | wc -l; }

fetch() {  # fetch NAME URL PATTERN_REF PATTERN_DEF MIN_DEF
  local name="$1" url="$2" ref="$3" def="$4" min="$5" zip="$dir/$1.zip" folder="$dir/$1"
  if [ ! -f "$zip" ]; then
    download "$(direct_url "$url")" "$zip"
  else
    echo "fetch_dic_challenge: $zip present, not downloaded again"
  fi
  check_sums "$zip"
  unpack "$zip" "$folder"
  local nref ndef
  nref="$(count "$folder" "$ref")"
  ndef="$(count "$folder" "$def")"
  [ "$nref" -eq 1 ] || die "$zip: expected one reference image '$ref', found $nref"
  [ "$ndef" -ge "$min" ] || die "$zip: expected at least $min images '$def', found $ndef"
  echo "fetch_dic_challenge: $folder: 1 reference + $ndef deformed images"
}

status=0
fetch Sample14 "${sample14_url:-https://drive.google.com/file/d/$SAMPLE14_ID/view}" \
  "Sample*14*Reference.tif" "Sample*14 L* Amp*.tif" 1
truth="$dir/Sample14_command.csv"
if [ ! -f "$truth" ]; then
  download "${DIC_CHALLENGE_SAMPLE14_TRUTH_URL:-$TRUTH14_URL}" "$truth" csv
fi
rows="$(awk -F, 'NF == 7 && $1 == NR - 1' "$truth" | wc -l)"
[ "$rows" -ge 2048 ] && [ "$rows" -eq "$(wc -l < "$truth")" ] ||
  die "$truth: expected >= 2048 lines 'x,u_L1,exx_L1,u_L3,exx_L3,u_L5,exx_L5' with x = 0, 1, ..., found $rows such lines"
check_sums "$truth"
if [ -z "$sample3_url" ] && [ ! -f "$dir/Sample3.zip" ]; then
  if id="$(lookup_in_folder Sample3.zip)"; then
    sample3_url="https://drive.google.com/file/d/$id/view"
    echo "fetch_dic_challenge: Sample3.zip is $id in $FOLDER_URL"
  fi
fi
if [ -n "$sample3_url" ] || [ -f "$dir/Sample3.zip" ]; then
  fetch Sample3 "$sample3_url" "Sample3 Reference.tif" "Sample3-* X* Y*.tif" 11
else
  echo "fetch_dic_challenge: error: no source for Sample3.zip: its Drive id is not known to this script and the folder listing $FOLDER_URL could not be read. Open that folder, copy the link of Sample3.zip and rerun with --sample3-url LINK (or save the archive as $dir/Sample3.zip)" >&2
  status=3
fi
echo "fetch_dic_challenge: done; now run: bench/dic_challenge.py '$dir'"
exit $status
