"""An annotation campaign: the map pairs of a dataset, where each pair's file goes, and its status.

Qt-free. A campaign comes from a dataset folder, a plain folder, or a small JSON manifest
(:func:`open_campaign`); the window walks it pair by pair and saves each pair's
correspondences under the naming rule below, so reopening the campaign restores every
status (read back from the files) and the pair the user was on (the state file).

Sources
-------
- A dataset folder in a layout :func:`ursim_core.evaluation.layouts.discover` knows
  (``ursim_kth_sketches``, the Halmstad robot maps): one pair per experiment, named like it.
- A plain folder of sketches with one metric map: the metric map is the one file named
  ``metric.*`` (else the one named ``model*.*``, as the datasets name their floor plans, else
  the one ROS ``.yaml``); every other image is a sketch.
- A manifest ``*.json``: ``{"metric": PATH, "sketches": [PATH, ...], "annotator": NAME,
  "output": FOLDER, "references": {SKETCH_STEM: PATH}}``; relative paths are relative to
  the manifest; only ``metric`` and ``sketches`` are required.

Naming rule
-----------
Pair ``NAME``'s correspondences are ``<output>/NAME.json`` and the campaign state
(position) is ``<output>/campaign.json``. ``<output>`` is the manifest's ``output``, else
``<source folder>/ursim_annotations/<annotator>`` (``annotator`` = "anonymous" when the
name is empty), else, when that folder cannot be written (a read-only dataset), the same
path under the user data folder: ``<data>/campaigns/<source folder name>/<annotator>``.

Statuses
--------
Read from a pair's file: "not started" (no file), "automatic" (only matcher output, none
reviewed), "in review" (some cliques reviewed or edited), "done" (every clique accepted
or rejected). Beside it, how the matcher read the pair's sketch (its file's ``matcher`` record)
and whether that was a close call: a campaign's pairs that want an orientation check stand out.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from ursim_core.correspondences import Correspondences, load_correspondences
from ursim_core.errors import FormatError, UrsimError, file_not_found
from ursim_core.io.atomic import atomic_write_bytes

__all__ = [
    "PAIR_STATUSES",
    "STATE_FILE",
    "CampaignPair",
    "Campaign",
    "open_campaign",
    "status_of",
    "PairSummary",
    "pair_summary",
    "summary_of",
    "reading_of",
]

PAIR_STATUSES = ("not started", "automatic", "in review", "done")
STATE_FILE = "campaign.json"
_IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".pgm", ".tif", ".tiff", ".bmp"}


@dataclass(frozen=True)
class CampaignPair:
    """One sketch / metric pair of a campaign and the file its correspondences go to."""

    name: str
    sketch: Path
    metric: Path
    output: Path
    reference: Path | None = None
    #: What the input map is, when the source says so (``MatchConfig.input_kind``): 'metric' for
    #: the Halmstad robot maps, so that the automatic matcher overlays them as ``ursim evaluate``
    #: does; None = unknown.
    input_kind: str | None = None


@dataclass
class Campaign:
    """The pairs, the annotator, the output folder and the current position."""

    name: str
    source: Path
    pairs: tuple[CampaignPair, ...]
    output_dir: Path
    annotator: str = ""
    current: int = 0
    #: Other annotators' ground truth per pair name (annotator -> file), when the source has it.
    ground_truth: dict[str, dict[str, Path]] = field(default_factory=dict)

    @property
    def state_path(self) -> Path:
        return self.output_dir / STATE_FILE

    def statuses(self) -> list[str]:
        """Status of every pair, read from its file."""
        return [status_of(pair.output) for pair in self.pairs]

    def index_of(self, name: str) -> int:
        return next(index for index, pair in enumerate(self.pairs) if pair.name == name)

    def save_state(self) -> None:
        """Write the position (atomically); the statuses live in the pairs' files."""
        self.output_dir.mkdir(parents=True, exist_ok=True)
        state = {"source": str(self.source), "annotator": self.annotator, "current": self.pairs[self.current].name}
        atomic_write_bytes(self.state_path, (json.dumps(state, indent=2) + "\n").encode("utf-8"))

    def _load_state(self) -> None:
        try:
            state = json.loads(self.state_path.read_text(encoding="utf-8"))
            self.current = self.index_of(str(state["current"]))
        except (OSError, ValueError, KeyError, TypeError, StopIteration):
            self.current = 0  # no state yet, or one that names no pair: start at the top


def status_of(path: Path) -> str:
    """A pair's status from its correspondence file (see the module docstring)."""
    return pair_summary(path).status


