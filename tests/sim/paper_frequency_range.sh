#!/bin/sh
# mjc-paper refuses a drive frequency outside the checked 0.25-2 Hz before running
# anything: exactly one line on stderr naming the option and the range, non-zero exit.
# Usage: paper_frequency_range.sh MJC_PAPER OUT_DIR
set -u
paper=$1
out=$2
for f in 0.1 0.2499 2.01 3 nan; do
  if msg=$("$paper" --quiet --out "$out" --frequency-hz "$f" 2>&1 >/dev/null); then
    echo "--frequency-hz $f was accepted"
    exit 1
  fi
  lines=$(printf '%s\n' "$msg" | wc -l)
  if [ "$lines" -ne 1 ]; then
    echo "--frequency-hz $f: $lines lines on stderr:"
    printf '%s\n' "$msg"
    exit 1
  fi
  case $msg in
    *--frequency-hz*"0.25 to 2 Hz"*) echo "refused: $msg" ;;
    *) echo "--frequency-hz $f: unexpected message: $msg"; exit 1 ;;
  esac
done
