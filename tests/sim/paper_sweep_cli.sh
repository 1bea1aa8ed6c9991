#!/bin/sh
# mjc-paper --scenario sweep refuses, before anything runs or is written, with one line
# on stderr and a non-zero exit: a bad --shard, a bad grid file, sweep options without
# the sweep, a missing --grid. Then a one-point grid runs and a rerun resumes it.
# Usage: paper_sweep_cli.sh MJC_PAPER SCRATCH_DIR
set -u
paper=$1
dir=$2
rm -rf "$dir"
mkdir -p "$dir"
good=$dir/good.json
printf '%s\n' '{"repetitions": 3, "axes": {"frequency_hz": [1.0]}}' >"$good"
printf '%s\n' '{"axes": {"amplitude_deg": [45]}}' >"$dir/range.json"
printf '%s\n' '{"axes": {"amplitude_deg": [10]}, "sed": 1}' >"$dir/key.json"

refused() {  # expected-text args...
  expect=$1
  shift
  if msg=$("$paper" "$@" 2>&1 >/dev/null); then
    echo "accepted: $*"
    exit 1
  fi
  lines=$(printf '%s\n' "$msg" | wc -l)
  if [ "$lines" -ne 1 ]; then
    echo "$*: $lines lines on stderr:"
    printf '%s\n' "$msg"
    exit 1
  fi
  case $msg in
    *"$expect"*) echo "refused: $msg" ;;
    *) echo "$*: unexpected message: $msg"; exit 1 ;;
  esac
  if [ -e "$dir/out" ]; then
    echo "$*: wrote $dir/out"
    exit 1
  fi
}

refused "--shard 3/2: the index must be 0 to n - 1" --scenario sweep --grid "$good" --out "$dir/out" --shard 3/2
refused "--shard 0/0: the index must be 0 to n - 1" --scenario sweep --grid "$good" --out "$dir/out" --shard 0/0
refused "--shard 'x' is not i/n" --scenario sweep --grid "$good" --out "$dir/out" --shard x
refused "'axes.amplitude_deg[0]' = 45 is outside 1 to 30" \
  --scenario sweep --grid "$dir/range.json" --out "$dir/out"
refused "unknown key 'sed'" --scenario sweep --grid "$dir/key.json" --out "$dir/out"
refused "cannot be read" --scenario sweep --grid "$dir/none.json" --out "$dir/out"
refused "needs --grid" --scenario sweep --out "$dir/out"
refused "--grid is for --scenario sweep" --grid "$good" --out "$dir/out"
refused "the board refused --velocity-window 40" \
  --scenario sweep --grid "$good" --velocity-window 40 --out "$dir/out"
refused "--subjects is set in the sweep's grid file" \
  --scenario sweep --grid "$good" --subjects subject2 --out "$dir/out"

"$paper" --quiet --scenario sweep --grid "$good" --out "$dir/out" >/dev/null 2>&1 || {
  echo "a one-point sweep failed"
  exit 1
}
again=$("$paper" --quiet --scenario sweep --grid "$good" --out "$dir/out" 2>&1 >/dev/null)
case $again in
  *"1 grid points, 1 resumed from"*"0 to run"*) echo "resumed: $again" ;;
  *) echo "the rerun did not resume: $again"; exit 1 ;;
esac
