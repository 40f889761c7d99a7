"""The examples of python/examples/ and the notebook cell of the README run as a user runs them."""

import os
import re
import subprocess
import sys

import pytest

from test_simulation import ROOT

EXAMPLES = ROOT / "python" / "examples"


@pytest.mark.parametrize("script", sorted(p.name for p in EXAMPLES.glob("*.py")))
def test_every_example_runs(script, tmp_path):
    pytest.importorskip("matplotlib")
    if script == "dask_ensemble.py":
        pytest.importorskip("distributed")
    env = {**os.environ, "MPLBACKEND": "Agg"}
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / script), str(tmp_path / "out")], env=env, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    if script != "contacts_from_arrays.py":
        assert list((tmp_path / "out").glob("*.png")), "the figure is written"


def test_the_readme_notebook_cell_runs_and_plots(tmp_path):
    """The five-line cell of README's "Use from Python", run in a fresh folder (its `out/` relative there)."""
    pytest.importorskip("matplotlib")
    readme = (ROOT / "README.md").read_text()
    cell = re.search(r"<!-- notebook cell -->\s*```python\n(.*?)```", readme, re.S).group(1)
    assert len(cell.strip().splitlines()) == 5, cell
    script = "import matplotlib\nmatplotlib.use('Agg')\n" + cell + "\nplt.savefig('settlement.png')\n"
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "settlement.png").stat().st_size > 1000


def test_the_readme_api_block_runs(tmp_path):
    """The "A simulation" block of README's "Use from Python", its scene read from the repository and its
    outputs written in a fresh folder."""
    readme = (ROOT / "README.md").read_text()
    block = re.search(r"<!-- python api -->\s*```python\n(.*?)```", readme, re.S).group(1)
    script = "import ballast\n" + block.replace('"examples/', f'"{ROOT}/examples/')
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out" / "run" / "final.json").is_file()
    assert (tmp_path / "out" / "settle" / "settlement.csv").is_file()


def test_the_readme_first_python_line_runs():
    """The `python -c` line after `pip install ./python` in README's "Use from Python", from the repository's
    root as a new user runs it."""
    readme = (ROOT / "README.md").read_text()
    line = re.search(r'^python -c "(.*)"$', readme.split("## Use from Python")[1], re.M).group(1)
    done = subprocess.run([sys.executable, "-c", line], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "(727, 3)"
