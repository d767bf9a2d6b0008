"""The evaluation's process pool: results as they finish, and each worker's share of the CPUs."""

import os

from ursim_core.cpus import THREADS_VARIABLE, usable_cpus
from ursim_core.evaluation.pool import completed


def _threads_told(_item) -> str | None:
    return os.environ.get(THREADS_VARIABLE)


def _usable(_item) -> int:
    return usable_cpus()


def test_each_worker_is_told_its_share_of_the_cpus(monkeypatch):
    monkeypatch.setenv(THREADS_VARIABLE, "4")
    told = dict(completed(_threads_told, [0, 1, 2], workers=2))
    assert set(told.values()) == {"2"}
    assert dict(completed(_usable, [0, 1], workers=2)) == {0: 2, 1: 2}
    # Never less than one.
    assert set(dict(completed(_usable, [0, 1, 2], workers=3)).values()) == {1}
    # The caller's own setting is left alone.
    assert os.environ[THREADS_VARIABLE] == "4"


def test_one_worker_runs_here_with_every_cpu(monkeypatch):
    monkeypatch.delenv(THREADS_VARIABLE, raising=False)
    assert dict(completed(_usable, [0, 1], workers=1)) == {0: usable_cpus(), 1: usable_cpus()}


def test_usable_cpus_reads_a_positive_count_only(monkeypatch):
    monkeypatch.delenv(THREADS_VARIABLE, raising=False)
    machine = usable_cpus()
    for value, expected in (("3", 3), (" 2 ", 2), ("0", machine), ("-1", machine), ("many", machine), ("", machine)):
        monkeypatch.setenv(THREADS_VARIABLE, value)
        assert usable_cpus() == expected


def _an_array(item: int):
    import numpy as np

    return np.full(1000, item)


def test_the_pool_keeps_no_result_it_has_yielded():
    # Each result is the caller's once yielded: the free-angle evaluation's segmentations, all
    # held by their futures until the last, were 9.9 GB in the main process.
    import gc
    import weakref

    earlier = []
    for item, result in completed(_an_array, list(range(6)), workers=2):
        assert int(result[0]) == item
        earlier.append(weakref.ref(result))
        del result
        gc.collect()
        # The one just yielded is still referenced by the suspended generator: one at a time.
        assert all(reference() is None for reference in earlier[:-1])
    assert len(earlier) == 6
