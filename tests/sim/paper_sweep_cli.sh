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

# A cable slack wider than the motion: the joint barely moves, so η and the power error
# (ratios to a loading work of ~0) are n/a with the reason, while the motion that does
# load the joint keeps its figures. The loading work judged is the row's own, in
# sweep.csv (truth_load_mJ), below the table's 0.001 mJ resolution.
printf '%s\n' '{"repetitions": 3, "axes": {"amplitude_deg": [2, 15], "cable_slack_deg": [8]}}' \
  >"$dir/slack.json"
"$paper" --quiet --scenario sweep --grid "$dir/slack.json" --out "$dir/slack" \
  >/dev/null 2>"$dir/slack.err" || { echo "the slack sweep failed: $(cat "$dir/slack.err")"; exit 1; }
load2=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "truth_load_mJ") c = i }
  NR == 2 { print $c }' "$dir/slack/sweep.csv")
awk -v l="$load2" 'BEGIN { exit !(l < 0.001) }' ||
  { echo "2° inside 8° of slack loaded the joint with $load2 mJ"; exit 1; }
row2=$(grep '^| 0 | 2 |' "$dir/slack/sweep.md")
case $row2 in
  *"| n/a (loading "*"| n/a (loading "*"| n/a (loading "*) echo "2°: $row2" ;;
  *) echo "the 2° row gives ratios of no loading: $row2"; exit 1 ;;
esac
row15=$(grep '^| 1 | 15 |' "$dir/slack/sweep.md")
case $row15 in
  *"n/a"*) echo "the 15° row lost its figures: $row15"; exit 1 ;;
  *) echo "15°: $row15" ;;
esac

# scripts/family-figures (./bench's worst-of-family figures) on the same sweep: the
# still 2° point is left out of the ratios and counted, the 15° point gives each figure.
figures=$(python3 "$(dirname "$0")/../../scripts/family-figures" "$dir/slack") ||
  { echo "family-figures failed on the slack sweep"; exit 1; }
echo "$figures"
power=$(printf '%s\n' "$figures" | grep '^power_rmse_pct_peak_family: ')
case $power in
  *"(worst of 2 points, 0 faulted, 1 without loading work: "*"amplitude_deg 15,"*) ;;
  *) echo "family-figures' power line: $power"; exit 1 ;;
esac
expected=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "power_rmse_pct_peak") c = i }
  NR == 3 { printf "%.3g", $c }' "$dir/slack/sweep.csv")
case $power in
  "power_rmse_pct_peak_family: $expected %"*) ;;
  *) echo "family-figures gave $power, sweep.csv's 15° row $expected"; exit 1 ;;
esac
if python3 "$(dirname "$0")/../../scripts/family-figures" "$dir/none" 2>/dev/null; then
  echo "family-figures accepted a folder without a sweep"
  exit 1
fi
