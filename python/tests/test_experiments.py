"""The papers' experiments from Python against the command line: a Saussine sample deposited from Python is
the CLI's byte for byte, its loaded scene runs the CLI's cycles, and an ensemble of replicas gives the summary
of `ballast saussine settle --replicas` byte for byte through a local process pool and through a Dask
`LocalCluster`; the Karrech deposit and the Luding box open and step; bad loading arguments name the key."""

import subprocess

import numpy as np
import pytest

import ballast
from test_simulation import cli

SHORT = {"cycles": 4, "dt": 1e-3, "bars": 0}
SHORT_FLAGS = ["--cycles", "4", "--dt", "1e-3", "--bars", "0"]


@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    """A 50-grain sample deposited from Python, and the same deposited by the command line."""
    root = tmp_path_factory.mktemp("sample")
    sim = ballast.saussine.sample(root / "py", grains=50, dt=5e-4)
    args = [cli(), "saussine", "sample", "--grains", "50", "--dt", "5e-4", "--out", str(root / "cli"), "--quiet"]
    subprocess.run(args, check=True, capture_output=True)
    return root, sim


def test_a_sample_deposited_from_python_is_the_command_lines(sample):
    root, sim = sample
    for name in ("sample.toml", "sample.json"):
        assert (root / "py" / name).read_bytes() == (root / "cli" / name).read_bytes(), name
    assert sim.engine == "nscd" and len(sim.names) == sim.positions.shape[0]


def test_the_loaded_sample_runs_the_command_lines_cycles(sample, tmp_path):
    root, sim = sample
    args = [cli(), "saussine", "settle", "--sample", str(root / "cli" / "sample.toml"), *SHORT_FLAGS]
    subprocess.run([*args, "--out", str(tmp_path / "cli"), "--quiet"], check=True, capture_output=True)
    # The sample as a path, and as the Simulation that holds it: the same loaded scene.
    loaded = ballast.saussine.load(root / "py" / "sample.toml", **SHORT)
    assert loaded.to_toml() == ballast.saussine.load(sim, **SHORT).to_toml()
    result = loaded.run(tmp_path / "py")
    assert result["status"] == "finished"
    assert (tmp_path / "py" / "cycles.csv").read_bytes() == (tmp_path / "cli" / "cycles.csv").read_bytes()
    cycles = ballast.table(tmp_path / "py" / "cycles.csv")
    assert cycles["cycle"].dtype == np.int64 and list(cycles["cycle"]) == [1, 2, 3, 4]
    assert cycles["settlement_mean_m"].dtype == np.float64 and np.isfinite(cycles["settlement_mean_m"]).all()


@pytest.fixture(scope="module")
def reference(sample, tmp_path_factory):
    """`ballast saussine settle --replicas 4` on the CLI's sample (the same bytes as the Python one)."""
    root, _ = sample
    out = tmp_path_factory.mktemp("cli-replicas")
    args = [cli(), "saussine", "settle", "--sample", str(root / "cli" / "sample.toml"), *SHORT_FLAGS]
    subprocess.run([*args, "--replicas", "4", "--out", str(out), "--quiet"], check=True, capture_output=True)
    return out / "settlement_ensemble.csv"


def test_an_ensemble_on_a_process_pool_is_the_command_lines(sample, reference, tmp_path):
    root, _ = sample
    result = ballast.ensemble(root / "cli" / "sample.toml", replicas=4, out=tmp_path / "pool", **SHORT)
    assert result["failed"] == []
    assert (tmp_path / "pool" / "settlement_ensemble.csv").read_bytes() == reference.read_bytes()
    table = result["table"]
    assert list(table["replicas"]) == [4] * 4 and table["settlement_mean_m"].shape == (4,)


