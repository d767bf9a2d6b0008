"""Building one part of the MAORIS kernels ahead of time with :mod:`numba.pycc` (one process).

:func:`ursim_core.segmentation.maoris.compiled.build_ahead` splits the kernels into the
parts of :data:`~ursim_core.segmentation.maoris.compiled.PARTS` and runs this module once per
part, in processes at once (``python -m ursim_core.segmentation.maoris.ahead_build NAME
FOLDER``): each writes the extension module ``NAME`` into ``FOLDER``. numba compiles on one
thread, so two parts on two CPUs take about half the time of one module.

What a build costs (measured on the 2-CPU machine of the project, numba 0.68, CPU seconds
of the one-module build of before): numba typing and lowering the kernels and their helpers
in Python (about two thirds), and LLVM optimising them. Wasted work is skipped here:

* typing every kernel once more to learn its return type for pycc (about 3 s): the return
  types are declared (:data:`.kernels.signatures.RETURN_TYPES`; a test checks them
  against numba's typing);
* the machine code of every helper (2.1 s in numba's JIT engine): typing a call to an
  ``@njit`` helper makes numba compile it as for the JIT, down to machine code that a
  build never runs (pycc links the helpers' optimised LLVM IR into the module and
  generates the module's machine code once), and writes the kernels that other kernels
  call to numba's cache;
* pycc's C support code compiled at ``-O3 -g``, with numba's typed dict, list and set
  that no kernel uses (2.6 s; 0.9 s per part now): it is the module's import function and
  the allocator of numba's runtime, called once per array, never in the loops of the
  kernels.

(The kernels themselves pass typed values, not literals, to the helpers that numba
compiled twice for them, and share the bodies of the two entry kernels that another calls.)

Numba's state in the process is left altered (helpers without machine code), so this runs
only in a process of its own.
"""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["build_part"]

# pycc's C sources that the kernels need: numba's typed containers are left out (a test
# checks that the built module leaves no numba symbol undefined).
_UNUSED_MIXINS = ("dictobject.c", "listobject.c", "setobject.c")
# Appended to the compiler's flags (the last -O and -g win).
_MIXIN_CFLAGS = ["-O1", "-g0"]


def build_part(name: str, modules: tuple[str, ...], folder: str | Path) -> Path:
    """Compile the kernels of ``modules`` (of :mod:`.kernels`) into the extension module
    ``name`` in ``folder``; return its path.

    Parameters
    ----------
    name : str
        The module's name (what Python imports).
    modules : tuple of str
        Modules of :mod:`.kernels` whose kernels of
        :data:`~ursim_core.segmentation.maoris.kernels.signatures.SIGNATURES` it exports.
    folder : str or Path
        Where to write it.

    Returns
    -------
    Path
        The extension module.
    """
    from numba.core.compiler import Flags
    from numba.pycc import CC
    from numba.pycc import compiler as pycc_compiler

    from ursim_core.segmentation.maoris.kernels import signatures

    _skip_helper_machine_code(_kernel_modules())
    cc = CC(name)
    cc.output_dir = str(folder)
    cc.verbose = False
    cc._extra_cflags = {"posix": list(_MIXIN_CFLAGS)}
    cc._mixin_sources = [source for source in cc._mixin_sources if not source.endswith(_UNUSED_MIXINS)]
    for key, args in signatures.SIGNATURES.items():
        if key[0] in modules:
            cc.export(key[1], signatures.RETURN_TYPES[key](*args))(signatures.kernel(key).py_func)
    original_flags = pycc_compiler.Flags
    pycc_compiler.Flags = _GilReleasingFlags.make(Flags)
    try:
        cc.compile()
    finally:
        pycc_compiler.Flags = original_flags
    return Path(folder) / cc.output_file


def _skip_helper_machine_code(kernel_modules) -> None:
    """Make numba compile the helpers as far as LLVM IR (optimised, as before) and no further.

    A helper's library is finalised (optimised) and added to numba's JIT engine, which then
    generates its machine code (``_finalize_specific``), and the dispatcher asks for the
    address of its Python wrapper (``get_executable``). Neither is used by pycc, which links
    the optimised IR; so the IR, and the modules built from it, stay the same. numba's cache
    on disk would need that machine code: it is turned off for the kernels (an entry kernel
    that another one calls was compiled by the JIT too, and written to the cache, for
    nothing).
    """
    from numba import _dynfunc
    from numba.core import codegen, cpu
    from numba.core.caching import NullCache
    from numba.core.dispatcher import Dispatcher

    for module in kernel_modules:
        for value in vars(module).values():
            if isinstance(value, Dispatcher):
                value._cache = NullCache()

    def _finalize_specific(library):
        pass

    def _get_executable(context, library, fndesc, env):
        library._ensure_finalized()
        # A function at address 0, never called: the build calls no kernel from Python.
        name = fndesc.qualname.split(".")[-1]
        return _dynfunc.make_function(fndesc.lookup_module(), name, "", 0, env, (library,))

    codegen.JITCodeLibrary._finalize_specific = _finalize_specific
    cpu.CPUContext.get_executable = _get_executable


def _kernel_modules() -> list:
    import importlib
    import pkgutil

    from ursim_core.segmentation.maoris import kernels

    names = [info.name for info in pkgutil.iter_modules(kernels.__path__)]
    return [importlib.import_module(f"{kernels.__name__}.{name}") for name in names]


class _GilReleasingFlags:
    """pycc builds its own ``Flags()`` for the exports, with no way to ask for ``nogil``."""

    @staticmethod
    def make(base):
        class Flags(base):
            def __init__(self, *args, **kwargs):
                super().__init__(*args, **kwargs)
                self.release_gil = True

        return Flags


def _main(argv: list[str]) -> None:
    from ursim_core.segmentation.maoris.compiled import PARTS

    name, folder = argv
    build_part(name, PARTS[name], folder)


if __name__ == "__main__":
    _main(sys.argv[1:])
