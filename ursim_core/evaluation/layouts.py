"""Finding the map pairs and their ground-truth correspondences in a dataset folder.

Two layouts are recognised, the ones the URSIM authors published (see the READMEs of
``../shared/datasets``):

``kth`` (sketch maps against one metric model)::

    <dataset>/sketches/NN.png
    <dataset>/model/model_simple.png
    <dataset>/gt_correspondences/<annotator>/gt_NN_model_simple.dat

    Every annotator matched the same sketch onto the same model, so one experiment carries the
    ground truth of every annotator (which is what makes a human-vs-human comparison possible).

``halmstad`` (robot maps against a robot map chosen as model, per annotator)::

    <dataset>/E5_NN.png
    <dataset>/GT/<Annotator>/model_simple.png
    <dataset>/GT/<Annotator>/gt_E5_NN_model_simple.dat

    Each annotator picked a different model (Malcolm: E5_08, Vasiliki: E5_10), so an experiment
    is one (map, model, annotator) triple. The folder that contains such dataset folders (e.g.
    ``ursim_halmstad_robot_maps`` with ``E5/``) is accepted too.

Annotator names are lower-cased so both layouts report ``malcolm`` and ``vasiliki``. A file
``gt_<model>_<model>.dat`` (the model matched onto itself) is not an experiment and is skipped.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ursim_core.errors import FormatError, ParameterError

__all__ = ["Experiment", "discover", "LAYOUTS", "IMAGE_SUFFIXES"]

#: Map image file types a dataset may use (compared case-insensitively).
IMAGE_SUFFIXES = (".png", ".pgm", ".ppm", ".bmp", ".jpg", ".jpeg", ".tif", ".tiff")

#: One-line description of each recognised layout, used in error messages.
LAYOUTS = {
    "kth": "sketches/<map>.png + model/<model>.png + gt_correspondences/<annotator>/gt_<map>_<model>.dat",
    "halmstad": "<map>.png + GT/<Annotator>/<model>.png + GT/<Annotator>/gt_<map>_<model>.dat "
    "(or a folder holding such folders, e.g. ursim_halmstad_robot_maps/E5)",
}

_MODEL_STEM = "model_simple"


@dataclass(frozen=True)
class Experiment:
    """One map pair to match, with the ground truth available for it.

    Attributes
    ----------
    name : str
        The input map's name (file stem), e.g. ``'00'`` or ``'E5_01'``.
    sketch : Path
        The input map (``map1`` of the ground-truth files: a sketch or a robot map).
    metric : Path
        The model map (``map2``).
    ground_truth : dict of str to Path
        Annotator name (lower case) to ``.dat`` file, in annotator order.
    layout : str
        ``'kth'`` or ``'halmstad'``.
    dataset : Path
        The dataset folder the experiment was found in.
    input_kind : {'sketch', 'metric'}
        What the input map is: 'metric' for the Halmstad robot maps (the layout holds robot maps
        only), so that the automatic matcher overlays them (``MatchConfig.input_kind``).

    Examples
    --------
    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp()).resolve()  # a Halmstad layout: robot maps against a model
    >>> (root / "GT" / "Malcolm").mkdir(parents=True)
    >>> for name in ("E5_01.png", "GT/Malcolm/model_simple.png", "GT/Malcolm/gt_E5_01_model_simple.dat"):
    ...     _ = (root / name).write_bytes(b"")
    >>> (experiment,) = discover(root)
    >>> experiment.name, experiment.layout, experiment.input_kind, experiment.annotators
    ('E5_01', 'halmstad', 'metric', ('malcolm',))
    >>> experiment.metric.relative_to(root).as_posix(), experiment.ground_truth["malcolm"].name
    ('GT/Malcolm/model_simple.png', 'gt_E5_01_model_simple.dat')
    """

    name: str
    sketch: Path
    metric: Path
    ground_truth: dict[str, Path] = field(default_factory=dict)
    layout: str = "kth"
    dataset: Path | None = None
    input_kind: str = "sketch"

    @property
    def annotators(self) -> tuple[str, ...]:
        return tuple(self.ground_truth)


def discover(dataset_dir: str | Path) -> list[Experiment]:
    """List the experiments (map pairs with ground truth) of a dataset folder.

    Parameters
    ----------
    dataset_dir : str or Path
        A folder in one of the :data:`LAYOUTS`.

    Returns
    -------
    list of Experiment
        Sorted by map name (numerically where names hold numbers), then model, then annotator.
        Input maps without any ground-truth file are left out.

    Raises
    ------
    ParameterError
        The folder does not exist or matches no known layout. The message lists the layouts and,
        when some sub-folders are datasets, names them.
    FormatError
        The folder looks like a dataset but is incomplete: a ground-truth file whose map is
        missing, a missing model, or an annotator folder without a ground-truth file.

    Examples
    --------
    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp())
    >>> for sub in ("sketches", "model", "gt_correspondences/ann"):
    ...     (root / sub).mkdir(parents=True)
    >>> for name in ("sketches/01.png", "model/model_simple.png", "gt_correspondences/ann/gt_01_model_simple.dat"):
    ...     _ = (root / name).write_bytes(b"")
    >>> [(e.name, e.annotators) for e in discover(root)]
    [('01', ('ann',))]
    """
    folder = Path(dataset_dir).expanduser()
    if not folder.is_dir():
        raise ParameterError("dataset folder not found (or not a folder)", path=folder)
    folder = folder.resolve()
    if _looks_like_kth(folder):
        experiments = _discover_kth(folder)
    elif _looks_like_halmstad(folder):
        experiments = _discover_halmstad(folder)
    else:
        children = [child for child in _subfolders(folder) if _looks_like_halmstad(child)]
        if not children:
            raise ParameterError(_unrecognised_message(folder), path=folder)
        experiments = [experiment for child in children for experiment in _discover_halmstad(child)]
    return sorted(experiments, key=lambda e: (_natural_key(e.name), _natural_key(e.metric.stem), e.annotators))


# --------------------------------------------------------------------------- layout tests


def _looks_like_kth(folder: Path) -> bool:
    return (folder / "sketches").is_dir() and (folder / "gt_correspondences").is_dir()


def _looks_like_halmstad(folder: Path) -> bool:
    gt_folder = folder / "GT"
    if not gt_folder.is_dir():
        return False
    return any(any(annotator.glob("gt_*.dat")) for annotator in _subfolders(gt_folder))


def _subfolders(folder: Path) -> list[Path]:
    try:
        return sorted((p for p in folder.iterdir() if p.is_dir() and not p.name.startswith(".")), key=lambda p: p.name)
    except OSError:
        return []


def _unrecognised_message(folder: Path) -> str:
    layouts = "; ".join(f"{name}: {text}" for name, text in LAYOUTS.items())
    message = f"not a dataset folder in a known layout. Expected one of: {layouts}"
    nested = _nested_datasets(folder)
    if nested:
        message += ". Dataset folders found below it: " + ", ".join(str(p) for p in nested) + " (name one of them)"
    return message


def _nested_datasets(folder: Path, depth: int = 2) -> list[Path]:
    found: list[Path] = []
    for child in _subfolders(folder):
        if _looks_like_kth(child) or _looks_like_halmstad(child):
            found.append(child)
        elif depth > 1:
            found.extend(_nested_datasets(child, depth - 1))
    return found


# --------------------------------------------------------------------------- KTH


def _discover_kth(folder: Path) -> list[Experiment]:
    model = _find_model(folder / "model", folder)
    sketches = _images_by_stem(folder / "sketches")
    if not sketches:
        raise FormatError("no map images in sketches/ (expected e.g. sketches/00.png)", path=folder / "sketches")
    annotator_folders = _subfolders(folder / "gt_correspondences")
    if not annotator_folders:
        raise FormatError(
            "no annotator folder in gt_correspondences/ (expected gt_correspondences/<annotator>/gt_<map>_<model>.dat)",
            path=folder / "gt_correspondences",
        )
    ground_truth: dict[str, dict[str, Path]] = {}
    annotators: set[str] = set()
    for annotator_folder in annotator_folders:
        annotator = _annotator_name(annotator_folder, annotators)
        files = _ground_truth_files(annotator_folder, model.stem)
        for map_stem, gt_path in files.items():
            if map_stem not in sketches:
                raise FormatError(
                    f"ground truth for map '{map_stem}' but there is no sketches/{map_stem}.png",
                    path=gt_path,
                )
            ground_truth.setdefault(map_stem, {})[annotator] = gt_path
    return [
        Experiment(
            name=stem,
            sketch=sketches[stem],
            metric=model,
            ground_truth=dict(sorted(ground_truth[stem].items())),
            layout="kth",
            dataset=folder,
        )
        for stem in ground_truth
    ]


def _find_model(model_folder: Path, dataset: Path) -> Path:
    if not model_folder.is_dir():
        raise FormatError(
            "missing model/ folder with the metric model map (expected model/model_simple.png)", path=dataset
        )
    images = _images_by_stem(model_folder)
    if _MODEL_STEM in images:
        return images[_MODEL_STEM]
    if len(images) == 1:
        return next(iter(images.values()))
    if not images:
        raise FormatError("no model image in model/ (expected model/model_simple.png)", path=model_folder)
    raise FormatError(
        f"several images in model/ ({', '.join(sorted(images))}) and none named {_MODEL_STEM}: cannot tell which is the model",
        path=model_folder,
    )


# --------------------------------------------------------------------------- Halmstad


def _discover_halmstad(folder: Path) -> list[Experiment]:
    maps = _images_by_stem(folder)
    experiments: list[Experiment] = []
    annotators: set[str] = set()
    for annotator_folder in _subfolders(folder / "GT"):
        if not any(annotator_folder.glob("gt_*.dat")):
            continue
        annotator = _annotator_name(annotator_folder, annotators)
        model = _find_annotator_model(annotator_folder)
        files = _ground_truth_files(annotator_folder, model.stem)
        for map_stem, gt_path in files.items():
            if map_stem not in maps:
                raise FormatError(
                    f"ground truth for map '{map_stem}' but there is no {map_stem}.png in {folder}",
                    path=gt_path,
                )
            experiments.append(
                Experiment(
                    name=map_stem,
                    sketch=maps[map_stem],
                    metric=model,
                    ground_truth={annotator: gt_path},
                    layout="halmstad",
                    dataset=folder,
                    input_kind="metric",
                )
            )
    return experiments


def _find_annotator_model(annotator_folder: Path) -> Path:
    images = _images_by_stem(annotator_folder)
    if _MODEL_STEM in images:
        return images[_MODEL_STEM]
    if len(images) == 1:
        return next(iter(images.values()))
    raise FormatError(
        f"expected the annotator's model map {_MODEL_STEM}.png beside the ground-truth files"
        + (f" (found {', '.join(sorted(images))})" if images else ""),
        path=annotator_folder,
    )


# --------------------------------------------------------------------------- shared helpers


def _images_by_stem(folder: Path) -> dict[str, Path]:
    if not folder.is_dir():
        return {}
    images: dict[str, Path] = {}
    for path in sorted(folder.iterdir()):
        if path.is_file() and path.suffix.lower() in IMAGE_SUFFIXES and not path.name.startswith("."):
            # PNG wins over other formats of the same name, as the datasets are PNG.
            if path.stem not in images or path.suffix.lower() == ".png":
                images[path.stem] = path
    return images


def _ground_truth_files(annotator_folder: Path, model_stem: str) -> dict[str, Path]:
    """Map stem -> ``gt_<map>_<model>.dat`` in one annotator folder."""
    pattern = re.compile(r"^gt_(?P<map>.+)_" + re.escape(model_stem) + r"\.dat$")
    files: dict[str, Path] = {}
    for path in sorted(annotator_folder.glob("gt_*.dat")):
        match = pattern.match(path.name)
        if match is None or match["map"] == model_stem:
            # Other models' files, or the model matched onto itself: not an experiment.
            continue
        files[match["map"]] = path
    if not files:
        raise FormatError(
            f"no ground-truth file named gt_<map>_{model_stem}.dat in this annotator folder",
            path=annotator_folder,
        )
    return files


def _annotator_name(annotator_folder: Path, taken: set[str]) -> str:
    """Lower-cased annotator name, added to ``taken``."""
    name = annotator_folder.name.lower()
    if name in taken:
        raise FormatError(
            f"two annotator folders are both named '{name}' when case is ignored",
            path=annotator_folder.parent,
        )
    taken.add(name)
    return name


def _natural_key(text: str) -> tuple:
    """Sort 'E5_2' before 'E5_10'."""
    return tuple(int(part) if part.isdigit() else part for part in re.split(r"(\d+)", text))
