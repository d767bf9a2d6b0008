"""Soak test: 1000 random edits, undos and redos against an independent reference model.

The reference model knows nothing of the session's code: a clique is a plain tuple
``(id, ((region, point), ...) sketch, (...) metric, status)``, the history a list of
states with an index. After every step the session's correspondences must equal the
model's state, and undo/redo availability and dirtiness must agree.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ursim_core.correspondences import load_correspondences
from ursim_core.segmentation import Segmentation
from ursim_core.segmentation.graph import region_graph
from ursim_gui.model.session import AnnotationSession

N_STEPS = 1000


def grid_labels(*, room: int, wall: int = 3) -> np.ndarray:
    """3x3 rooms (ids 1..9 in raster order) separated by walls."""
    size = 3 * room + 4 * wall
    labels = np.zeros((size, size), np.int32)
    for index in range(9):
        row, col = divmod(index, 3)
        top, left = wall + row * (room + wall), wall + col * (room + wall)
        labels[top : top + room, left : left + room] = index + 1
    return labels


class ReferenceModel:
    """The session's editing rules, restated with plain tuples."""

    def __init__(self, interiors: dict[str, dict[int, tuple[int, int]]]):
        self.interiors = interiors
        self.states: list[tuple] = [()]
        self.index = 0
        self.saved: tuple | None = None

    @property
    def state(self) -> tuple:
        return self.states[self.index]

    def _push(self, new: tuple) -> None:
        if new == self.state:
            return  # no-op edits make no history entry
        del self.states[self.index + 1 :]
        self.states.append(new)
        self.index += 1

    def link(self, sketch, metric, into):
        entries = {
            side: tuple((region, self.interiors[side][region]) for region in dict.fromkeys(regions))
            for side, regions in (("sketch", sketch), ("metric", metric))
        }
        cliques = list(self.state)
        if into is None:
            new_id = max((clique[0] for clique in cliques), default=0) + 1
            cliques.append((new_id, entries["sketch"], entries["metric"], None))
        else:
            position = next(i for i, clique in enumerate(cliques) if clique[0] == into)
            clique_id, old_sketch, old_metric, status = cliques[position]
            grown = []
            for old, new in ((old_sketch, entries["sketch"]), (old_metric, entries["metric"])):
                present = {region for region, _ in old}
                grown.append(old + tuple(entry for entry in new if entry[0] not in present))
            cliques[position] = (clique_id, grown[0], grown[1], status)
        self._push(tuple(cliques))

    def unlink(self, side, region):
        cliques = []
        for clique_id, sketch, metric, status in self.state:
            if side == "sketch":
                sketch = tuple(entry for entry in sketch if entry[0] != region)
            else:
                metric = tuple(entry for entry in metric if entry[0] != region)
            if sketch or metric:
                cliques.append((clique_id, sketch, metric, status))
        self._push(tuple(cliques))

    def set_status(self, clique_id, status):
        self._push(tuple((c[0], c[1], c[2], status) if c[0] == clique_id else c for c in self.state))

    def delete(self, clique_id):
        self._push(tuple(c for c in self.state if c[0] != clique_id))

    def undo(self):
        self.index = max(self.index - 1, 0)

    def redo(self):
        self.index = min(self.index + 1, len(self.states) - 1)

    def save(self):
        self.saved = self.state

    @property
    def dirty(self) -> bool:
        if self.saved is None:
            # Untitled: dirty exactly when there is something to lose.
            return bool(self.state)
        return self.state != self.saved


def as_model_state(session: AnnotationSession) -> tuple:
    cliques = []
    for clique in session.correspondences.cliques:
        assert len(clique.sketch_regions) == len(clique.sketch_points)
        assert len(clique.metric_regions) == len(clique.metric_points)
        assert clique.source == "manual"
        cliques.append(
            (
                clique.id,
                tuple(zip(clique.sketch_regions, clique.sketch_points)),
                tuple(zip(clique.metric_regions, clique.metric_points)),
                clique.status,
            )
        )
    return tuple(cliques)


