"""`Simulation.settle`, the settlement driver from Python: the example's accelerated run gives the command
line's numbers; a loaded sleeper without a `[settlement]` table, given the same settings as arguments, runs the
same procedure; a stop resumes to the same numbers; bad settings name the key."""

import json
import subprocess

import pytest

import ballast
from test_simulation import ROOT, cli

EXAMPLE = ROOT / "examples" / "settlement_sleeper.toml"
PLAIN = ROOT / "examples" / "sleeper_load.toml"
SAME = ("total_cycles", "computed_cycles", "jumps", "settlement_m", "gained", "steps", "end")


def rows(folder):
    """`settlement.csv` without its wall-time column."""
    lines = (folder / "settlement.csv").read_text().splitlines()
    header = lines[0].split(",")
    keep = [i for i, name in enumerate(header) if "wall" not in name]
    return [[line.split(",")[i] for i in keep] for line in lines]


def test_settle_gives_the_command_lines_numbers(tmp_path):
    args = [cli(), "run", str(EXAMPLE), "--out", str(tmp_path / "cli"), "--quiet", "--threads", "1"]
    subprocess.run(args, check=True, capture_output=True)
    expected = json.loads((tmp_path / "cli" / "summary.json").read_text())
    sim = ballast.load(EXAMPLE)
    seen = []
    got = sim.settle(out=tmp_path / "py", progress=seen.append, threads=1)
    assert got["total_cycles"] == 30 and got["out"] == str(tmp_path / "py")
    assert {k: got[k] for k in SAME} == {k: expected[k] for k in SAME}
    assert rows(tmp_path / "cli") == rows(tmp_path / "py")
    assert sim.steps_done == got["steps"], "the simulation holds the state reached"
    assert seen[0]["cycle"] == 1 and seen[-1]["cycle"] == seen[-1]["target"] == 30


def test_settings_as_arguments_replace_the_table(tmp_path):
    sim = ballast.load(EXAMPLE)
    whole = sim.settle(cycles=14, out=tmp_path / "own")
    given = ballast.load(PLAIN).settle(
        cycles=14, accelerate=(2, 4, 4), law="shenton", body="sleeper", settings={"relax_tolerance": 1e-5},
        out=tmp_path / "given",
    )
    assert {k: whole[k] for k in SAME} == {k: given[k] for k in SAME}
    assert rows(tmp_path / "own") == rows(tmp_path / "given")


def test_a_stopped_settle_resumes_to_the_same_numbers(tmp_path):
    whole = ballast.load(EXAMPLE).settle(cycles=14, out=tmp_path / "whole")
    first = ballast.load(EXAMPLE).settle(cycles=14, out=tmp_path / "cut", stop_after=1000)
    assert first["end"] == "stopped" and (tmp_path / "cut" / "checkpoint.json").is_file()
    end = ballast.load(EXAMPLE).settle(cycles=14, out=tmp_path / "cut", resume=True)
    assert {k: end[k] for k in SAME} == {k: whole[k] for k in SAME}
    assert rows(tmp_path / "whole") == rows(tmp_path / "cut")


def test_bad_settings_name_the_key():
    with pytest.raises(ballast.SceneError, match="accelerate: the scene has no") as e:
        ballast.load(PLAIN).settle(cycles=4)
    assert e.value.key == "accelerate"
    with pytest.raises(ballast.SceneError, match="unknown field `relax_tolerence`") as e:
        ballast.load(EXAMPLE).settle(settings={"relax_tolerence": 1e-5})
    assert e.value.key == "settlement"
    with pytest.raises(ballast.SceneError) as e:
        ballast.load(EXAMPLE).settle(cycles=0)
    assert e.value.key == "cycles"
