"""Deprecated: the old home of the correspondence values and codecs, kept for one release.

Import from :mod:`ursim_core.correspondences` instead (the names live in ``values``,
``json_codec``, ``schema``, ``dat_codec`` and ``assignment``). Every name this module used to
export still resolves here, with a :class:`DeprecationWarning`.
"""

from __future__ import annotations

import importlib
import warnings

_NEW_HOME = {
    "FORMAT_NAME": "schema",
    "CURRENT_VERSION": "schema",
    "correspondences_schema": "schema",
    "SUPPORTED_VERSIONS": "json_codec",
    "load_correspondences": "json_codec",
    "save_correspondences": "json_codec",
    "correspondences_to_json": "json_codec",
    "SOURCES": "values",
    "STATUSES": "values",
    "MapRef": "values",
    "Clique": "values",
    "Correspondences": "values",
    "utc_timestamp": "values",
    "load_dat": "dat_codec",
    "save_dat": "dat_codec",
    "regions_at_points": "assignment",
    "assign_regions": "assignment",
    "from_pairs": "assignment",
}

__all__ = list(_NEW_HOME)


def __getattr__(name: str):
    module = _NEW_HOME.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn(
        f"ursim_core.correspondences.codec.{name} moved: import it from ursim_core.correspondences",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(importlib.import_module(f"ursim_core.correspondences.{module}"), name)