OPERATIONS = ("link", "link_into", "unlink", "accept", "reject", "pending", "delete", "undo", "redo", "save")
WEIGHTS = np.array([20, 6, 12, 6, 6, 3, 8, 20, 14, 2], float)


@pytest.mark.parametrize("seed", [20240501, 7])
def test_random_edits_match_an_independent_replay(seed, tmp_path):
    sketch_labels, metric_labels = grid_labels(room=18), grid_labels(room=27)
    session = AnnotationSession(timestamp=lambda: "2024-05-01T12:00:00Z")
    interiors = {}
    for side, labels in (("sketch", sketch_labels), ("metric", metric_labels)):
        segmentation = Segmentation(labels=labels, graph=region_graph(labels), method="label-image")
        # From a file, as the app opens maps (a map with no file is a drawing: unsaved work).
        cv2.imwrite(str(tmp_path / f"{side}.png"), np.where(labels > 0, 255, 0).astype(np.uint8))
        session.load_map(side, tmp_path / f"{side}.png")
        session.set_segmentation(side, segmentation)
        interiors[side] = {region: segmentation.graph.nodes[region]["interior"] for region in segmentation.graph}
    model = ReferenceModel(interiors)
    rng = np.random.default_rng(seed)
    regions = np.arange(1, 10)
    history_events = []
    session.history_changed.connect(lambda: history_events.append(1))
    counts = dict.fromkeys(OPERATIONS, 0)

    for step in range(N_STEPS):
        operation = OPERATIONS[rng.choice(len(OPERATIONS), p=WEIGHTS / WEIGHTS.sum())]
        ids = [clique[0] for clique in model.state]
        if operation in ("link_into", "accept", "reject", "pending", "delete") and not ids:
            operation = "link"
        if operation in ("link", "link_into"):
            sketch = [int(r) for r in rng.choice(regions, size=rng.integers(0, 3))]
            metric = [int(r) for r in rng.choice(regions, size=rng.integers(0 if sketch else 1, 3))]
            into = int(rng.choice(ids)) if operation == "link_into" else None
            session.link(sketch, metric, into=into)
            model.link(sketch, metric, into)
        elif operation == "unlink":
            side, region = ("sketch", "metric")[int(rng.integers(2))], int(rng.choice(regions))
            session.unlink(side, region)
            model.unlink(side, region)
        elif operation in ("accept", "reject", "pending"):
            status = {"accept": "accepted", "reject": "rejected", "pending": "pending"}[operation]
            clique_id = int(rng.choice(ids))
            session.set_status(clique_id, status)
            model.set_status(clique_id, status)
        elif operation == "delete":
            clique_id = int(rng.choice(ids))
            session.delete_clique(clique_id)
            model.delete(clique_id)
        elif operation == "undo":
            session.undo()
            model.undo()
        elif operation == "redo":
            session.redo()
            model.redo()
        else:
            session.save(tmp_path / "soak.json")
            model.save()
        counts[operation] += 1

        assert as_model_state(session) == model.state, f"step {step}: {operation}"
        assert session.can_undo == (model.index > 0), f"step {step}: {operation}"
        assert session.can_redo == (model.index < len(model.states) - 1), f"step {step}: {operation}"
        assert session.dirty == model.dirty, f"step {step}: {operation}"
        # One history entry per edit that changes something, none otherwise.
        assert len(session.history) == len(model.states) - 1, f"step {step}: {operation}"
        assert session.history.index == model.index, f"step {step}: {operation}"

    # Every operation kind really ran, and the history was exercised in both directions.
    assert all(counts[name] > 0 for name in OPERATIONS), counts
    assert history_events, "history_changed never fired"

    session.save(tmp_path / "final.json")
    assert load_correspondences(tmp_path / "final.json") == session.correspondences
    reopened = AnnotationSession()
    reopened.restore(load_correspondences(tmp_path / "final.json"), origin=tmp_path / "final.json")
    assert reopened.correspondences == session.correspondences and not reopened.dirty
