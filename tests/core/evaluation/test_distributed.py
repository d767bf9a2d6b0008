"""An evaluation on a Dask cluster (ursim_core.evaluation.distributed) gives the CSV of the local run (2 workers)."""

from __future__ import annotations

import pytest

distributed = pytest.importorskip("distributed", reason="the 'distributed' extra (dask[distributed]) is not installed")

from ursim_core.errors import ParameterError  # noqa: E402
from ursim_core.evaluation.packing import Packed  # noqa: E402
from ursim_core.evaluation.report import runs_csv  # noqa: E402
from ursim_core.evaluation.runner import run_evaluation  # noqa: E402

GRID = (0.0, 0.1, 0.2)


def _without_times(csv_text: str) -> list[list[str]]:
    rows = [line.split(",") for line in csv_text.splitlines()]
    column = rows[0].index("time_s")
    return [row[:column] + row[column + 1 :] for row in rows]


@pytest.mark.slow
def test_local_cluster_gives_the_local_csv(synthetic_dataset, tmp_path):
    options = dict(
        matchers=["planar", "hungarian"],
        variants=["T4", "T2"],
        m_grid=GRID,
        preset="robot",
        metric_preset="robot",
        augment="angles=90,33",
    )
    local = run_evaluation(synthetic_dataset, workers=1, **options)
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        cache: dict = {}
        on_cluster = run_evaluation(synthetic_dataset, scheduler=client, segmentation_cache=cache, **options)
        # Each distinct map was segmented once, as one task.
        segment_tasks = [key for key in client.run_on_scheduler(_task_keys) if str(key).startswith("segment-")]
        # Again from the memory cache, which holds the turned sketches with their resamplings
        # packed: they are scattered to the cluster whole.
        assert any(isinstance(found, Packed) and found.resamplings for found in cache.values())
        again = run_evaluation(synthetic_dataset, scheduler=client, segmentation_cache=cache, **options)
    assert _without_times(runs_csv(on_cluster)) == _without_times(runs_csv(local))
    assert _without_times(runs_csv(again)) == _without_times(runs_csv(local))
    assert again.timings["maps_from_cache"] == again.timings["maps"]
    assert on_cluster.timings["maps"] == local.timings["maps"] == len(set(segment_tasks))
    assert on_cluster.settings["scheduler"].startswith("tcp://")


def _task_keys(dask_scheduler=None):
    # Every key the scheduler saw: a finished task whose future was released is no longer in
    # ``tasks`` (how many are left depends on timing), but its transitions stay in the log.
    seen = {str(entry[0]) for entry in dask_scheduler.transition_log}
    return sorted(seen | {str(key) for key in dask_scheduler.tasks})


def test_unreachable_scheduler_is_a_parameter_error(synthetic_dataset):
    with pytest.raises(ParameterError, match="cannot reach the Dask scheduler"):
        run_evaluation(synthetic_dataset, matchers=["planar"], variants=["T4"], scheduler="tcp://127.0.0.1:9")
