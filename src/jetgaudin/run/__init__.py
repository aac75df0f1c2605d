"""The run layer: one driver for every map (orbit = a batch of one, ensemble, flow), streamed to a run directory
with durable checkpoints, resumable bit for bit, one writer per directory (``docs/architecture.md``,
``docs/reliability.md``).

>>> import tempfile, numpy as np, jetgaudin as jg
>>> from jetgaudin.run import RunSpec, start, load
>>> spec = RunSpec(jg.TwoPointBacklund(1.0, 5 + 0.1j), np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1, 0, 0]), 20)
>>> with tempfile.TemporaryDirectory() as d:
...     res = start(spec, d + "/run")
...     data = load(d + "/run")
>>> res.status, data.X.shape
('completed', (21, 9))
"""

from .api import RunResult, resume, start
from .driver import RunInterrupted
from .files import ENSEMBLE_H5, ORBIT_CSV, ORBIT_H5, RUN_JSON, read_csv, read_run
from .load import RunData, load
from .spec import DEFAULT_MAX_DRIFT, DEFAULT_MAX_IMAG, HealthLimits, Layout, RunSpec, RunStatus, integral_names

__all__ = [
    "DEFAULT_MAX_DRIFT",
    "DEFAULT_MAX_IMAG",
    "ENSEMBLE_H5",
    "HealthLimits",
    "Layout",
    "ORBIT_CSV",
    "ORBIT_H5",
    "RUN_JSON",
    "RunData",
    "RunInterrupted",
    "RunResult",
    "RunSpec",
    "RunStatus",
    "integral_names",
    "load",
    "read_csv",
    "read_run",
    "resume",
    "start",
]
