#!/usr/bin/env bash
# Every output of the example scenes, a short Saussine sample + settle (plain and accelerated), a planar MD run,
# a Karrech deposit + load and a Luding compression + cycle, with a checkpoint and a --resume, hashed file by file:
# the byte-for-byte check of a refactoring that must not change behaviour (issue 33).
#
#   scripts/golden.sh DIR            runs everything into DIR (release build) and writes DIR/manifest.sha256
#   diff A/manifest.sha256 B/manifest.sha256    compares two states of the code
#
# Wall-clock times differ from run to run by nature: they are dropped before hashing (below).
set -euo pipefail
out=${1:?usage: scripts/golden.sh DIR}
cd "$(dirname "$0")/.."
cargo build --release --quiet
b="${CARGO_TARGET_DIR:-$PWD/target}/release/ballast"
mkdir -p "$out"
root=$PWD
cd "$out"
# Relative paths: the scenes written name their source, and must not name this folder.
out=.
# The scenes too: a scene written from another names its source by its path.
rm -rf examples && mkdir examples && cp "$root"/examples/*.toml examples/
run() { echo "+ ballast $*" >&2; "$b" "$@" --quiet >/dev/null; }
for scene in examples/*.toml; do
    name=$(basename "$scene" .toml)
    steps=300
    [ "$name" = settlement_sleeper ] && steps=2500
    vtk="--vtk-every 100"
    # An accelerated run writes no snapshots, and refuses to be asked for them.
    [ "$name" = settlement_sleeper ] && vtk=""
    run run "$scene" --out "$out/run-$name" --steps "$steps" $vtk --figures --threads 1
done
run run "examples/block_on_floor.toml" --engine md --out "$out/run-block-md" --steps 300 --vtk-every 100 --figures
run run "examples/sleeper_load.toml" --out "$out/resume" --steps 300 --stop-after 150 --checkpoint-every 0
run run "examples/sleeper_load.toml" --out "$out/resume" --steps 300 --resume --checkpoint-every 0
# Checkpoints left as they are, one per engine: copied next to a later state of the code and resumed there, each
# must end as an uninterrupted run does (cp -r OLD/stopped X && ballast run examples/sleeper_load.toml --out X
# --steps 300 --resume ends as ./resume; likewise md_two_spheres.toml for 3000 steps, block_on_floor.toml with
# --engine md for 300).
run run "examples/sleeper_load.toml" --out "$out/stopped" --steps 300 --stop-after 150 --checkpoint-every 0
run run "examples/md_two_spheres.toml" --out "$out/stopped-md" --steps 3000 --stop-after 1500 --checkpoint-every 0
run run "examples/block_on_floor.toml" --engine md --out "$out/stopped-md2d" --steps 300 --stop-after 100 \
    --checkpoint-every 0
run saussine sample --grains 60 --dt 1e-4 --seed 3 --out "$out/sample"
run saussine settle --sample "$out/sample/sample.toml" --cycles 2 --dt 1e-3 --bars 0 --out "$out/settle"
run saussine settle --sample "$out/sample/sample.toml" --cycles 12 --dt 1e-3 --bars 0 --accelerate 2,4,4 \
    --out "$out/settle-acc"
run karrech deposit --spheres 40 --young 1e7 --dt 2e-6 --duration 0.6 --every 1000 --out "$out/karrech"
run karrech load --from "$out/karrech" --cycles 1 --every 500 --out "$out/karrech-load"
run luding compress --spheres 27 --duration 3 --every 2000 --out "$out/luding"
run luding cycle --from "$out/luding" --cycles 1 --every 1000 --out "$out/luding-cycles"
# Wall-clock seconds (found by running the script twice and diffing) live in the JSON keys and CSV columns named
# *wall_time* and in the rates derived from them (*_per_s): dropped before hashing, and the file marked so.
python3 - <<'PY'
import csv, hashlib, io, json, os, re
clock = re.compile(r"wall_time|_per_s$")
def drop(v):
    if isinstance(v, dict):
        return {k: drop(x) for k, x in v.items() if not clock.search(k)}
    if isinstance(v, list):
        return [drop(x) for x in v]
    return v
hashed = []
for dirpath, _, files in os.walk("."):
    for f in files:
        path = os.path.join(dirpath, f)
        if f.startswith("manifest.") or path.startswith("./examples/"):
            continue
        data = open(path, "rb").read()
        if data.startswith(b"ballast-checkpoint"):
            # The envelope's CRC covers the wall time inside: compare the state it holds.
            data = data.split(b"\n", 1)[1]
            path += " (envelope dropped)"
        if f.endswith(".json"):
            value = json.loads(data)
            clean = json.dumps(drop(value), sort_keys=True).encode()
            if clean != json.dumps(value, sort_keys=True).encode():
                data, path = clean, path + " (wall-clock keys dropped)"
        if f.endswith(".csv"):
            rows = list(csv.reader(io.StringIO(data.decode())))
            keep = [i for i, h in enumerate(rows[0] if rows else []) if not clock.search(h)]
            if rows and len(keep) < len(rows[0]):
                data = "\n".join(",".join(r[i] for i in keep if i < len(r)) for r in rows).encode()
                path += " (wall-clock columns dropped)"
        hashed.append(f"{hashlib.sha256(data).hexdigest()}  {path}")
open("manifest.sha256", "w").write("\n".join(sorted(hashed, key=lambda l: l.split("  ", 1)[1])) + "\n")
print(f"{len(hashed)} files hashed: manifest.sha256")
PY
