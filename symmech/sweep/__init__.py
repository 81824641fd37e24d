"""Sweeps: one scene over a grid of parameters and initial states, on every core or a cluster.

``sweep(scene, grid, t_end, ...)`` (:mod:`.api`) runs every row of the grid
(:mod:`.grid`: a dict of arrays, :func:`product` of ranges, or a DataFrame) through the
compiled C loop of :func:`symmech.simulate.simulate` and returns a pandas DataFrame, one row
per run.  The package is callable: ``symmech.sweep(scene, grid, t_end)`` is that function.
Chunks run in local threads or, given a ``dask.distributed.Client``, as Dask tasks
(:mod:`.runner`, :mod:`.worker`); ``store=`` streams finished chunks to a Parquet folder
that a rerun resumes from (:mod:`.store`).  Needs the optional dependencies pandas and
pyarrow (and dask.distributed for a cluster): ``pip install 'symmech[sweep]'``.
"""

import sys
import types
from typing import Any

from symmech.sweep.driver import OUTPUTS, sweep
from symmech.sweep.grid import product

__all__ = ["OUTPUTS", "product", "sweep"]


class _CallablePackage(types.ModuleType):
    """``symmech.sweep(...)`` calls :func:`sweep` (the package and the function share the
    name)."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallablePackage
