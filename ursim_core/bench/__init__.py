"""Benchmarks behind ``ursim bench``: speed and memory figures, printed, never asserted.

May import anything in :mod:`ursim_core` (it sits at the top, beside the CLI).
"""
