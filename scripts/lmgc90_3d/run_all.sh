#!/usr/bin/env bash
# Side-by-side runs of LMGC90 3D and ballast's 3D NSCD engine on LMGC90's polyhedra examples
# (Colonne_PR, 100_PR_PerioBox walled variant); see README.md beside this file.
#
#   LMGC90_SRC=$LMGC/src LMGC90_BUILD=$LMGC/build BALLAST=$TARGET/release/ballast \
#   WORK=$LMGC/runs bash scripts/lmgc90_3d/run_all.sh
#
# Every run uses one thread (OMP_NUM_THREADS=1 for LMGC90, --threads 1 for ours), one after the other.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
LMGC90_SRC=${LMGC90_SRC:-$LMGC/src}
LMGC90_BUILD=${LMGC90_BUILD:-$LMGC/build}
BALLAST=${BALLAST:-$TARGET/release/ballast}
WORK=${WORK:-$LMGC/runs}
PY=${PY:-/usr/bin/python3}            # the Python LMGC90 was built against (numpy, scipy)
COLONNE_STEPS=${COLONNE_STEPS:-5000}  # the script's nb_steps
PERIOBOX_STEPS=${PERIOBOX_STEPS:-8000} # the script has 100000; 8000 lets the whole column land
export OMP_NUM_THREADS=1
export PYTHONPATH=$LMGC90_BUILD${PYTHONPATH:+:$PYTHONPATH}

# --- Colonne_PR: 5 bricks on a foundation brick shaken along y -----------------------------------
mkdir -p "$WORK/colonne_t0" && cd "$WORK/colonne_t0"
cp "$LMGC90_SRC/examples/RIGID_3D/Colonne_PR/gen_sample.py" .
$PY gen_sample.py > gen.log 2>&1                       # the example's own DATBOX (pylmgc90.pre)
$PY "$HERE/colonne_shake_from_t0.py" DATBOX              # the same shaking, from t = 0 (see the script)
$PY "$HERE/datbox_to_toml.py" DATBOX -o colonne.toml --dt 1e-3 --steps "$COLONNE_STEPS" \
    --theta 0.5 --criterion strict --tolerance 1e-4 --max-iterations 5000
$PY "$HERE/run_lmgc90.py" --case colonne --steps "$COLONNE_STEPS" --out lmgc90 > lmgc90.log 2>&1
$PY "$HERE/run_lmgc90.py" --case colonne --steps "$COLONNE_STEPS" --check-every 10 --blocks 500 \
    --out lmgc90_check10 > lmgc90_check10.log 2>&1
{ time "$BALLAST" run colonne.toml --out ours --threads 1 ; } > ours.log 2>&1
$PY "$HERE/compare.py" --title "Colonne_PR (shaking from t = 0), $COLONNE_STEPS steps of 1 ms" \
    --scene colonne.toml \
    --lmgc90 lmgc90 --lmgc90-label "LMGC90, script (check every 500 sweeps)" \
    --lmgc90 lmgc90_check10 --lmgc90-label "LMGC90, check every 10 sweeps" \
    --ours ours --json table.json --windows 5 > table.md
cat table.md

# --- 100_PR_PerioBox, walled variant: 100 polyhedra, floor + 4 walls --------------------------------
mkdir -p "$WORK/periobox_walled" && cd "$WORK/periobox_walled"
$PY "$HERE/gen_periobox_walled.py" \
    "$LMGC90_SRC/build_native/examples/RIGID_3D/100_PR_PerioBox/DATBOX" . > gen.log 2>&1
$PY "$HERE/datbox_to_toml.py" DATBOX -o periobox_walled.toml --dt 2e-3 --steps "$PERIOBOX_STEPS" \
    --theta 0.5 --criterion strict --tolerance 1.666e-5 --max-iterations 4000
$PY "$HERE/run_lmgc90.py" --case periobox --steps "$PERIOBOX_STEPS" --out lmgc90 > lmgc90.log 2>&1
{ time "$BALLAST" run periobox_walled.toml --out ours --threads 1 ; } > ours.log 2>&1
$PY "$HERE/run_lmgc90.py" --case periobox --steps "$PERIOBOX_STEPS" --check-every 10 --blocks 400 \
    --out lmgc90_check10 > lmgc90_check10.log 2>&1
$PY "$HERE/compare.py" --title "100_PR_PerioBox, walled variant, $PERIOBOX_STEPS steps of 2 ms" \
    --scene periobox_walled.toml \
    --lmgc90 lmgc90 --lmgc90-label "LMGC90, script (check every 400 sweeps)" \
    --lmgc90 lmgc90_check10 --lmgc90-label "LMGC90, check every 10 sweeps" \
    --ours ours --json table.json --windows 8 > table.md
cat table.md

# --- reference only: the example as written (periodic, source point, driven floor), LMGC90 alone ---
mkdir -p "$WORK/periobox_periodic" && cd "$WORK/periobox_periodic"
cp -r "$LMGC90_SRC/build_native/examples/RIGID_3D/100_PR_PerioBox/DATBOX" .
$PY "$HERE/run_lmgc90.py" --case periobox --periodic --steps "$PERIOBOX_STEPS" --out lmgc90 > lmgc90.log 2>&1
