"""The values of a correspondence file: :class:`MapRef`, :class:`Clique`, :class:`Correspondences`.

All values are frozen dataclasses; edit them with :func:`dataclasses.replace`
and the ``with_*`` helpers, which makes undo a matter of keeping old values.
Unknown keys of a file live in their ``extra`` dicts, so a re-save writes them back.
"""

from __future__ import annotations

import dataclasses
import math
import operator
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

__all__ = [
    "SOURCES",
    "STATUSES",
    "MapRef",
    "Clique",
    "Correspondences",
    "utc_timestamp",
    "MAP_KEYS",
    "SEGMENTATION_KEYS",
    "CLIQUE_KEYS",
    "TOP_KEYS",
    "MAPS_KEYS",
]

SOURCES = ("manual", "auto")
STATUSES = ("accepted", "rejected", "pending")

_SHA256_PATTERN = re.compile(r"^[0-9a-fA-F]{64}$")

# The keys of the JSON objects each value reads; anything else goes to its ``extra``.
MAP_KEYS = ("path", "sha256", "size", "segmentation")
SEGMENTATION_KEYS = ("method", "params", "labels")
CLIQUE_KEYS = (
    "id",
    "sketch_points",
    "metric_points",
    "sketch_regions",
    "metric_regions",
    "source",
    "score",
    "note",
    "status",
)
TOP_KEYS = ("format", "version", "annotator", "created", "modified", "maps", "cliques")
MAPS_KEYS = ("sketch", "metric")


@dataclass(frozen=True)
class MapRef:
    """Which map (and which segmentation of it) one side of a correspondence file refers to.

    Parameters
    ----------
    path : Path or None
        The map image. Absolute after :func:`load_correspondences`; as written in
        the header after :func:`load_dat`.
    sha256 : str or None
        Hex SHA-256 of the map file, to notice a changed map.
    size : (int, int) or None
        ``(rows, cols)`` of the map image.
    segmentation_method : str or None
        Name of the segmenter whose labels the region ids refer to (e.g. ``"maoris"``).
    segmentation_params : dict
        Its parameters, as given to the segmenter.
    labels_path : Path or None
        A saved label image of that segmentation, if any.
    segmentation_extra : dict
        Unknown keys of the file's ``segmentation`` object, written back unchanged.
    extra : dict
        Unknown keys of the file's map object, written back unchanged.

    Examples
    --------
    >>> ref = MapRef(path="maps/sketch.png", size=(120, 80), segmentation_method="maoris")
    >>> ref.path.name, ref.size
    ('sketch.png', (120, 80))
    """

    # Dict fields are left out of the hash (equality still compares them), so
    # these values can be set members and dictionary keys.
    path: Path | None = None
    sha256: str | None = None
    size: tuple[int, int] | None = None
    segmentation_method: str | None = None
    segmentation_params: dict = field(default_factory=dict, hash=False)
    labels_path: Path | None = None
    segmentation_extra: dict = field(default_factory=dict, hash=False)
    extra: dict = field(default_factory=dict, hash=False)

    def __post_init__(self):
        _set(self, "path", None if self.path is None else Path(self.path))
        _set(self, "labels_path", None if self.labels_path is None else Path(self.labels_path))
        if self.sha256 is not None and not _SHA256_PATTERN.match(str(self.sha256)):
            raise ValueError(f"sha256 must be 64 hexadecimal digits, got {self.sha256!r}")
        if self.size is not None:
            rows, cols = (operator.index(value) for value in self.size)
            if rows < 1 or cols < 1:
                raise ValueError(f"size must be two positive integers (rows, cols), got {self.size!r}")
            _set(self, "size", (rows, cols))
        _set(self, "segmentation_params", dict(self.segmentation_params))
        _set(self, "segmentation_extra", _checked_extra(self.segmentation_extra, SEGMENTATION_KEYS))
        _set(self, "extra", _checked_extra(self.extra, MAP_KEYS))


