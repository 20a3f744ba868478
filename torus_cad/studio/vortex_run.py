"""One operating point of the vortex solver for the studio, in the solve's process
(torus_cad.studio.performance_card starts it): the numbers and the loading plot ``simulate --solver
vortex`` draws, sent back over a pipe. Runs in the worker process, never in the server: it imports
the solver.
"""

from __future__ import annotations

import multiprocessing.connection

from torus_cad import PropellerParameters
from torus_cad.errors import TorusCadError
from torus_cad.studio.messages import REPORT_KEYS, PerformanceRequest, failures_reported
from torus_cad.vortex.loading_files import write_loading_plot
from torus_cad.vortex.vortex_performance import vortex_performance


def run_vortex(
    request: PerformanceRequest,
    connection: multiprocessing.connection.Connection,
    memory_limit_bytes: int | None = None,
) -> None:
    """Solve ``request`` and send ``("result", id, {"report", "strips", "png"})``, or ``("failed",
    id, reason)`` with the one line of the error (a solve that does not converge raises
    KernelError).

    ``memory_limit_bytes``: the process's memory limit, named when an allocation fails.
    """
    request_id = request.request_id
    with failures_reported(connection, request_id, "the vortex solve", memory_limit_bytes):
        try:
            connection.send(("result", request_id, _solved(request)))
        except TorusCadError as error:
            connection.send(("failed", request_id, str(error)))


def _solved(request: PerformanceRequest) -> dict[str, object]:
    """The report's numbers, the strip count and the loading plot's PNG bytes of ``request``."""
    params = PropellerParameters.from_dict(request.design)
    result = vortex_performance(params, request.rpm, request.airspeed_m_s)
    title = (
        f"loading, {params.name}: {request.rpm:.0f} rpm, "
        f"{request.airspeed_m_s:g} m/s, vortex lattice"
    )
    path = write_loading_plot(
        result.strips, request.out_dir / f"loading_{request.request_id}.png", title
    )
    png = path.read_bytes()
    path.unlink()
    report = {key: result.report[key] for key in REPORT_KEYS}
    return {"report": report, "strips": len(result.strips.s), "png": png}
