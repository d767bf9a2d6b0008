"""Render the README screenshots of the real main window.

    URSIM_DATASETS=/path/to/datasets .venv/bin/python tools/readme_screenshots.py [--window-size 1600x900]

Runs offscreen unless a platform is set (``QT_QPA_PLATFORM=xcb`` under Xvfb shows the
real window decorations and fonts). Needs the KTH sketches dataset. Writes:

- docs/images/campaign.png: a campaign of the 18 KTH sketches mid-way: six pairs done,
  the seventh in review (wrong automatic matches rejected, the first ones accepted, the
  next one selected and zoomed to).
- docs/images/agreement.png: the agreement view of the same campaign against the
  annotator "malcolm", on pair 03: his file is the reference (the maps mark the cliques
  the two disagree on), and the campaign's table of A vs B and matcher vs each.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtCore import QEventLoop, QTimer
from PySide6.QtWidgets import QApplication

from ursim_core.evaluation.datasets import dataset_root
from ursim_gui.window.main_window import MainWindow

OUT = Path(__file__).resolve().parent.parent / "docs" / "images"


def wait(app, condition, timeout_s: float = 180) -> None:
    loop, timer, deadline = QEventLoop(), QTimer(), QTimer()
    timer.timeout.connect(lambda: loop.quit() if condition() else None)
    deadline.setSingleShot(True)
    deadline.timeout.connect(loop.quit)
    timer.start(20)
    deadline.start(int(timeout_s * 1000))
    loop.exec()
    timer.stop()
    for _ in range(5):
        app.processEvents()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--window-size", default="1600x900", help="WIDTHxHEIGHT of the window (default 1600x900)")
    args = parser.parse_args()
    width, height = (int(v) for v in args.window_size.lower().split("x"))
    root = dataset_root()
    kth = None if root is None else root / "ursim_kth_sketches"
    if kth is None or not kth.is_dir():
        print("the KTH sketches dataset was not found (set $URSIM_DATASETS)", file=sys.stderr)
        return 1
    app = QApplication.instance() or QApplication(sys.argv)
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as data_dir, tempfile.TemporaryDirectory() as out:
        window = MainWindow(Path(data_dir))
        window.preferences.set_annotator("reviewer")
        window.resize(width, height)
        window.show()
        ready: list[int] = []
        window.campaigns.pair_ready.connect(ready.append)
        window.campaigns.open(kth, output_dir=Path(out) / "ursim_annotations" / "reviewer")
        wait(app, lambda: len(ready) >= 1)
        for step in range(6):
            window.actions["accept_all"].trigger()
            window.actions["next_pair"].trigger()
            wait(app, lambda step=step: len(ready) >= step + 2)
        session = window.session
        window.agreement.choose("malcolm")  # his ground truth as the reference: TP / FP marks
        cliques = session.correspondences.cliques
        for clique in cliques:
            if session.clique_status(clique.id) == "fp":
                session.set_status(clique.id, "rejected")
        for clique in cliques[:3]:
            if clique.status is None:
                session.set_status(clique.id, "accepted")
        window.actions["connectors"].setChecked(True)
        window.docks["campaign"].raise_()
        window.docks["evaluation"].raise_()
        pending = [c for c in session.correspondences.cliques if c.status is None]
        if pending:
            session.select_clique(pending[0].id)
        window.fit_views()
        wait(app, lambda: True)
        window.grab().save(str(OUT / "campaign.png"))

        window.agreement.compute()
        wait(app, lambda: bool(window.agreement.rows))
        window.actions["connectors"].setChecked(False)
        # Pair 03, where the two annotators disagree most: its FP / FN marks.
        window.campaigns.go_to(window.campaigns.campaign.index_of("03"))
        wait(app, lambda: session.reference is not None)
        session.clear_selection()
        window.docks["agreement"].raise_()
        window.fit_views()
        wait(app, lambda: True)
        window.grab().save(str(OUT / "agreement.png"))
        window.discard_and_close()
    print(f"wrote {OUT / 'campaign.png'} and {OUT / 'agreement.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
