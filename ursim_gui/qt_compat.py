"""Work around a reference-counting bug of shiboken6 6.12 on Python 3.11.

With shiboken6 6.12.0 every PySide6 method that returns nothing takes one reference
away from ``None`` (Python 3.12+ hides this: ``None`` is immortal there). On Python
3.11 ``None``'s count starts near 5,000, so after a few thousand Qt calls (one
painter path, a few mouse moves) the interpreter aborts with "deallocating None".
Reproduce: ``for _ in range(10**5): QPainterPath().closeSubpath()`` -> abort.
PySide6 6.11.3 does not have the bug.

The workaround gives ``None`` the practically infinite count it has on 3.12+, once,
before any Qt call. It only touches the interpreter when the buggy combination is
installed, and never imports Qt itself (the model layer stays Qt-free).
"""

from __future__ import annotations

import ctypes
import logging
import sys
from importlib import metadata

__all__ = ["protect_none_refcount", "needs_none_protection"]

_BUGGY_SHIBOKEN = ("6.12.",)
_PROTECTION = 1 << 40
_applied = False


def needs_none_protection() -> bool:
    """True for Python < 3.12 with an affected shiboken6 release installed."""
    if sys.version_info >= (3, 12):
        return False
    try:
        version = metadata.version("shiboken6")
    except metadata.PackageNotFoundError:
        return False
    return version.startswith(_BUGGY_SHIBOKEN)


def protect_none_refcount() -> bool:
    """Apply the workaround if needed (idempotent). True when it is in effect."""
    global _applied
    if _applied:
        return True
    if not needs_none_protection():
        return False
    # ob_refcnt is the first field of every CPython object (non-debug builds).
    ctypes.c_ssize_t.from_address(id(None)).value += _PROTECTION
    _applied = True
    logging.getLogger(__name__).info("shiboken6 6.12 on Python 3.11: None reference count protected")
    return True
