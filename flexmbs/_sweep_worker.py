"""Set-up of the worker processes of a sweep's ``LocalCluster``: a Dask preload
(``distributed.worker.preload``), run in each worker process as it starts or restarts."""

from __future__ import annotations

import signal
from typing import Any


def dask_setup(worker: Any) -> None:
    """Ignore SIGINT: Ctrl-C at a terminal reaches the whole process group, and a worker would
    print a traceback and finish its case while the sweep is stopping it; the sweep handles
    Ctrl-C and stops its workers itself."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
