"""JobRunner: jobs run off the GUI thread, report progress, can be cancelled, report errors."""

from __future__ import annotations

import threading
import time

from PySide6.QtCore import QThread, QTimer

from ursim_gui.workers import JobRunner


class SlowJob:
    description = "slow job"

    def __init__(self, steps: int = 20, fail: bool = False):
        self.steps, self.fail, self.thread = steps, fail, None

    def run(self, progress, cancelled):
        self.thread = threading.current_thread()
        for step in range(self.steps):
            if cancelled():
                raise RuntimeError("cancelled")
            time.sleep(0.01)
            progress((step + 1) / self.steps, f"step {step + 1}")
        if self.fail:
            raise ValueError("bad input")
        return "done"


def test_job_runs_in_a_worker_and_the_gui_thread_stays_free(qtbot):
    runner = JobRunner()
    ticks, progress = [], []
    timer = QTimer()
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start(5)
    runner.progress.connect(lambda fraction, message: progress.append(fraction))
    job = SlowJob()
    with qtbot.waitSignal(runner.finished, timeout=5000) as blocker:
        assert runner.start(job)
        assert not runner.start(SlowJob())  # one job at a time
    timer.stop()
    assert blocker.args == [job, "done"]
    assert job.thread is not threading.main_thread()
    assert progress[-1] == 1.0 and len(progress) >= 10
    gaps = [b - a for a, b in zip(ticks, ticks[1:])]
    assert len(ticks) > 10 and max(gaps) < 0.1
    assert not runner.busy


def test_cancel_drops_the_result(qtbot):
    runner = JobRunner()
    finished = []
    runner.finished.connect(lambda job, result: finished.append(result))
    runner.start(SlowJob(steps=500))
    qtbot.wait(30)
    with qtbot.waitSignal(runner.cancelled, timeout=5000):
        runner.cancel()
    assert finished == [] and not runner.busy


def test_failure_is_reported_with_its_message(qtbot):
    runner = JobRunner()
    with qtbot.waitSignal(runner.failed, timeout=5000) as blocker:
        runner.start(SlowJob(steps=2, fail=True))
    assert blocker.args[1] == "bad input"
    assert QThread.currentThread() is runner.thread()
