"""Sweeps: many runs of one system, each a point of named values, spread over Dask workers.

A sweep is a list of points (`grid`, `zipped` or `latin_hypercube` over `Axis`es) and an
evaluator: a picklable callable that runs one point and returns its report as a flat dict. The
engine knows nothing of what a point means; `cosim.platform.sweep` evaluates scene points and
`SystemPoint` evaluates points of any SSP system.

`run_sweep` runs the points on `dask.distributed` (a `LocalCluster` with one single-threaded worker
process per core by default, or an existing scheduler by address), `workers=0` in this process.
Points are grouped into tasks so that short points do not each pay a task's overhead; a worker
loads each FMU once (cosim.engine.fmi.loaded), not once per point. Nothing is lost: a point that
fails is a row with its message; rows are written as their task ends (a Parquet part file each,
renamed into place whole, and a CSV line each); a sweep started again with the same output skips
the points it has; a task whose worker dies is retried on another worker up to `retries` times
(Dask's `distributed.scheduler.allowed-failures`), after which its points are rows that say so.

In parts: `points` (axes and how points are drawn), `system` (the SSP target, `SystemPoint`),
`table` (the results on disk), `dask_run` (tasks, in this process or on Dask), `file` (the sweep
file, with pluggable targets) and `plot`.
"""

from .dask_run import SweepOutcome, evaluate_task, run_sweep, task_size
from .file import Sweep, Target, load_sweep
from .plot import plot_sweep
from .points import Axis, SweepError, Value, column_name, grid, latin_hypercube, point_key, zipped
from .system import SYSTEM, SystemPoint
from .table import STATISTICS, ResultTable, statistics

__all__ = ["Axis", "ResultTable", "STATISTICS", "SYSTEM", "Sweep", "SweepError", "SweepOutcome", "SystemPoint",
           "Target", "Value", "column_name", "evaluate_task", "grid", "latin_hypercube", "load_sweep", "plot_sweep",
           "point_key", "run_sweep", "statistics", "task_size", "zipped"]
