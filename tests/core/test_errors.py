"""The not-found errors: caught as the core's error type and as FileNotFoundError alike."""

from __future__ import annotations

import errno
import pickle

import pytest

from ursim_core import errors
from ursim_core.errors import (
    FormatError,
    FormatFileNotFoundError,
    MapError,
    MapFileNotFoundError,
    ParameterError,
    SegmentationError,
    SegmentationFileNotFoundError,
    UrsimError,
    UrsimFileNotFoundError,
    file_not_found,
)

KINDS = [
    (UrsimError, UrsimFileNotFoundError),
    (MapError, MapFileNotFoundError),
    (FormatError, FormatFileNotFoundError),
    (SegmentationError, SegmentationFileNotFoundError),
]


@pytest.mark.parametrize("base, not_found", KINDS)
def test_a_missing_file_is_caught_by_the_error_type_and_by_file_not_found_error(base, not_found):
    error = file_not_found(base, "file not found", path="maps/a.png")
    assert type(error) is not_found
    for handler in (base, UrsimError, FileNotFoundError, OSError):
        with pytest.raises(handler):
            raise error
    assert (error.errno, error.filename) == (errno.ENOENT, "maps/a.png")
    assert error.strerror  # "No such file or directory", as the system's


def test_the_message_is_the_core_one_line_not_the_os_error_format():
    error = MapFileNotFoundError("image file not found: a.pgm", path="map.yaml", field="image", filename="a.pgm")
    assert str(error) == "map.yaml: field 'image': image file not found: a.pgm"
    assert (error.problem, str(error.path), error.field, error.filename) == (
        "image file not found: a.pgm",
        "map.yaml",
        "image",
        "a.pgm",
    )


@pytest.mark.parametrize("base, not_found", KINDS)
def test_not_found_errors_survive_pickling(base, not_found):
    # Errors cross process pools (evaluation, match-batch).
    error = not_found("file not found", path="x/corr.json", field="cliques", filename="x/corr.json")
    copy = pickle.loads(pickle.dumps(error))
    assert type(copy) is not_found
    assert (str(copy), copy.problem, copy.path, copy.field, copy.filename, copy.errno) == (
        str(error),
        error.problem,
        error.path,
        error.field,
        error.filename,
        errno.ENOENT,
    )


def test_other_error_types_are_given_as_they_are():
    error = file_not_found(ParameterError, "file not found", path="p.json")
    assert type(error) is ParameterError and not isinstance(error, OSError)
    assert str(error) == "p.json: file not found"
    # A not-found class given itself is used as it is.
    assert type(file_not_found(MapFileNotFoundError, "gone", path="a.png")) is MapFileNotFoundError


def test_the_not_found_classes_are_exported():
    for name in ("UrsimFileNotFoundError", "MapFileNotFoundError", "FormatFileNotFoundError"):
        assert name in errors.__all__
    assert "SegmentationFileNotFoundError" in errors.__all__ and "file_not_found" in errors.__all__
