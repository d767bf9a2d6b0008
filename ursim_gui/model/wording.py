"""Words of the app's messages that depend on a number (Qt-free, for the model, panels and views).

>>> counted(1, "pair"), counted(3, "pair"), counted(0, "anchor")
('1 pair', '3 pairs', '0 anchors')
"""

from __future__ import annotations

__all__ = ["counted"]


def counted(count: int, noun: str, plural: str | None = None) -> str:
    """``count`` and ``noun``, in the plural (``plural``, else ``noun + "s"``) unless ``count`` is one.

    >>> counted(2, "clique"), counted(1, "reading"), counted(2, "sketch", "sketches")
    ('2 cliques', '1 reading', '2 sketches')
    """
    return f"{count} {noun}" if count == 1 else f"{count} {plural or noun + 's'}"
