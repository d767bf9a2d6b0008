"""Running an evaluation's segmentations and match tasks on a Dask cluster (``dask.distributed``).

Used by :func:`ursim_core.evaluation.runner.run_evaluation` when given ``scheduler=ADDRESS``.
Each distinct map is segmented once, as a Dask task; the match tasks take those results as
arguments (Dask moves them between workers), so no segmentation is computed twice. The
segmentations also come back to the caller, which maps the ground truth onto them. Results are
those of the local run: the same functions run on the same inputs, only elsewhere.

Needs the optional extra: ``pip install 'ursim-studio[distributed]'``. Start a cluster with
``dask scheduler`` on one machine and ``dask worker tcp://HOST:8786`` on each worker machine
(each with this package installed), then ``ursim evaluate DATASET --scheduler tcp://HOST:8786``.
"""

from __future__ import annotations

from typing import Any

from ursim_core.errors import ParameterError
from ursim_core.evaluation.cache import record_segmentation, segment_job, split_cached
from ursim_core.evaluation.packing import with_unpacked
from ursim_core.evaluation.pool import Progress
from ursim_core.evaluation.results import RunRow
from ursim_core.evaluation.tasks import MatchTask, run_task, sorted_rows

__all__ = ["connect", "segment_all_dask", "run_tasks_dask"]


def connect(scheduler: Any):
    """A ``distributed.Client`` for ``scheduler``: an address (``tcp://host:8786``) or a Client.

    Raises
    ------
    ParameterError
        Dask is not installed, the address is malformed, or the scheduler cannot be reached.
    """
    try:
        from distributed import Client
    except ImportError:
        raise ParameterError(
            "needs Dask: pip install 'ursim-studio[distributed]' (dask[distributed])", field="scheduler"
        ) from None
    if isinstance(scheduler, Client):
        return scheduler
    address = str(scheduler)
    try:
        # Checked before a Client exists: a Client that fails to start is left half made, and
        # its __del__ can deadlock the next Client started in the process (seen with distributed
        # 2026.11: the clean-up waits for the loop lock the starting Client holds).
        _check_address(address)
        return Client(address, timeout="10s")
    except (OSError, TimeoutError) as error:
        raise ParameterError(f"cannot reach the Dask scheduler {address}: {error}", field="scheduler") from None
    except (ValueError, TypeError) as error:
        # 'not a url' (no port), 'http://x:y' (unknown scheme), 'tcp://h:p' (no port number).
        raise ParameterError(
            f"{address!r} is not a Dask scheduler address ({error}); expected e.g. tcp://HOST:8786",
            field="scheduler",
        ) from None


def _check_address(address: str) -> None:
    """Raise ValueError for an address Dask would refuse: an unknown scheme, no host and port."""
    from distributed.comm import get_address_host_port, parse_address
    from distributed.comm.registry import get_backend

    scheme, _ = parse_address(address)
    get_backend(scheme)
    if scheme in ("tcp", "tls", "ws", "wss"):
        get_address_host_port(address)


def _run_task_with(task: MatchTask, sketch, metric, place) -> list[RunRow]:
    return run_task(task, {task.sketch_key: sketch, task.metric_key: metric, task.place_key: place})


def segment_all_dask(client, jobs, reporter: Progress, memory_cache, cache_dir):
    """Segmentations by job key and their futures on the cluster (cached ones are scattered).

    The cluster holds them whole; here a turned sketch's resamplings are kept packed, as in the
    local evaluation (:mod:`ursim_core.evaluation.packing`): the tasks read the futures.
    """
    from distributed import as_completed

    packed: dict[str, Any] = {}
    segmentations, to_run = split_cached(jobs, reporter, memory_cache, cache_dir, packed)
    futures: dict[str, Any] = {
        key: client.scatter(with_unpacked(found, packed.get(key))) for key, found in segmentations.items()
    }
    cached = len(jobs) - len(to_run)
    pending = {client.submit(segment_job, job, key=f"segment-{job.key}", pure=False): job for job in to_run}
    for future in as_completed(pending):
        job = pending[future]
        futures[job.key] = future
        record_segmentation(job, future.result(), segmentations, reporter, memory_cache, cache_dir, packed)
    return segmentations, futures, cached


def run_tasks_dask(client, tasks: list[MatchTask], futures: dict[str, Any], reporter: Progress) -> list[RunRow]:
    """Every match task as a Dask task on the segmentation futures; rows in the local run's order."""
    from distributed import as_completed

    pending = {
        client.submit(
            _run_task_with,
            task,
            futures[task.sketch_key],
            futures[task.metric_key],
            futures[task.place_key],
            pure=False,
        ): task
        for task in tasks
    }
    rows: list[RunRow] = []
    try:
        for future in as_completed(pending):
            task = pending[future]
            rows.extend(future.result())
            turned = f" {task.augment}" if task.augment else ""
            reporter.step(f"match {task.name}{turned} {task.matcher} {task.variant}")
    except BaseException:
        client.cancel(list(pending))
        raise
    return sorted_rows(tasks, rows)