class PairSummary(NamedTuple):
    """What the campaign list shows of a pair: its status, its cliques and how many are reviewed,
    how the matcher read its sketch ("" when it was told, or the file does not say) and whether
    the reading it ranked next came close (:func:`reading_of`)."""

    status: str
    cliques: int = 0
    reviewed: int = 0
    reading: str = ""
    close_call: bool = False


def pair_summary(path: Path) -> PairSummary:
    """The :class:`PairSummary` of a pair's correspondence file."""
    if not path.is_file():
        return PairSummary("not started")
    try:
        corr = load_correspondences(path)
    except UrsimError:
        return PairSummary("in review")  # a file the user must look at
    return summary_of(corr)


def summary_of(corr: Correspondences) -> PairSummary:
    """The :class:`PairSummary` of a correspondence value."""
    cliques = corr.cliques
    reviewed = sum(clique.status is not None for clique in cliques)
    if not cliques and "matcher" not in corr.extra:
        # Not matched yet (the pair just opened, its match queued): nothing to review.
        status = "not started"
    elif cliques and reviewed == len(cliques):
        status = "done"
    elif all(clique.source == "auto" and clique.status is None and not clique.note for clique in cliques):
        status = "automatic"
    else:
        status = "in review"
    return PairSummary(status, len(cliques), reviewed, *reading_of(corr.extra.get("matcher")))


def reading_of(record) -> tuple[str, bool]:
    """How a file's ``matcher`` record says the matcher read the sketch, in words with the gap to
    the reading it ranked next, and whether that gap makes it a close call
    (``ursim_core.matching.orientation.CLOSE_READING``); ``("", False)`` when the record does not
    say (the orientation was told, or no match made the file).

    Examples
    --------
    >>> record = {"config": {"orientation": "any"}, "orientation": {"degrees": 180.0, "mirrored": False},
    ...           "next_reading": {"degrees": 0.0, "mirrored": True, "ranked_worse_by": 0.004}}
    >>> reading_of(record)
    ('turned 180° · next ranked 0.4% worse', True)
    >>> reading_of({"config": {"orientation": 90.0}}), reading_of(None)
    (('', False), ('', False))
    """
    from ursim_core.matching.orientation import CLOSE_READING, describe_gap
    from ursim_gui.model.orientation import SketchOrientation

    found = SketchOrientation.found_in_record(record)
    if found is None:
        return "", False
    # Short, for a column: the panel's words without "counter-clockwise".
    words = found.describe().replace(" counter-clockwise", "")
    runner_up = SketchOrientation.runner_up_in(record=record)
    if runner_up is None:
        return words, False
    gap = runner_up[1]
    return f"{words} · next {describe_gap(gap, hint=False)}", gap < CLOSE_READING


def open_campaign(
    source: str | os.PathLike,
    *,
    annotator: str = "",
    output_dir: str | os.PathLike | None = None,
    data_dir: str | os.PathLike | None = None,
) -> Campaign:
    """Read a campaign from a dataset folder, a plain folder or a JSON manifest.

    Parameters
    ----------
    source : path
        Folder or ``*.json`` manifest (see the module docstring).
    annotator : str, keyword-only
        Whose annotations these are (names the output folder).
    output_dir : path, keyword-only
        Where the pairs' files go; overrides the naming rule's folder.
    data_dir : path, keyword-only
        The app's user data folder, the fallback for a read-only source.

    Raises
    ------
    UrsimError
        The source is not a campaign: the message names it and what is missing.
    """
    source = Path(source).expanduser().absolute()
    manifest: dict = {}
    if source.is_file():
        manifest = _read_manifest(source)
        annotator = annotator or str(manifest.get("annotator", ""))
        folder = source.parent
        pairs_in = _manifest_pairs(source, manifest)
        name = source.stem
    elif source.is_dir():
        folder = source
        pairs_in = _folder_pairs(source)
        name = source.name
    elif not os.path.lexists(source):
        raise file_not_found(
            FormatError,
            "campaign not found: give a dataset folder, a folder of sketches or a manifest .json",
            path=source,
        )
    else:
        raise FormatError(
            "not a campaign: give a dataset folder, a folder of sketches or a manifest .json", path=source
        )
    if output_dir is None and manifest.get("output"):
        output_dir = (folder / str(manifest["output"])).absolute()
    if output_dir is None:
        output_dir = _default_output(folder, annotator, data_dir)
    output_dir = Path(output_dir)
    pairs = tuple(
        CampaignPair(
            name=pair_name,
            sketch=sketch,
            metric=metric,
            output=output_dir / f"{pair_name}.json",
            reference=ref,
            input_kind=kind,
        )
        for pair_name, sketch, metric, ref, _gt, kind in pairs_in
    )
    if not pairs:
        raise FormatError("the campaign has no map pairs", path=source)
    campaign = Campaign(
        name=name,
        source=source,
        pairs=pairs,
        output_dir=output_dir,
        annotator=annotator,
        ground_truth={pair_name: gt for pair_name, _s, _m, _r, gt, _k in pairs_in if gt},
    )
    campaign._load_state()
    return campaign


