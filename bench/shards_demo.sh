#!/usr/bin/env bash
# Three shards of a sweep as three processes on this machine, against the same sweep unsharded: the
# same set of points (each once), the merged file read by compare, and each run's wall time. All runs
# append to one store (OUT_DIR/history.sqlite), the three shards at once.
#
#   bench/shards_demo.sh OUT_DIR [SWEEP ...]     default sweep: figure9 --quick --methods all (CI's)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: bench/shards_demo.sh OUT_DIR [SWEEP ...]}
shift
sweep=("$@")
((${#sweep[@]})) || sweep=(figure9 --quick --methods all)
name=${sweep[0]}
bin=build/bokehbench
rm -rf "$out" && mkdir -p "$out"
store=$out/history.sqlite

now_ms() { echo $(($(date +%s%N) / 1000000)); }
seconds_since() { local ms=$(($(now_ms) - $1)); printf '%d.%03d\n' $((ms / 1000)) $((ms % 1000)); }
start=$(now_ms)
$bin "${sweep[@]}" --no-plot --out-dir "$out/whole" --store "$store" > "$out/whole.log"
whole_s=$(seconds_since "$start")

start=$(now_ms)
pids=()
for i in 1 2 3; do
  ( s=$(now_ms); $bin "${sweep[@]}" --no-plot --shard "$i/3" --out-dir "$out/shard$i" --store "$store" > "$out/shard$i.log"
    seconds_since "$s" > "$out/shard$i.seconds" ) &
  pids+=($!)
done
for p in "${pids[@]}"; do wait "$p"; done
shards_s=$(seconds_since "$start")

$bin merge "$out"/shard{1,2,3}/"$name.json" --out "$out/merged.json"
/usr/bin/python3 - "$out" "$name" <<'PY'
import json, sys, pathlib
out, name = pathlib.Path(sys.argv[1]), sys.argv[2]
ids = lambda d: {p["id"] for p in d["points"]} | {p["id"] for p in d["skipped"]}
whole = json.loads((out / "whole" / f"{name}.json").read_text())
shards = [json.loads((out / f"shard{i}" / f"{name}.json").read_text()) for i in (1, 2, 3)]
seen = [i for s in shards for i in ids(s)]
print(f"unsharded: {len(ids(whole))} points; shards: {[len(ids(s)) for s in shards]} = {len(seen)}, "
      f"each once: {len(seen) == len(set(seen))}, the same set: {set(seen) == ids(whole)}")
PY
echo "wall time: unsharded ${whole_s} s; three shards at once ${shards_s} s (each: $(cat "$out"/shard{1,2,3}.seconds | tr '\n' ' ')s)"
set +e
$bin compare "$out/whole/$name.json" "$out/merged.json" > "$out/compare.txt"
echo "compare unsharded vs merged: exit $? (0 no confident regression, 2 slower, 3 not comparable); $out/compare.txt"
$bin history list --store "$store" | head -8
