"""Constants shared by the compiled kernels and the Python side (imports nothing)."""

NO_MINIMUM = -1
"""An edge's "lowest value met along fused paths" before any fusion has set one."""