def _annotator_folder(annotator: str) -> str:
    cleaned = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in annotator.strip())
    return cleaned or "anonymous"


def _default_output(folder: Path, annotator: str, data_dir) -> Path:
    beside = folder / "ursim_annotations" / _annotator_folder(annotator)
    if _writable(beside):
        return beside
    if data_dir is None:
        from ursim_gui.model.autosave import default_autosave_folder

        data_dir = default_autosave_folder().parent
    return Path(data_dir) / "campaigns" / folder.name / _annotator_folder(annotator)


def _writable(folder: Path) -> bool:
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            return False
        probe = probe.parent
    return probe.is_dir() and os.access(probe, os.W_OK | os.X_OK)


#: Far above any campaign's manifest (a path per sketch), far below what would hurt to read.
MAX_MANIFEST_BYTES = 16 * 1024**2


def _read_manifest(path: Path) -> dict:
    from ursim_core.io.reading import read_json_file

    # The project's guarded reader: a named pipe does not hang the app, deep nesting or a
    # repeated key is a FormatError naming the file.
    data = read_json_file(path, max_bytes=MAX_MANIFEST_BYTES, error=FormatError, what="campaign manifest")
    if (
        not isinstance(data, dict)
        or not isinstance(data.get("metric"), str)
        or not isinstance(data.get("sketches"), list)
    ):
        raise FormatError('a campaign manifest needs "metric" (a path) and "sketches" (a list of paths)', path=path)
    return data


def _manifest_pairs(path: Path, manifest: dict):
    folder = path.parent
    metric = (folder / manifest["metric"]).absolute()
    references = manifest.get("references") or {}
    pairs, seen = [], set()
    for entry in manifest["sketches"]:
        if not isinstance(entry, str):
            raise FormatError('every entry of "sketches" must be a path', path=path, field="sketches")
        sketch = (folder / entry).absolute()
        name = _unique(sketch.stem, seen)
        ref = references.get(sketch.stem) if isinstance(references, dict) else None
        pairs.append((name, sketch, metric, (folder / ref).absolute() if isinstance(ref, str) else None, {}, None))
    return pairs


def _folder_pairs(folder: Path):
    from ursim_core.evaluation.layouts import discover

    try:
        experiments = discover(folder)
    except UrsimError:
        experiments = None
    if experiments:
        pairs, seen = [], set()
        for experiment in experiments:
            name = _unique(experiment.name, seen)
            pairs.append(
                (name, experiment.sketch, experiment.metric, None, dict(experiment.ground_truth), experiment.input_kind)
            )
        return pairs
    files = sorted(
        p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in _IMAGE_SUFFIXES | {".yaml", ".yml"}
    )
    # The datasets name their floor plan model*.png (the Halmstad KT folder: model_simple.png).
    metrics = (
        [p for p in files if p.stem.lower() == "metric"]
        or [p for p in files if p.stem.lower().startswith("model")]
        or [p for p in files if p.suffix.lower() in (".yaml", ".yml")]
    )
    if len(metrics) != 1:
        raise FormatError(
            "not a dataset layout, and not a plain campaign folder: it needs exactly one metric map "
            f"(named metric.* or model*.*, or one ROS .yaml), found {len(metrics)}",
            path=folder,
        )
    metric = metrics[0]
    image_of_yaml = (
        {metric.with_suffix(suffix) for suffix in _IMAGE_SUFFIXES}
        if metric.suffix.lower() in (".yaml", ".yml")
        else set()
    )
    seen: set[str] = set()
    return [
        (_unique(p.stem, seen), p, metric, None, {}, None)
        for p in files
        if p != metric and p not in image_of_yaml and p.suffix.lower() in _IMAGE_SUFFIXES
    ]


def _unique(name: str, seen: set[str]) -> str:
    candidate, index = name, 2
    while candidate in seen:
        candidate, index = f"{name}_{index}", index + 1
    seen.add(candidate)
    return candidate