@dataclass(frozen=True)
class Clique:
    """One correspondence: sketch regions that correspond to metric regions.

    Parameters
    ----------
    id : int
        Identifier >= 1, unique within a :class:`Correspondences`.
    sketch_points, metric_points : tuple of (int, int)
        Clicked ``(row, col)`` points; authoritative.
    sketch_regions, metric_regions : tuple of int
        Region ids (labels >= 1) under the points in the referenced segmentations.
    source : {"manual", "auto"}
        Drawn by a person or proposed by a matcher.
    score : float or None
        Matcher score, if any (lower or higher is better depending on the matcher).
    note : str
        Free text.
    status : {"accepted", "rejected", "pending"} or None
        Review state; None means the default for the source (see :attr:`effective_status`).
    extra : dict
        Unknown keys of the file's clique object, written back unchanged.

    Examples
    --------
    >>> clique = Clique(id=1, sketch_points=[(10, 20)], metric_points=[(5, 7), (6, 9)])
    >>> clique.metric_points
    ((5, 7), (6, 9))
    >>> clique.effective_status
    'accepted'
    """

    id: int
    sketch_points: tuple[tuple[int, int], ...] = ()
    metric_points: tuple[tuple[int, int], ...] = ()
    sketch_regions: tuple[int, ...] = ()
    metric_regions: tuple[int, ...] = ()
    source: str = "manual"
    score: float | None = None
    note: str = ""
    status: str | None = None
    extra: dict = field(default_factory=dict, hash=False)

    def __post_init__(self):
        clique_id = operator.index(self.id)
        if clique_id < 1:
            raise ValueError(f"clique id must be >= 1, got {clique_id}")
        _set(self, "id", clique_id)
        for name in ("sketch_points", "metric_points"):
            _set(self, name, _as_points(getattr(self, name), name))
        for name in ("sketch_regions", "metric_regions"):
            _set(self, name, _as_regions(getattr(self, name), name))
        if self.source not in SOURCES:
            raise ValueError(f"source must be one of {SOURCES}, got {self.source!r}")
        if self.status is not None and self.status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES} or None, got {self.status!r}")
        if self.score is not None:
            score = float(self.score)
            if not math.isfinite(score):
                raise ValueError(f"score must be a finite number or None, got {self.score!r}")
            _set(self, "score", score)
        if not isinstance(self.note, str):
            raise ValueError(f"note must be a string, got {self.note!r}")
        _set(self, "extra", _checked_extra(self.extra, CLIQUE_KEYS))

    @classmethod
    def _from_valid_json(cls, item: dict, extra: dict) -> Clique:
        """A clique from a JSON object the schema validator accepted, without checking it again.

        The codecs' fast path for big files: the schema guarantees what ``__post_init__``
        would check (integers, ranges, enums), so only the normalisation is done here.
        """
        score = item.get("score")
        return cls._trusted(
            id=item["id"],
            sketch_points=tuple(map(tuple, item["sketch_points"])),
            metric_points=tuple(map(tuple, item["metric_points"])),
            sketch_regions=tuple(item.get("sketch_regions", ())),
            metric_regions=tuple(item.get("metric_regions", ())),
            source=item.get("source", "manual"),
            score=None if score is None else float(score),
            note=item.get("note", ""),
            status=item.get("status"),
            extra=extra,
        )

    @classmethod
    def _trusted(cls, **fields) -> Clique:
        """A clique of fields already in their normal form (every field given), unchecked.

        For the codecs, whose parsers enforce the same rules as ``__post_init__``; a frozen
        dataclass keeps its fields in ``__dict__``, so filling it at once skips ten setattr
        calls a clique.
        """
        clique = object.__new__(cls)
        clique.__dict__.update(fields)
        return clique

    @property
    def effective_status(self) -> str:
        """The status, with the default filled in: pending for auto, accepted for manual."""
        if self.status is not None:
            return self.status
        return "pending" if self.source == "auto" else "accepted"

    @property
    def is_reviewed(self) -> bool:
        """True for a clique a person made (manual) or reviewed (accepted or rejected); a pending
        automatic clique is a matcher's proposal, which the next match replaces."""
        return self.source != "auto" or self.status in ("accepted", "rejected")

    @property
    def is_empty(self) -> bool:
        """True when the clique has no point and no region on either side."""
        return not (self.sketch_points or self.metric_points or self.sketch_regions or self.metric_regions)


