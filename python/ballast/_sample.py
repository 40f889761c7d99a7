"""A sample given to the experiments as a path to a scene file or as a Simulation."""

import os
from typing import Tuple, Union

from ._ballast import Simulation

Sample = Union[str, "os.PathLike[str]", Simulation]


def text_of(sample: Sample) -> Tuple[str, str]:
    """The TOML text of ``sample`` and the name its scenes' notes give it (the path, or ``<simulation>`` for
    the state a Simulation holds)."""
    if isinstance(sample, Simulation):
        return sample.to_toml(), "<simulation>"
    path = os.fspath(sample)
    with open(path, encoding="utf-8") as f:
        return f.read(), path
