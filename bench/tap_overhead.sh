#!/usr/bin/env bash
# Does a live tap slow a run down? The Chapter 3 quarter car (distributed, 1 ms, 4 s = 4000
# coupled steps), alternately untapped and tapped on everything ('**', every data and control
# message, with the CSV of every data message), REPEATS times each; prints coupled steps/s.
# Then replays the journal as fast as possible into a tap and prints the replay rate.
#
#   bash bench/tap_overhead.sh [OUT_DIR] [REPEATS]   (default runs/tap_overhead, 3)
#
# Results: docs/tap_replay.md.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-runs/tap_overhead}"
repeats="${2:-3}"
mkdir -p "$out"
port() { python -c "from cosim.bus import free_loopback_endpoint as f; print(f())"; }
rate() { python -c "import json,sys; s=json.load(open(sys.argv[1])); print(f\"{s['steps_per_s']:.0f}\")" "$1"; }
for i in $(seq "$repeats"); do
  python -m orchestrator run scenarios/ch3_step_quarter_car.toml --out "$out/plain$i" --quiet \
    > /dev/null
  ep=$(port)
  python -m orchestrator run scenarios/ch3_step_quarter_car.toml --out "$out/tapped$i" \
    --quiet --listen "$ep" > /dev/null &
  run=$!
  while [ ! -f "$out/tapped$i/journal.msgpack" ]; do sleep 0.05; done
  python -m orchestrator tap "$out/tapped$i" --duration 60 --count 16004 \
    --csv "$out/tapped$i.csv" > "$out/tap$i.log" 2>&1 &
  tap=$!
  wait "$run"
  kill -TERM "$tap" 2> /dev/null || true
  wait "$tap" || true
  echo "repeat $i: untapped $(rate "$out/plain$i/summary.json") steps/s," \
    "tapped $(rate "$out/tapped$i/summary.json") steps/s ($(tail -1 "$out/tap$i.log"))"
done
ep=$(port)
python -m orchestrator tap '*' plant/state --listen "$ep" --count 4001 --duration 60 \
  > "$out/replay_tap.log" 2>&1 &
tap=$!
sleep 1
python -m orchestrator replay "$out/plain1" --fast --connect "$ep" 2> /dev/null
wait "$tap"
tail -1 "$out/replay_tap.log"
