"""Long computations (segmentation, matching) packaged for a worker thread.

A job holds its inputs and has one method, ``run(progress, cancelled)``. It never
touches the session or any widget: ``ursim_gui.jobs`` runs it in its worker process
and hands the result back to the GUI thread, which calls
``AnnotationSession.set_segmentation`` or ``apply_match``. Keeping the jobs free of
Qt means they are tested like plain functions.

Segmentation is one core call without progress hooks, so its job reports progress and
checks for cancellation *between* its steps. Matching with the automatic m reports each
value of m of its sweep and checks for cancellation between two of them. A cancel
request made during a step takes effect as soon as that step returns, and the result is
then discarded instead of being applied.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

from ursim_gui.model.wording import counted

__all__ = [
    "JobCancelled",
    "SegmentJob",
    "MatchJob",
    "LaidMatch",
    "ProgressCallback",
    "CancelledCallback",
    "COMPILING_NOTE",
    "compiling_note",
]

#: ``progress(fraction, message)`` with ``fraction`` in [0, 1].
ProgressCallback = Callable[[float, str], None]
#: ``cancelled() -> bool``, polled between steps.
CancelledCallback = Callable[[], bool]


class JobCancelled(Exception):
    """Raised by ``run`` when ``cancelled()`` returned True between two steps."""


def _check(cancelled: CancelledCallback, what: str) -> None:
    if cancelled():
        raise JobCancelled(f"{what} cancelled")


#: Shown while the first segmentation of a fresh install compiles the numba kernels, when the
#: core does not say how long that takes.
COMPILING_NOTE = "Compiling the segmentation kernels (first run only)…"


def compiling_note(job) -> str | None:
    """The line to show when ``job`` is a segmentation that will compile the MAORIS kernels.

    The core's own line when it has one (``ursim_core.segmentation.maoris.compile_notice()``,
    the same as the CLI's, with the expected seconds), else :data:`COMPILING_NOTE` when
    ``kernels_cached()`` says they are not built (a few directory listings); None once they
    are, or when the core has neither.
    """
    if not isinstance(job, SegmentJob) or job.method not in ("maoris", "learned"):  # learned runs MAORIS
        return None
    from ursim_core.segmentation import maoris

    notice = getattr(maoris, "compile_notice", None)
    if notice is not None:
        text = notice()
        return None if text is None else text.replace("...", "…")
    cached = getattr(maoris, "kernels_cached", None)
    if cached is None or cached():
        return None
    return COMPILING_NOTE


class SegmentJob:
    """Segment one map into regions.

    Parameters
    ----------
    map : ursim_core.io.maps.Map or ndarray of bool
        The map (or its free-space mask).
    preset : str or None
        Preset name of the method ('sketch', 'robot', ...).
    params : dict, optional
        Single-parameter overrides of the preset.
    method : str, optional
        A key of ``ursim_core.segmentation.SEGMENTERS``.
    side : str, optional
        'sketch' or 'metric': carried along so the code receiving the result knows
        where it belongs; a sketch is segmented in its canonical pose (below).
    canonical : bool, optional
        For ``side='sketch'``: segment in the canonical pose, as ``ursim match`` does (the
        matcher does not assume the sketch's orientation). Default True.

    Examples
    --------
    >>> import numpy as np
    >>> free = np.zeros((60, 130), bool)
    >>> free[5:55, 5:60] = True; free[5:55, 70:125] = True; free[27:33, 60:70] = True
    >>> seg = SegmentJob(free, "default", None).run(lambda f, m: None, lambda: False)
    >>> seg.n_regions
    2
    """

    def __init__(
        self,
        map: Any,
        preset: str | None,
        params: dict[str, Any] | None = None,
        *,
        method: str = "maoris",
        side: str | None = None,
        canonical: bool = True,
    ) -> None:
        self.map = map
        self.preset = preset
        self.params = dict(params or {})
        self.method = method
        self.side = side
        self.canonical = canonical

    @property
    def description(self) -> str:
        """Human-readable name for a status bar ('Segmenting sketch (preset sketch)')."""
        what = f"Segmenting {self.side}" if self.side else "Segmenting"
        return f"{what} (preset {self.preset})" if self.preset else what

    def run(self, progress: ProgressCallback, cancelled: CancelledCallback) -> Any:
        """Return the ``ursim_core.segmentation.Segmentation``.

        Raises
        ------
        JobCancelled
            When ``cancelled()`` is True before or after the segmentation step.
        ursim_core.errors.UrsimError
            For an unknown method, preset or parameter (checked before the long step).
        """
        from ursim_core.segmentation import resolve_params, segment, segment_canonical

        progress(0.0, "checking parameters")
        _check(cancelled, "segmentation")
        # Fail fast on a bad parameter instead of after a long computation.
        resolve_params(self.method, self.preset, self.params)
        _check(cancelled, "segmentation")
        progress(0.05, "segmenting")
        params = dict(self.params or {})
        if self.side == "sketch" and self.canonical and params.pop("canonical", True):
            # As the CLI: a sketch whose orientation the matcher does not assume is segmented in
            # its canonical pose (ursim_core.segmentation.canonical), recorded in its parameters,
            # and in its other resamplings when it is turned onto its wall axes (the planar
            # matcher votes over them: ursim_core.matching.resampling).
            segmentation = segment_canonical(
                self.map, method=self.method, preset=self.preset, params=params, resampled=True
            )
        else:
            segmentation = segment(self.map, method=self.method, preset=self.preset, params=params)
        _check(cancelled, "segmentation")
        progress(1.0, f"{segmentation.n_regions} regions")
        return segmentation


class MatchJob:
    """Match a sketch segmentation to a metric segmentation.

    Parameters
    ----------
    sketch_seg, metric_seg : ursim_core.segmentation.Segmentation
        The two segmented maps.
    config : ursim_core.matching.MatchConfig, optional
        Matching parameters; the core's defaults when None.
    constraints : ursim_core.matching.MatchConstraints, optional
        What the person has reviewed (``AnnotationSession.review_constraints``): the answer
        contains their pairs and avoids the rejected ones.
    laid_sketch : bool, keyword-only
        Also make the match's laid sketch (:func:`~ursim_gui.model.view_state.laid_sketch_of`)
        and return both as a :class:`LaidMatch`: the worker does the laying's flow, not the
        GUI thread that shows it.
    """

    def __init__(
        self,
        sketch_seg: Any,
        metric_seg: Any,
        config: Any = None,
        constraints: Any = None,
        *,
        laid_sketch: bool = False,
    ) -> None:
        self.sketch_seg = sketch_seg
        self.metric_seg = metric_seg
        self.config = config
        self.constraints = constraints
        self.laid_sketch = laid_sketch

    @property
    def description(self) -> str:
        return "Matching sketch to metric map"

    def run(self, progress: ProgressCallback, cancelled: CancelledCallback) -> Any:
        """Return the ``ursim_core.matching.MatchResult``.

        Raises
        ------
        JobCancelled
            When ``cancelled()`` is True before or after the matching step.
        """
        # Imported here: matching pulls in the heavy descriptor code, and the model
        # package must stay cheap to import (and importable while it is absent).
        from ursim_core.matching import MatchConfig, match_prepared, prepare

        progress(0.0, "preparing")
        _check(cancelled, "matching")
        config = self.config if self.config is not None else MatchConfig()
        reached = [0.0]

        def phase(start: float, end: float):
            def report(fraction: float, message: str) -> None:
                # Each matcher run (an m of the sweep, an orientation candidate) is a point
                # to cancel at; the bar never goes back.
                _check(cancelled, "matching")
                reached[0] = max(reached[0], start + (end - start) * min(max(float(fraction), 0.0), 1.0))
                progress(reached[0], message)

            return report

        prepared = prepare(
            self.sketch_seg, self.metric_seg, config, progress=phase(0.0, 0.5), constraints=self.constraints
        )
        _check(cancelled, "matching")
        progress(max(reached[0], 0.05), "matching")
        sweep_progress = phase(max(reached[0], 0.05), 1.0)

        result = match_prepared(prepared, progress=sweep_progress)
        _check(cancelled, "matching")
        if self.laid_sketch:
            from ursim_gui.model.view_state import laid_sketch_of

            laid = laid_sketch_of(result, self.sketch_seg.labels, self.metric_seg.labels)
            progress(1.0, counted(len(result.pairs), "pair"))
            return LaidMatch(result, laid)
        progress(1.0, counted(len(result.pairs), "pair"))
        return result


class LaidMatch(NamedTuple):
    """What :class:`MatchJob` returns with ``laid_sketch=True``: the ``MatchResult`` and its
    laid sketch (None when the match did not lay the sketch)."""

    result: Any
    laid: Any
