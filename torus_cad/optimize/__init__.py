"""Design optimisation: optuna searches the design space, the batch runner builds each trial.

* :mod:`~torus_cad.optimize.study_file` reads and checks a study file (vary, objectives,
  constraints);
* :mod:`~torus_cad.optimize.metrics` names the numbers a study can use (build report,
  ``performance.*``);
* :mod:`~torus_cad.optimize.trial_job` is what a worker does with one trial;
* :mod:`~torus_cad.optimize.trial_simulation` runs ``torus-cad simulate`` for ``performance.*``
  metrics;
* :mod:`~torus_cad.optimize.storage` holds the study (SQLite or PostgreSQL), shared by processes;
* :mod:`~torus_cad.optimize.study` runs the trials; :mod:`~torus_cad.optimize.results` writes
  the table, the pictures and the best designs.

::

    from torus_cad.optimize import read_study_file, run_study

    if __name__ == "__main__":          # needed: the worker processes re-import this script
        result = run_study(read_study_file("examples/optimize_light.toml"), "optimize_out/light",
        workers=2)
        print(result.summary())

Needs the ``optimize`` extra (optuna, cmaes, psycopg2-binary): ``pip install -c constraints.txt -e
'.[optimize]'``.
"""

from torus_cad.optimize.study import StudyInterrupted, StudyResult, run_study
from torus_cad.optimize.study_file import StudySpec, parse_study, read_study_file

__all__ = [
    "StudyInterrupted",
    "StudyResult",
    "StudySpec",
    "parse_study",
    "read_study_file",
    "run_study",
]
