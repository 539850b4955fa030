#!/usr/bin/env bash
# `make demo`: a tour of the CLI (codec, simulated vehicle) in .venv.
set -euo pipefail
cd "$(dirname "$0")/.."
nemesys=.venv/bin/nemesys
say() { printf '\n\033[1m$ %s\033[0m\n' "$*"; }

say nemesys patterns
$nemesys patterns

say nemesys encode lawnmower speed=0.8 depth=12.3 sweep_length=120 lane_spacing=7.3 laps=4
$nemesys encode lawnmower speed=0.8 depth=12.3 sweep_length=120 lane_spacing=7.3 laps=4

bits=$($nemesys encode helix speed=0.4 start_depth=2 end_depth=8 radius=3 turns=4 direction=ccw --json |
  .venv/bin/python -c 'import json, sys; print(json.load(sys.stdin)["bits"])')
# Flip two codeword bits (positions 40 and 77) as a noisy link would.
noisy=$(.venv/bin/python -c 'import sys; b = list(sys.argv[1]); [b.__setitem__(i, "10"[int(b[i])]) for i in (40, 77)]; print("".join(b))' "$bits")
say nemesys decode "<helix frame with 2 flipped bits>"
$nemesys decode "$noisy"

say nemesys encode circle speed=3 depth=2 radius=5 direction=cw "  # out of range: refused"
$nemesys encode circle speed=3 depth=2 radius=5 direction=cw || true

say nemesys scenario tank --out .demo "  # the paper's tank test in the simulator"
$nemesys scenario tank --out .demo

# The simulated vehicle behind its rosbridge websocket, on a free loopback port.
log=$(mktemp)
$nemesys sim --port 0 --ber 0.005 --seed 3 --quiet >"$log" 2>&1 &
sim_pid=$!
trap 'kill $sim_pid 2>/dev/null || true; rm -f "$log"' EXIT
for _ in $(seq 50); do grep -q 'ws://' "$log" && break; sleep 0.1; done
url=$(grep -o 'ws://[0-9.:]*' "$log")
say nemesys sim --port 0 --ber 0.005 "  # running at $url"
say nemesys send --to "$url" circle speed=0.18 depth=3 radius=5 direction=cw
$nemesys send --to "$url" circle speed=0.18 depth=3 radius=5 direction=cw || true