@dataclass(frozen=True)
class Correspondences:
    """A whole correspondence file: the two maps and the cliques between them.

    Parameters
    ----------
    sketch, metric : MapRef
        The two maps (for .dat files: map1 and map2).
    cliques : tuple of Clique
        In file order; ids are unique.
    annotator : str
        Who made the manual cliques.
    created, modified : str
        ISO-8601 UTC timestamps; empty until first saved.
    extra : dict
        Unknown top-level keys, written back unchanged.
    maps_extra : dict
        Unknown keys of the ``maps`` object (beside ``sketch`` and ``metric``).
    loaded_sha256 : str or None
        SHA-256 of the file this value was loaded from (set by the loaders, never written).
        Pass it as ``expected_sha256`` to the next save to detect that another session
        changed the file meanwhile. Not part of equality.

    Examples
    --------
    >>> corr = Correspondences(cliques=(Clique(id=1), Clique(id=4)))
    >>> corr.next_clique_id()
    5
    >>> [clique.id for clique in corr.with_clique(Clique(id=2)).cliques]
    [1, 4, 2]
    """

    sketch: MapRef = field(default_factory=MapRef)
    metric: MapRef = field(default_factory=MapRef)
    cliques: tuple[Clique, ...] = ()
    annotator: str = ""
    created: str = ""
    modified: str = ""
    extra: dict = field(default_factory=dict, hash=False)
    maps_extra: dict = field(default_factory=dict, hash=False)
    loaded_sha256: str | None = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        cliques = tuple(self.cliques)
        seen: set[int] = set()
        for clique in cliques:
            if not isinstance(clique, Clique):
                raise TypeError(f"cliques must be Clique values, got {type(clique).__name__}")
            if clique.id in seen:
                raise ValueError(f"duplicate clique id {clique.id}")
            seen.add(clique.id)
        _set(self, "cliques", cliques)
        _set(self, "extra", _checked_extra(self.extra, TOP_KEYS))
        _set(self, "maps_extra", _checked_extra(self.maps_extra, MAPS_KEYS))

    def next_clique_id(self) -> int:
        """The smallest id larger than every id in use (1 when there is none)."""
        return max((clique.id for clique in self.cliques), default=0) + 1

    def clique(self, clique_id: int) -> Clique:
        """The clique with this id; KeyError if there is none."""
        for clique in self.cliques:
            if clique.id == clique_id:
                return clique
        raise KeyError(clique_id)

    def with_cliques(self, cliques: Iterable[Clique]) -> Correspondences:
        """A copy with the cliques replaced by ``cliques``."""
        return dataclasses.replace(self, cliques=tuple(cliques))

    def with_clique(self, clique: Clique) -> Correspondences:
        """A copy where ``clique`` replaces the clique with its id, or is appended."""
        cliques = list(self.cliques)
        for index, existing in enumerate(cliques):
            if existing.id == clique.id:
                cliques[index] = clique
                break
        else:
            cliques.append(clique)
        return self.with_cliques(cliques)

    def without_clique(self, clique_id: int) -> Correspondences:
        """A copy without the clique with this id; KeyError if there is none."""
        self.clique(clique_id)
        return self.with_cliques(clique for clique in self.cliques if clique.id != clique_id)


def _set(instance: Any, name: str, value: Any) -> None:
    # Normalising fields of a frozen dataclass in __post_init__.
    object.__setattr__(instance, name, value)


def _checked_extra(extra: Mapping, known: Sequence[str]) -> dict:
    extra = dict(extra)
    clashes = sorted(key for key in extra if key in known)
    if clashes:
        raise ValueError(f"extra keys {clashes} clash with known fields; set the fields instead")
    for key in extra:
        if not isinstance(key, str):
            raise ValueError(f"extra keys must be strings, got {key!r}")
    return extra


def _as_points(points: Iterable, name: str) -> tuple[tuple[int, int], ...]:
    result = []
    for point in points:
        coordinates = tuple(point)
        if len(coordinates) != 2:
            raise ValueError(f"{name}: a point is (row, col), got {point!r}")
        row, col = (operator.index(value) for value in coordinates)
        if row < 0 or col < 0:
            raise ValueError(f"{name}: point coordinates must be >= 0, got {point!r}")
        result.append((row, col))
    return tuple(result)


def _as_regions(regions: Iterable, name: str) -> tuple[int, ...]:
    result = tuple(operator.index(region) for region in regions)
    if any(region < 1 for region in result):
        raise ValueError(f"{name}: region ids are labels >= 1, got {result!r}")
    return result


def utc_timestamp(moment: datetime | None = None) -> str:
    """ISO-8601 UTC timestamp with second precision, e.g. ``2024-05-01T12:00:00Z``.

    Examples
    --------
    >>> utc_timestamp(datetime(2024, 5, 1, 12, 0, tzinfo=UTC))
    '2024-05-01T12:00:00Z'
    """
    moment = datetime.now(UTC) if moment is None else moment.astimezone(UTC)
    return moment.strftime("%Y-%m-%dT%H:%M:%SZ")
