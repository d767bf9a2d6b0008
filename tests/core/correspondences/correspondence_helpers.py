"""Checks shared by the correspondence file tests."""

from __future__ import annotations

from pathlib import Path

from ursim_core.errors import UrsimError


def one_line_error(path: Path, error: UrsimError) -> str:
    """The message of ``error``: one line that names the file ``path``."""
    message = str(error)
    assert "\n" not in message
    assert str(path) in message or path.name in message
    return message
