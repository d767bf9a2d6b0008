"""GUI timings: ``python -m ursim_gui.bench`` (runs offscreen unless a platform is set).

Measures, on synthetic maps:

1. open + overlay: a 4000x4000 map set in a main window's session, then its
   segmentation (overlay LUT, outlines, graph), each with one frame painted; budget 1 s.
2. hover: highlighting a region's partners in the other view and painting the frame, in
   a main window with a KTH-size pair (1870x924); budget 16 ms.
3. edit: one undoable edit (set a clique's status) with everything it updates (both
   overlays, table, evaluation, marks) and both views painted; budget 16 ms.
4. UI blocking during segmentation and matching in the worker: the longest gap between
   ticks of a 10 ms timer in the GUI thread; budget 100 ms.
5. campaign: on the KTH dataset (when found), "next pair" (D) to the matched, fitted view of
   the next sketch, per pair, after the kernels are compiled; budget 1 s.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
os.environ.setdefault("URSIM_GUI_DATA_DIR", os.path.join(os.path.expanduser("~"), ".cache", "ursim-bench-gui"))

__all__ = ["room_grid_labels", "main"]


def room_grid_labels(rows: int, cols: int, room: int) -> np.ndarray:
    """Label image of square rooms of side ``room`` with 3 px walls and doors between them."""
    labels = np.zeros((rows, cols), np.int32)
    region = 0
    for r0 in range(0, rows - room + 1, room):
        for c0 in range(0, cols - room + 1, room):
            region += 1
            labels[r0 + 3 : r0 + room, c0 + 3 : c0 + room] = region
            labels[r0 + room // 2 - 4 : r0 + room // 2 + 4, c0 : c0 + 3] = region if c0 else 0
    return labels


def _ms(seconds: float) -> str:
    return f"{seconds * 1000:8.1f} ms"


def _paint(view) -> None:
    view.viewport().repaint()


def bench_open(app, data_dir: Path, size: int) -> tuple[float, float]:
    """(map shown, overlay shown) seconds for a size x size map in a main window.

    The segmentation is computed beforehand (the budget starts after segmentation);
    both steps go through the session, the binding and one painted frame.
    """
    from ursim_core.io.maps import map_from_array
    from ursim_core.segmentation import Segmentation
    from ursim_core.segmentation.graph import region_graph
    from ursim_gui.window.main_window import MainWindow

    labels = room_grid_labels(size, size, 100)
    segmentation = Segmentation(labels=labels, graph=region_graph(labels), method="label-image")
    map_ = map_from_array(np.where(labels > 0, 255, 0).astype(np.uint8))
    window = MainWindow(data_dir=data_dir)
    window.resize(1600, 1000)
    window.show()
    app.processEvents()
    start = time.perf_counter()
    window.session.set_map("metric", map_)
    app.processEvents()
    shown = time.perf_counter() - start
    start = time.perf_counter()
    window.session.set_segmentation("metric", segmentation)
    app.processEvents()
    overlay = time.perf_counter() - start
    window.discard_and_close()
    return shown, overlay


def bench_hover_and_edit(app, data_dir) -> tuple[list[float], list[float]]:
    """Hover and edit timings in a real main window on a KTH-size pair (1870x924)."""
    from types import SimpleNamespace

    import cv2

    from ursim_core.io.maps import load_map
    from ursim_core.segmentation import Segmentation
    from ursim_core.segmentation.graph import region_graph
    from ursim_gui.window.main_window import MainWindow

    labels = room_grid_labels(924, 1870, 90)
    segmentation = Segmentation(labels=labels, graph=region_graph(labels), method="label-image")
    window = MainWindow(data_dir=data_dir)
    window.resize(1600, 1000)
    window.show()
    session = window.session
    # The maps from files, as a pair is opened: a map with no file is a drawing, unsaved work that
    # the autosave would write out (once) during the timing.
    picture = Path(data_dir) / "hover_pair.png"
    cv2.imwrite(str(picture), np.where(labels > 0, 255, 0).astype(np.uint8))
    for side in ("sketch", "metric"):
        session.set_map(side, load_map(picture))
        session.set_segmentation(side, segmentation)
    n = int(labels.max())
    session.apply_match(
        SimpleNamespace(pairs=[(i, n + 1 - i) for i in range(1, n + 1)], anchors=[(1, n)], m=0.1, cost=0.0, reason="")
    )
    app.processEvents()
    _sketch, _metric = window.views["sketch"], window.views["metric"]
    hover = []
    for region in range(1, n + 1, 3):
        start = time.perf_counter()
        window.binding.hover("sketch", region)
        app.processEvents()
        hover.append(time.perf_counter() - start)
    edit, model_and_views = [], []
    cliques = [clique.id for clique in session.correspondences.cliques]
    for index in range(20):
        start = time.perf_counter()
        session.set_status(cliques[index], "rejected")
        model_and_views.append(time.perf_counter() - start)
        app.processEvents()  # the next frame: Qt paints the dirty areas
        edit.append(time.perf_counter() - start)
    print(f"  (of which the edit and view updates before painting: median {_ms(statistics.median(model_and_views))})")
    window.discard_and_close()
    return hover, edit


def bench_blocking(app, job) -> tuple[float, float]:
    """Run ``job`` in the worker; return (longest GUI-thread gap, job wall time)."""
    from PySide6.QtCore import QTimer

    from ursim_gui.jobs.runner import JobRunner

    runner = JobRunner()
    ticks: list[float] = []
    timer = QTimer()
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start(10)
    start = time.perf_counter()
    runner.start(job)
    while runner.busy:
        app.processEvents()
        time.sleep(0.001)
    timer.stop()
    runner.shutdown()
    gaps = [b - a for a, b in zip(ticks, ticks[1:])] or [0.0]
    return max(gaps), time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ursim_gui.bench", description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=4000, help="side of the big map (default 4000)")
    parser.add_argument("--pairs", type=int, default=18, help="KTH campaign pairs to walk (default 18)")
    args = parser.parse_args(argv)
    from PySide6.QtWidgets import QApplication

    from ursim_core.io.maps import map_from_array
    from ursim_core.segmentation import segment
    from ursim_gui.model.jobs import MatchJob, SegmentJob

    app = QApplication.instance() or QApplication([])
    import tempfile

    with tempfile.TemporaryDirectory() as data_dir:
        shown, overlay = bench_open(app, Path(data_dir), args.size)
        print(
            f"{args.size}x{args.size} map: show map {_ms(shown)}, then segmentation overlay {_ms(overlay)}   (budget 1000 ms)"
        )
        hover, edit = bench_hover_and_edit(app, Path(data_dir))
    print(
        f"hover highlight 1870x924, median / max: {_ms(statistics.median(hover))} / {_ms(max(hover))}   (budget 16 ms, {len(hover)} regions)"
    )
    print(f"edit (status) + redraw, median / max: {_ms(statistics.median(edit))} / {_ms(max(edit))}   (budget 16 ms)")
    free = room_grid_labels(924, 1870, 150) > 0
    gap, wall = bench_blocking(
        app, SegmentJob(map_from_array(np.where(free, 255, 0).astype(np.uint8)), "robot", side="metric")
    )
    print(f"segmentation in worker: longest UI gap {_ms(gap)} over {wall:.2f} s   (budget 100 ms)")
    seg = segment(free, preset="robot")
    gap, wall = bench_blocking(app, MatchJob(seg, seg))
    print(f"matching in worker    : longest UI gap {_ms(gap)} over {wall:.2f} s   (budget 100 ms)")
    from ursim_core.evaluation.datasets import dataset_root

    root = dataset_root()
    kth = None if root is None else root / "ursim_kth_sketches"
    if kth is None or not kth.is_dir():
        print("campaign next pair: skipped (KTH dataset not found; set $URSIM_DATASETS)")
        return 0
    with tempfile.TemporaryDirectory() as data_dir:
        times, gap = bench_campaign(app, Path(data_dir), kth, args.pairs)
    print(
        f"campaign next pair (KTH, {len(times)} pairs) to matched view, median / max: "
        f"{_ms(statistics.median(times))} / {_ms(max(times))}   (budget 1000 ms); longest UI gap {_ms(gap)}"
    )
    return 0


def bench_campaign(app, data_dir: Path, dataset: Path, pairs: int) -> tuple[list[float], float]:
    """(seconds from "next pair" to its matched view, per pair; UI gap max) on a dataset campaign.

    The first pair (which also segments the metric map) is opened before timing; each
    timed step is the D key's work: save the pair left, open the next sketch, segment
    it and match it in the worker, apply the match and fit the views.
    """
    import tempfile

    from PySide6.QtCore import QEventLoop, QTimer

    from ursim_gui.window.main_window import MainWindow

    window = MainWindow(data_dir=data_dir)
    window.resize(1366, 768)
    window.show()
    window.preferences.set_annotator("bench")
    ready: list[float] = []
    window.campaigns.pair_ready.connect(lambda _index: ready.append(time.perf_counter()))

    def wait_ready(count: int) -> None:
        loop = QEventLoop()
        timer = QTimer()
        timer.timeout.connect(lambda: loop.quit() if len(ready) >= count else None)
        timer.start(1)
        loop.exec()
        timer.stop()

    ticks: list[float] = []
    tick = QTimer()
    tick.timeout.connect(lambda: ticks.append(time.perf_counter()))
    times = []
    with tempfile.TemporaryDirectory() as out:
        window.campaigns.open(dataset, output_dir=Path(out))
        wait_ready(1)
        tick.start(10)
        for step in range(1, min(pairs, len(window.campaigns.campaign.pairs))):
            start = time.perf_counter()
            window.actions["next_pair"].trigger()
            wait_ready(step + 1)
            app.processEvents()
            _paint(window.views["sketch"])
            times.append(time.perf_counter() - start)
        tick.stop()
        window.discard_and_close()
    gap = max((b - a for a, b in zip(ticks, ticks[1:])), default=0.0)
    return times, gap


if __name__ == "__main__":
    raise SystemExit(main())
