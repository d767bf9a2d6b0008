"""Locating the research datasets (GPL-3.0, never copied into this repository).

The data lives in ``../shared/datasets`` beside the repository, or wherever the
environment variable ``URSIM_DATASETS`` points.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["dataset_root", "DATASET_ENV", "MISSING_REASON"]

DATASET_ENV = "URSIM_DATASETS"
_REPO_ROOT = Path(__file__).resolve().parents[2]
MISSING_REASON = (
    f"research datasets not found: set ${DATASET_ENV} or place them in {_REPO_ROOT.parent / 'shared' / 'datasets'}"
)


def dataset_root(explicit: str | Path | None = None) -> Path | None:
    """Return the datasets folder, or None when it is absent.

    Parameters
    ----------
    explicit : str or Path, optional
        A path given on the command line; it wins over the environment.

    Examples
    --------
    >>> root = dataset_root()
    >>> root is None or root.is_dir()
    True
    """
    candidates = []
    if explicit:
        candidates.append(Path(explicit))
    if os.environ.get(DATASET_ENV):
        candidates.append(Path(os.environ[DATASET_ENV]))
    candidates.append(_REPO_ROOT.parent / "shared" / "datasets")
    for candidate in candidates:
        if candidate.is_dir():
            return candidate.resolve()
    return None
