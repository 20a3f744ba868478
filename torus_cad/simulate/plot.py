"""The PNG beside a simulation's report: thrust and torque by iteration above, residuals (log)
below."""

from __future__ import annotations

from pathlib import Path

from torus_cad.parameters.design import Handedness
from torus_cad.simulate.coefficients import thrust_and_torque
from torus_cad.simulate.history import History


def write_history_plot(history: History, handedness: Handedness, path: Path, title: str) -> Path:
    """Write the picture (matplotlib, Agg) to ``path``; return it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    thrust, torque = thrust_and_torque(history.force_n, history.moment_nm, handedness)
    figure, (forces, residuals) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    try:
        forces.plot(history.iterations, thrust, color="tab:blue", label="thrust, N")
        forces.set_ylabel("thrust, N", color="tab:blue")
        twin = forces.twinx()
        twin.plot(history.iterations, torque * 1000.0, color="tab:red", label="torque, N mm")
        twin.set_ylabel("torque, N mm", color="tab:red")
        forces.set_title(title)
        forces.grid(True, alpha=0.3)
        for name, values in history.residuals.items():
            residuals.semilogy(history.residual_iterations[: len(values)], values, label=name)
        residuals.set_xlabel("iteration")
        residuals.set_ylabel("initial residual")
        residuals.grid(True, which="both", alpha=0.3)
        residuals.legend(loc="upper right", ncol=3, fontsize="small")
        figure.tight_layout()
        figure.savefig(path, dpi=100)
    finally:
        plt.close(figure)
    return path
