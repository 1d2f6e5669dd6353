#!/usr/bin/env bash
# Latency of `s2kf live` over loopback: `s2kf serve` streams a simulated walk (50 markers, as long
# as the run, so the stream never jumps back to its start as a looped recording does) at 100, 300
# and 1000 Hz and `s2kf live` tracks it with a subject calibrated on it, sending every pose out as a
# JSON line over UDP. Each run's summary gives the time from a frame's arrival to its pose going out
# once the tracker has caught up with the held first second (median, p99, max, frames over one frame
# period), the frames dropped while busy (and of them, before the first pose), the frames tracked
# while catching up and the latest of them, the tracker's own median time per frame and the most
# memory the program held. SECONDS_PER_RATE is a whole number. With RSS_LOG=FILE set, the live
# program's resident memory (VmRSS) is also written to FILE every 10 s: rate, seconds, kB.
#   benchmarks/live_latency.sh [BUILD_DIR] [SECONDS_PER_RATE] [RATES...]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
seconds=${2:-20}
shift $(( $# > 2 ? 2 : $# ))
rates=("$@")
[ ${#rates[@]} -gt 0 ] || rates=(100 300 1000)
s2kf=$build/s2kf
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '%-6s %8s %10s %9s %9s %8s %9s %9s %9s %11s %10s %9s\n' rate frames median_ms p99_ms max_ms misses dropped preparing catch_up catch_up_ms step_ms rss_mb
for rate in "${rates[@]}"; do
  rm -f "$work/port"
  recording=$work/walk_$rate.c3d
  # Two seconds more than the run: the client's connection and the end of the run are not exact.
  "$s2kf" simulate --motion walk --rate "$rate" --frames $(( (seconds + 2) * rate )) --seed 1 \
    --out "$recording" >/dev/null
  "$s2kf" calibrate "$recording" --frames 150 --iterations 1 --quiet --out "$work/subject.json"
  "$s2kf" serve "$recording" --port 0 --port-file "$work/port" --rate "$rate" --quiet &
  server=$!
  for _ in $(seq 100); do [ -s "$work/port" ] && break; sleep 0.05; done
  /usr/bin/time -f %M -o "$work/rss" "$s2kf" live "127.0.0.1:$(cat "$work/port")" --subject "$work/subject.json" \
    --samples 301 --seconds "$seconds" --formats csv --quiet --udp-json 127.0.0.1:9 --out "$work/live_$rate" &
  timer=$!
  if [ -n "${RSS_LOG:-}" ]; then
    sleep 0.5
    live=$(pgrep -P "$timer" || true)  # the program, under /usr/bin/time
    start=$SECONDS
    while rss=$(awk '/^VmRSS/ {print $2}' "/proc/$live/status" 2>/dev/null) && [ -n "$rss" ]; do
      echo "$rate $(( SECONDS - start )) $rss" >>"$RSS_LOG"
      sleep 10
    done &
    sampler=$!
  fi
  wait "$timer"
  [ -z "${RSS_LOG:-}" ] || kill "$sampler" 2>/dev/null || true
  kill "$server"
  wait "$server" 2>/dev/null || true
  python3 - "$work/live_$rate.json" "$rate" "$(cat "$work/rss")" <<'PY'
import json, sys
summary = json.load(open(sys.argv[1]))
live = summary["live"]
latency = live["latency_ms"]
print(f'{sys.argv[2]:<6} {latency["frames"]:>8} {latency["median"]:>10.3f} {latency["p99"]:>9.3f} '
      f'{latency["max"]:>9.3f} {latency["deadline_misses"]:>8} {live["frames_dropped_busy"]:>9} '
      f'{live["frames_dropped_preparing"]:>9} {live["catch_up"]["frames"]:>9} {live["catch_up"]["max_ms"]:>11.1f} '
      f'{summary["latency_ms"]["median"]:>10.3f} {int(sys.argv[3]) / 1024:>9.1f}')
PY
done
