"""Batches of designs, for sweeps and fuzzing: one runner, one outcome enum, one results table.

* :mod:`~torus_cad.batch.sweep_file` reads and checks a sweep file (keys, types, budgets);
* :mod:`~torus_cad.batch.designs` turns it into designs (grid, random, Latin hypercube) with ids;
* :mod:`~torus_cad.batch.job` is what a worker does with one design;
* :mod:`~torus_cad.batch.runner` runs designs on a local process pool (time limit, crash
  isolation, workers that die with their parent) or, through :mod:`~torus_cad.batch.cluster`,
  on Dask;
* :mod:`~torus_cad.batch.table` writes the results as CSV and Parquet;
* :mod:`~torus_cad.batch.sweep_run` puts these together for ``torus-cad sweep``.

::

    from torus_cad.batch import load_sweep, run_sweep

    if __name__ == "__main__":          # needed: the worker processes re-import this script
        result = run_sweep(load_sweep("examples/sweep_example.toml"), "sweep_out/example",
        workers=2)
        print(result.summary())
"""

from torus_cad.batch.designs import Design, design_id, generate_designs
from torus_cad.batch.job import DesignTask, run_design
from torus_cad.batch.outcome import DesignResult, Outcome
from torus_cad.batch.runner import BatchError, Interrupted, LocalPool, run_tasks
from torus_cad.batch.sweep_file import SweepMode, SweepSpec, VaryAxis, load_sweep, parse_sweep
from torus_cad.batch.sweep_run import SweepInterrupted, SweepResult, run_sweep

__all__ = [
    "BatchError",
    "Design",
    "DesignResult",
    "DesignTask",
    "Interrupted",
    "LocalPool",
    "Outcome",
    "SweepInterrupted",
    "SweepMode",
    "SweepResult",
    "SweepSpec",
    "VaryAxis",
    "design_id",
    "generate_designs",
    "load_sweep",
    "parse_sweep",
    "run_design",
    "run_sweep",
    "run_tasks",
]