def test_an_ensemble_on_a_dask_cluster_is_the_command_lines(sample, reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    root, _ = sample
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            result = ballast.ensemble(
                root / "cli" / "sample.toml", replicas=4, out=tmp_path / "dask", executor=client, **SHORT
            )
    assert result["failed"] == []
    assert (tmp_path / "dask" / "settlement_ensemble.csv").read_bytes() == reference.read_bytes()


def test_settings_are_replicated_each_in_its_folder(sample, tmp_path):
    root, _ = sample
    from concurrent.futures import ThreadPoolExecutor

    settings = [{"name": "soft"}, {"name": "stiff", "stiffness_factor": 100.0}]
    with ThreadPoolExecutor(2) as pool:
        results = ballast.ensemble(
            root / "cli" / "sample.toml", replicas=2, settings=settings, out=tmp_path, executor=pool, **SHORT
        )
    assert set(results) == {"soft", "stiff"}
    for name in ("soft", "stiff"):
        assert (tmp_path / name / "runs" / "replica-1" / "cycles.csv").is_file()
    soft, stiff = (results[n]["table"]["settlement_mean_m"] for n in ("soft", "stiff"))
    # A sublayer 100 times stiffer: the sleeper settles less (Saussine §4.2, Fig. 12).
    assert stiff[-1] < soft[-1]


def test_bad_loading_arguments_name_the_key(sample):
    root, _ = sample
    with pytest.raises(ballast.SceneError) as e:
        ballast.saussine.load(root / "cli" / "sample.toml", cycles=4, stiffnes_factor=100.0)
    assert e.value.key == "stiffnes_factor"
    with pytest.raises(ballast.SceneError) as e:
        ballast.saussine.load(root / "cli" / "sample.toml", guide="sideways")
    assert e.value.key == "guide"
    with pytest.raises(ValueError, match="out: the replicas"):
        ballast.ensemble(root / "cli" / "sample.toml", replicas=2)


def test_the_karrech_deposit_and_the_luding_box_open_and_step(tmp_path):
    sim = ballast.karrech.deposit(tmp_path / "karrech", spheres=20, dt=1e-6, duration=2e-3, every=100)
    assert sim.engine == "md" and sim.positions.shape[1] == 3
    assert (tmp_path / "karrech" / "final.json").is_file()
    box = ballast.luding.box(spheres=27, duration=1e-3, every=10)
    assert box.engine == "md"
    box.step(5)
    assert np.isfinite(box.positions).all()


def strip_wall_times(path):
    """A CSV's text without the columns of wall-clock time (the one thing two runs of a study differ in)."""
    lines = path.read_text().splitlines()
    keep = [i for i, name in enumerate(lines[0].split(",")) if "wall" not in name]
    return [[line.split(",")[i] for i in keep] for line in lines]


def test_the_convergence_and_compare_studies_are_the_command_lines(sample, tmp_path):
    root, sim = sample
    path = str(root / "cli" / "sample.toml")
    flags = ["--cycles", "2", "--dt", "1e-3", "--bars", "0", "--quiet"]
    policies = [("energy", 1.66e-3), ("strict", 1e-3)]
    cli_conv = tmp_path / "cli-conv"
    args = [cli(), "saussine", "convergence", "--sample", path, "--policies", "energy:1.66e-3,strict:1e-3"]
    subprocess.run([*args, *flags, "--out", str(cli_conv)], check=True, capture_output=True)
    # The sample as the Simulation that holds it (written to the study's folder).
    conv = ballast.saussine.convergence(sim, tmp_path / "py-conv", policies=policies, cycles=2, dt=1e-3, bars=0)
    assert conv["failed"] == [] and list(conv["table"]["policy"]) == ["energy", "strict"]
    assert strip_wall_times(tmp_path / "py-conv" / "convergence.csv") == strip_wall_times(cli_conv / "convergence.csv")
    cli_cmp = tmp_path / "cli-cmp"
    args = [cli(), "compare", "--sample", path, "--overlaps", "1e-2"]
    subprocess.run([*args, *flags, "--out", str(cli_cmp)], check=True, capture_output=True)
    cmp = ballast.saussine.compare(path, tmp_path / "py-cmp", overlaps=[1e-2], cycles=2, dt=1e-3, bars=0)
    assert cmp["failed"] == [] and set(cmp["table"]["engine"]) == {"nscd", "md2d"}
    assert strip_wall_times(tmp_path / "py-cmp" / "compare.csv") == strip_wall_times(cli_cmp / "compare.csv")


def test_an_ensemble_of_a_cyclic_scene_replicates_it_as_it_is(tmp_path):
    """A loaded scene (it has [output] cycles) is replicated as it is: replica 0 runs the scene's own cycles,
    as `ballast run` does; loading arguments are refused for it."""
    from concurrent.futures import ThreadPoolExecutor

    from test_simulation import ROOT

    scene = ROOT / "tests" / "data" / "loaded50.toml"
    subprocess.run([cli(), "run", str(scene), "--out", str(tmp_path / "cli"), "--quiet"], check=True, capture_output=True)
    with ThreadPoolExecutor(2) as pool:
        result = ballast.ensemble(scene, replicas=2, out=tmp_path / "ens", executor=pool, seating_cycles=1)
    assert result["failed"] == [] and list(result["table"]["cycle"]) == [1, 2]
    replica0 = tmp_path / "ens" / "runs" / "replica-0" / "cycles.csv"
    assert replica0.read_bytes() == (tmp_path / "cli" / "cycles.csv").read_bytes()
    with pytest.raises(ballast.SceneError) as e:
        ballast.ensemble(scene, replicas=2, out=tmp_path / "bad", cycles=3)
    assert e.value.key == "loading"


def test_an_ensemble_on_mpi4pys_pool_is_the_command_lines(sample, reference, tmp_path):
    """mpi4py's `MPIPoolExecutor` under `mpiexec -n 3 python -m mpi4py.futures` (a manager and two workers)."""
    import os
    import shutil
    import sys

    pytest.importorskip("mpi4py")
    mpiexec = shutil.which("mpiexec")
    if mpiexec is None:
        pytest.skip("no mpiexec")
    root, _ = sample
    script = tmp_path / "ensemble.py"
    script.write_text(
        "import ballast\nfrom mpi4py.futures import MPIPoolExecutor\n"
        "if __name__ == '__main__':\n"
        "    with MPIPoolExecutor() as ex:\n"
        f"        r = ballast.ensemble({str(root / 'cli' / 'sample.toml')!r}, replicas=4, out={str(tmp_path / 'mpi')!r},"
        " executor=ex, cycles=4, dt=1e-3, bars=0)\n"
        "    assert r['failed'] == [], r['failed']\n"
    )
    # OpenMPI refuses root unless told (CI runs as root); more ranks than cores on a 2-core machine.
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    args = [mpiexec, "--oversubscribe", "-n", "3", sys.executable, "-m", "mpi4py.futures", str(script)]
    done = subprocess.run(args, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "mpi" / "settlement_ensemble.csv").read_bytes() == reference.read_bytes()


def test_a_table_reads_as_numpy_columns_or_a_pandas_frame(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("cycle,settlement_m,accrued_m,engine\n1,0.5,,nscd\n2,0.25,1e-3,md2d\n")
    t = ballast.table(path)
    assert list(t) == ["cycle", "settlement_m", "accrued_m", "engine"]
    assert t["cycle"].dtype == np.int64 and t["settlement_m"].dtype == np.float64
    assert np.isnan(t["accrued_m"][0]) and t["accrued_m"][1] == 1e-3 and t["engine"] == ["nscd", "md2d"]
    pandas = pytest.importorskip("pandas")
    frame = ballast.table(path, frame=True)
    assert isinstance(frame, pandas.DataFrame) and frame.shape == (2, 4) and frame["settlement_m"].sum() == 0.75
