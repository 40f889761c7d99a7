#!/bin/bash
# Interleaved timing rounds of the md-bed benchmark: in each round LAMMPS and
# LIGGGHTS on one core (run_peers.sh), then ours on 1 and 2 threads
# (examples/md_bed on a cached settled bed), then LAMMPS on 2 ranks. Interleaving
# puts every code in the same minutes of a noisy machine.
#
#   ROUNDS=3 benches/peers/rounds.sh > rounds.txt
#
# Needs the peers set up as in benches/peers/README.md and settled beds of ours
# in $BED_DIR/bed$N.json (written by the first run of
# `BED_CACHE=$BED_DIR/bed$N.json cargo run --release --example md_bed -- N`).
set -eu
cd "$(dirname "$0")/../.."
ROUNDS=${ROUNDS:-3}
BED_DIR=${BED_DIR:-/tmp}
cargo build --release --example md_bed >&2
for round in $(seq 1 "$ROUNDS"); do
  echo "# round $round $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)"
  bash benches/peers/run_peers.sh 2>/dev/null
  for N in 2000 8000; do
    echo "ballast $N"
    BED_CACHE="$BED_DIR/bed$N.json" target/release/examples/md_bed "$N" 0 10000 2>&1 | grep threads
  done
  LAMMPS_NP=2 bash benches/peers/run_peers.sh 2>/dev/null | grep np2
done
echo "# end $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)"
