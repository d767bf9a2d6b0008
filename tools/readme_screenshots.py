"""Render the README screenshots of the real main window (offscreen).

    QT_QPA_PLATFORM=offscreen .venv/bin/python tools/readme_screenshots.py

Writes docs/images/example_matched.png (the bundled pair, segmented, matched and scored
against its ground truth) and docs/images/correction.png (a review in progress: wrong automatic
matches rejected, the first ones accepted, the next one selected).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtWidgets import QApplication

from ursim_gui.app import EXAMPLE_DIR
from ursim_gui.window.main_window import MainWindow

OUT = Path(__file__).resolve().parent.parent / "docs" / "images"


def main() -> int:
    app = QApplication.instance() or QApplication(sys.argv)
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as data_dir:
        window = MainWindow(Path(data_dir))
        window.resize(1680, 1000)
        window.show()
        if not window.open_inputs(example=True, wait=True):
            print("could not open the example", file=sys.stderr)
            return 1
        window.session.load_reference(EXAMPLE_DIR / "ground_truth.json")
        app.processEvents()
        window.fit_views()
        app.processEvents()
        window.grab().save(str(OUT / "example_matched.png"))

        session = window.session
        cliques = session.correspondences.cliques
        # A review half done: wrong automatic matches rejected, the first ones accepted, the
        # next one selected (its regions outlined in both views and its row highlighted).
        for clique in cliques:
            if session.clique_status(clique.id) == "fp":
                session.set_status(clique.id, "rejected")
        for clique in cliques[:4]:
            session.set_status(clique.id, "accepted")
        session.select_clique(cliques[4].id)
        app.processEvents()
        window.grab().save(str(OUT / "correction.png"))
        window.discard_and_close()
    print(f"wrote {OUT / 'example_matched.png'} and {OUT / 'correction.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
