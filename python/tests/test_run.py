"""`Simulation.run`, the library's run loop from Python: the outputs of `ballast run` byte for byte, a run
stopped (by `stop_after`, by `progress` returning False, by Ctrl-C) leaves a checkpoint that `resume=True`
continues to the bytes of an uninterrupted run, and the simulation keeps the state the run reached."""

import json
import subprocess

import numpy as np
import pytest

import ballast
from test_simulation import ROOT, cli, ctrl_c_after

BLOCK = ROOT / "examples" / "block_on_floor.toml"
SPHERES = ROOT / "examples" / "md_two_spheres.toml"
OUTPUTS = ("series.csv", "final.json", "contacts.csv", "scene.toml")


def same_outputs(a, b):
    for name in OUTPUTS:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


@pytest.mark.parametrize("scene", [BLOCK, SPHERES], ids=lambda p: p.stem)
def test_run_writes_the_command_lines_outputs_and_keeps_the_end_state(tmp_path, scene):
    steps = 300
    args = [cli(), "run", str(scene), "--out", str(tmp_path / "cli"), "--steps", str(steps), "--quiet"]
    subprocess.run(args, check=True, capture_output=True)
    sim = ballast.load(scene)
    seen = []
    result = sim.run(tmp_path / "py", steps=steps, progress=seen.append)
    assert result["status"] == "finished" and result["step"] == steps == sim.steps_done
    assert result["report"]["steps"] == steps
    same_outputs(tmp_path / "cli", tmp_path / "py")
    final = json.loads((tmp_path / "py" / "final.json").read_text())
    expected = np.array([b["position"] + ([b["angle"]] if "angle" in b else []) for b in final["bodies"]])
    assert np.array_equal(sim.positions, expected)
    # progress: at least the last step, each a dict of the documented keys.
    assert seen and seen[-1]["step"] == steps and seen[-1]["end_step"] == steps
    assert set(seen[-1]) == {"step", "end_step", "time", "kinetic_energy", "contacts", "cycles", "settlement"}


@pytest.mark.parametrize("how", ["stop_after", "progress"])
def test_a_stopped_run_resumes_to_the_bytes_of_an_uninterrupted_one(tmp_path, how):
    steps = 400
    ballast.load(SPHERES).run(tmp_path / "whole", steps=steps)
    sim = ballast.load(SPHERES)
    if how == "stop_after":
        first = sim.run(tmp_path / "parts", steps=steps, stop_after=150)
    else:
        first = sim.run(tmp_path / "parts", steps=steps, progress=lambda p: False)
    assert first["status"] == "stopped" and 0 < first["step"] < steps and sim.steps_done == first["step"]
    assert (tmp_path / "parts" / "checkpoint.json").is_file()
    assert not (tmp_path / "parts" / "final.json").exists()
    # Continued by a fresh simulation of the scene, and by the stopped one (its state does not matter).
    again = ballast.load(SPHERES)
    end = again.run(tmp_path / "parts", steps=steps, resume=True)
    assert end["status"] == "finished" and end["step"] == steps
    same_outputs(tmp_path / "whole", tmp_path / "parts")
    with pytest.raises(ballast.CheckpointError, match="resume: no checkpoint.json"):
        sim.run(tmp_path / "parts", steps=steps, resume=True)


def test_a_finished_run_is_extended_to_the_bytes_of_a_longer_one(tmp_path):
    ballast.load(SPHERES).run(tmp_path / "whole", steps=401)
    first = ballast.load(SPHERES).run(tmp_path / "parts", steps=200, keep_checkpoint=True)
    assert first["status"] == "finished" and (tmp_path / "parts" / "checkpoint.json").is_file()
    with pytest.raises(ballast.CheckpointError, match="another scene"):
        ballast.load(SPHERES).run(tmp_path / "parts", steps=401, resume=True)
    end = ballast.load(SPHERES).run(tmp_path / "parts", steps=401, resume=True, extend=True)
    assert end["status"] == "finished" and end["step"] == 401
    same_outputs(tmp_path / "whole", tmp_path / "parts")


def test_a_run_resumes_with_another_tolerance(tmp_path):
    changed = tmp_path / "tight.toml"
    changed.write_text(BLOCK.read_text().replace("[output]", "[nscd]\ntolerance = 1e-6\n\n[output]", 1))
    first = ballast.load(BLOCK).run(tmp_path / "run", steps=40, stop_after=20)
    assert first["status"] == "stopped" and first["solver_changes"] == []
    with pytest.raises(ballast.CheckpointError, match="another scene"):
        ballast.load(changed).run(tmp_path / "run", steps=40, resume=True)
    end = ballast.load(changed).run(tmp_path / "run", steps=40, resume=True, change_solver=True)
    assert end["status"] == "finished" and end["step"] == 40
    assert [(c["step"], c["key"], c["after"]) for c in end["solver_changes"]] == [(20, "nscd.tolerance", "0.000001")]
    assert (tmp_path / "run" / "solver_changes.csv").read_text().startswith("step,time_s,key,before,after\n20,")


def test_ctrl_c_stops_a_run_with_keyboard_interrupt_and_a_checkpoint(tmp_path):
    sim = ballast.load(SPHERES)
    with ctrl_c_after(0.5), pytest.raises(KeyboardInterrupt):
        sim.run(tmp_path / "run", steps=10**9)
    done = sim.steps_done
    assert 0 < done < 10**9
    assert (tmp_path / "run" / "checkpoint.json").is_file()
    rows = (tmp_path / "run" / "series.csv").read_text().splitlines()
    assert len(rows) >= 2, "the rows up to the stop are on disk"
    more = ballast.load(SPHERES).run(tmp_path / "run", steps=10**9, resume=True, stop_after=10)
    assert more["status"] == "stopped" and more["step"] == done + 10


def test_an_exception_in_progress_stops_the_run_and_is_raised(tmp_path):
    def fail(p):
        raise RuntimeError("from progress")

    sim = ballast.load(BLOCK)
    with pytest.raises(RuntimeError, match="from progress"):
        sim.run(tmp_path / "run", steps=10**6, progress=fail)
    assert (tmp_path / "run" / "checkpoint.json").is_file()


def test_a_run_without_a_folder_steps_on_from_the_state_held(tmp_path):
    sim = ballast.load(BLOCK)
    sim.step(5)
    result = sim.run(steps=20)
    assert result["out"] is None and result["status"] == "finished"
    assert sim.steps_done == 25 and result["step"] == 25
    # Stepped by hand the same way: the same state.
    other = ballast.load(BLOCK)
    other.step(25)
    assert np.array_equal(sim.positions, other.positions)
    with pytest.raises(ValueError, match="resume: needs the folder"):
        sim.run(resume=True)
