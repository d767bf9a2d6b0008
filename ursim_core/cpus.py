"""How many CPUs the core's threads may use.

Several steps run parts of their work on threads (the MAORIS kernels' bands, the resamplings of a
turned map). A process pool that already runs one worker per CPU (``ursim evaluate``) tells its
workers their share through ``URSIM_THREADS``, so that the threads inside a worker do not compete
with the other workers.
"""

from __future__ import annotations

import os

__all__ = ["THREADS_VARIABLE", "usable_cpus"]

#: The environment variable that caps :func:`usable_cpus` (a positive integer).
THREADS_VARIABLE = "URSIM_THREADS"


def usable_cpus() -> int:
    """CPUs this process may use: ``URSIM_THREADS`` when it is set to a positive integer, else the
    CPUs it may run on (a container or taskset may allow fewer than the machine has).

    Examples
    --------
    >>> usable_cpus() >= 1
    True
    """
    told = os.environ.get(THREADS_VARIABLE, "").strip()
    if told.isdigit() and int(told) > 0:
        return int(told)
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
