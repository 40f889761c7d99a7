#!/bin/bash
# One loading cycle of a loaded 3D scene per stopping rule, from R replicas of its state
# (docs/track3d.md, "The stopping rule on the seated 2 000-grain section").
#
#   BALLAST=$TARGET/release/ballast bash one_cycle_study.sh SCENE.toml OUT_DIR
#
# SCENE is a loaded state (e.g. the final_scene.toml of a `track3d settle` run after its seating);
# every run is 250 steps (one 20 Hz cycle at dt = 2e-4 s) on one thread. Replica r starts from the
# scene with every mobile body moved by at most 1e-9 m (`ballast run --replica r`; r = 0: as it is).
# Settings (name criterion tolerance replicas [extra [nscd] lines]):
#   q3  quad 1e-3, 12 replicas;  e5 energy 1.66e-5, 6;  q4 quad 1e-4 (at most 2 000 sweeps), 6;
#   q4x quad 1e-4 reached on every step (on_stall = "extend", up to 20 000 sweeps), 2 — the reference.
# Then: python3 summarize_cycle.py OUT_DIR q4x q3 e5 q4
# SETTINGS="q3 quad 1e-3 6;q4 quad 1e-4 6" runs those instead (name criterion tolerance replicas, `;` between),
# and REFERENCE names the summary's reference (default: the last setting).
# The scene's own [nscd] keys other than these (e.g. face_gaps) are kept.
set -euo pipefail
SCENE=$1
OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd)
BALLAST=${BALLAST:-ballast}
STEPS=${STEPS:-250}
mkdir -p "$OUT"
go() { # name criterion tolerance replica [extra]
  local n="$OUT/$1-r$4"
  [ -f "$n/summary.json" ] && return 0
  sed -e "s/^criterion = .*/criterion = \"$2\"/" -e "s/^tolerance = .*/tolerance = $3/" \
      -e "s/^max_iterations = \(.*\)/max_iterations = \1${5:-}/" "$SCENE" > "$n.toml"
  "$BALLAST" run "$n.toml" --out "$n" --steps "$STEPS" --threads 1 --quiet --replica "$4" --perturb 1e-9 \
      > "$n.log" 2>&1
}
if [ -n "${SETTINGS:-}" ]; then
  names=()
  IFS=';' read -ra rows <<< "$SETTINGS"
  for row in "${rows[@]}"; do
    read -r name crit tol reps <<< "$row"
    names+=("$name")
    for ((r = 0; r < reps; r++)); do go "$name" "$crit" "$tol" "$r"; done
  done
  ref=${REFERENCE:-${names[-1]}}
  python3 "$HERE/summarize_cycle.py" "$OUT" "$ref" $(printf '%s\n' "${names[@]}" | grep -vx "$ref")
  exit 0
fi
for r in 0 1 2 3 4 5 6 7 8 9 10 11; do go q3 quad 1e-3 $r; done
for r in 0 1 2 3 4 5; do go e5 energy 1.66e-5 $r; done
for r in 0 1 2 3 4 5; do go q4 quad 1e-4 $r; done
for r in 0 1; do go q4x quad 1e-4 $r '\non_stall = "extend"\nstall_max_iterations = 20000'; done
python3 "$HERE/summarize_cycle.py" "$OUT" q4x q3 e5 q4
