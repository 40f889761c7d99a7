"""The Python binding against the library and the command line: every example scene loads and steps, the
state comes out as numpy arrays of the documented shapes, positions after N steps equal the command line's
`final.json` bit for bit, the write-back round-trips, and errors are the documented Python exceptions."""

import contextlib
import json
import os
import pathlib
import signal
import subprocess
import threading

import numpy as np
import pytest

import ballast

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.toml"))


def cli():
    """The `ballast` command: $BALLAST_BIN, else a build of this repository."""
    if "BALLAST_BIN" in os.environ:
        return os.environ["BALLAST_BIN"]
    for profile in ("release", "debug"):
        path = ROOT / "target" / profile / "ballast"
        if path.exists():
            return str(path)
    pytest.fail("no ballast command: build it (cargo build) or set BALLAST_BIN")


@contextlib.contextmanager
def ctrl_c_after(seconds):
    """SIGINT to this process after `seconds`, with Python's own Ctrl-C handler installed meanwhile: a process
    started in the background by a non-interactive shell inherits SIGINT ignored, and Python then installs no
    handler, so the signal would never reach the run."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)


@pytest.mark.parametrize("scene", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_loads_and_steps(scene):
    sim = ballast.load(scene)
    stats = sim.step(3)
    assert sim.steps_done == 3
    assert stats["time"] == pytest.approx(3 * sim.dt, rel=1e-12)
    n = len(sim.names)
    assert sim.positions.shape == (n, 3) and sim.positions.dtype == np.float64
    assert sim.velocities.shape == (n, 3) and sim.velocities.dtype == np.float64
    assert sim.fixed.shape == (n,) and sim.fixed.dtype == np.bool_
    assert np.isfinite(sim.positions).all()
    contacts = sim.contacts()
    m = len(contacts["kind"])
    dim = 3 if sim.engine in ("md", "nscd3d") else 2
    assert contacts["bodies"].shape == (m, 2) and contacts["bodies"].dtype == np.int64
    for key in ("points", "normals", "tangential_forces"):
        assert contacts[key].shape == (m, dim), key
    for key in ("gaps", "normal_forces"):
        assert contacts[key].shape == (m,), key


@pytest.mark.parametrize("scene, engine", [("block_on_floor", None), ("block_on_floor", "md2d"), ("md_two_spheres", None)])
def test_positions_equal_the_command_lines_final_state(tmp_path, scene, engine):
    """The same scene, the same steps: the binding's positions are the command line's, bit for bit (one thread
    or two give the same numbers)."""
    path = ROOT / "examples" / f"{scene}.toml"
    steps = 40
    args = [cli(), "run", str(path), "--out", str(tmp_path / "out"), "--steps", str(steps), "--quiet"]
    if engine:
        args += ["--engine", engine]
    subprocess.run(args, check=True, capture_output=True)
    final = json.loads((tmp_path / "out" / "final.json").read_text())
    sim = ballast.load(path, engine=engine)
    if engine:
        # A planar run of N steps is N of the planar engine's steps (its own dt).
        steps = final["step"]
    sim.step(steps)
    expected = np.array([b["position"] + ([b["angle"]] if "angle" in b else []) for b in final["bodies"]])
    assert np.array_equal(sim.positions, expected)
    assert sim.time == final["time"]


def test_set_positions_round_trips_and_refuses_moving_a_fixed_body():
    sim = ballast.load(ROOT / "examples" / "block_on_floor.toml")
    p = sim.positions.copy()
    p[1, 1] += 1e-3
    sim.set_positions(p)
    assert np.array_equal(sim.positions, p)
    assert not sim.velocities.any()
    moved = p.copy()
    moved[0, 0] += 1.0  # body 0, the floor, is fixed
    with pytest.raises(ValueError, match=r"positions\[0\]: body 'floor' is fixed"):
        sim.set_positions(moved)
    with pytest.raises(ValueError, match=r"positions: expected an array of shape \(2, 3\)"):
        sim.set_positions(p[:1])


def test_errors_are_python_exceptions_naming_the_key():
    text = (ROOT / "examples" / "block_on_floor.toml").read_text()
    with pytest.raises(ballast.SceneError) as bad:
        ballast.from_toml(text.replace("dt = 1.0e-3", "dt = -1.0e-3"))
    assert bad.value.key == "simulation.dt" and "simulation.dt" in str(bad.value)
    assert isinstance(bad.value, ValueError)
    with pytest.raises(ballast.SceneError) as syntax:
        ballast.from_toml("[simulation\n")
    assert syntax.value.key is None
    with pytest.raises(FileNotFoundError):
        ballast.load(ROOT / "examples" / "no_such_scene.toml")
    with pytest.raises(ValueError, match="n: must be at least 1"):
        ballast.load(ROOT / "examples" / "block_on_floor.toml").step(0)


def test_a_run_that_blows_up_raises_diverged_error_with_step_and_body():
    """A block squeezed by a press at an imposed 1 m/s: the overlap runs away (as tests/run_loop.rs)."""
    text = (ROOT / "examples" / "block_on_floor.toml").read_text()
    press = (
        '\n[[body]]\nname = "press"\nmaterial = "grain"\n'
        "polygon = [[-0.1, 0.0], [0.1, 0.0], [0.1, 0.05], [-0.1, 0.05]]\nposition = [0.0, 0.101]\n"
        "imposed = { vx = 0.0, vy = -1.0, spin = 0.0 }\n"
    )
    sim = ballast.from_toml(text + press)
    with pytest.raises(ballast.DivergedError) as e:
        sim.step(200)
    assert e.value.name in ("block", "press") and e.value.step >= 1
    assert sim.steps_done == e.value.step - 1, "the state is the last good step's"


def test_ctrl_c_ends_stepping_between_two_steps_with_keyboard_interrupt():
    """SIGINT while `step` runs a long way: KeyboardInterrupt within the signal check's period, the state that
    of the last step made (finite, its clock consistent with its step count)."""
    import time

    sim = ballast.load(ROOT / "examples" / "md_two_spheres.toml")
    start = time.monotonic()
    with ctrl_c_after(0.3), pytest.raises(KeyboardInterrupt):
        sim.step(10**12)
    elapsed = time.monotonic() - start
    # 0.3 s until the signal, then at most one 20 ms chunk plus a step: 1 s leaves room for a loaded machine.
    assert elapsed < 1.3, elapsed
    assert 0 < sim.steps_done < 10**12
    assert sim.time == pytest.approx(sim.steps_done * sim.dt, rel=1e-9)
    assert np.isfinite(sim.positions).all()
    sim.step(1)  # and it goes on
