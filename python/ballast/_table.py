"""Tables the runs and studies write (CSV) as numpy arrays, or pandas DataFrames."""

from os import PathLike
from typing import Any, Union

from . import _ballast


def table(path: Union[str, "PathLike[str]"], frame: bool = False) -> Any:
    """The CSV table at ``path`` (``series.csv``, ``cycles.csv``, ``settlement.csv``,
    ``settlement_ensemble.csv``, …) as a dict of its columns in order: int64 arrays for integer columns,
    float64 arrays for numbers (empty cells NaN; the units are in the column names: ``_m``, ``_s``, ``_n``, …),
    lists of str otherwise. With ``frame=True``, a pandas DataFrame (pandas must be installed)."""
    columns = _ballast.table(str(path))
    if not frame:
        return columns
    import pandas  # optional: only for frame=True

    return pandas.DataFrame(columns)
