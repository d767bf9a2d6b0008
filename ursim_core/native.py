"""C extension modules compiled on the installed machine: building, finding and loading them.

The project ships C sources, not binaries: the MAORIS kernels
(:mod:`ursim_core.segmentation.maoris.compiled`) and the planar matcher's loop
(:mod:`ursim_core.matching.kernels`) are compiled once per install by the C compiler Python
was built with (``make`` does it; the first use does when nothing did). A :class:`NativeModule`
names one such module: its sources, where its build may live (beside the sources in a checkout
or writable install, else the user's cache), and the digest of the sources it was built from, so
that an edited source is built again instead of loading stale code.

Floating point is compiled as written (``-ffp-contract=off``: no fused multiply-adds, no
``-ffast-math``), so that a kernel computes what its reference in Python or numba does, bit for bit.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import os
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

# The compiler's modules (subprocess, sysconfig, tempfile, threads) are imported by the functions
# that build: a process that only loads a built module does not pay for them.

__all__ = ["CFLAGS", "NativeModule", "compile_extension"]

#: Compiler flags of every source (after Python's own ``CCSHARED``, e.g. ``-fPIC``).
CFLAGS = ("-O3", "-std=gnu11", "-pthread", "-ffp-contract=off", "-fno-strict-aliasing", "-Wall", "-Wno-unused-function")


def _run(command: list[str], cwd: Path) -> None:
    import shlex
    import subprocess

    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        output = (done.stderr or done.stdout).strip()
        raise RuntimeError(f"`{shlex.join(command[:2])} ...` failed (exit {done.returncode}): {output[-1500:]}")


def compile_extension(
    sources: list[Path], output: str | Path, *, include_dirs=(), numpy: bool = False, jobs: int | None = None
) -> Path:
    """Compile ``sources`` (one compiler process each, ``jobs`` at once) and link them into ``output``.

    The compile and link commands are this Python's (``CC``, ``CCSHARED``, ``LDSHARED``, which
    the environment may override); ``numpy`` adds NumPy's headers.

    Raises
    ------
    RuntimeError
        When there is no C compiler or it fails (with the end of its messages).
    """
    import shlex
    import sysconfig
    from concurrent.futures import ThreadPoolExecutor

    output = Path(output)
    includes = [f"-I{sysconfig.get_paths()['include']}", *(f"-I{folder}" for folder in include_dirs)]
    if numpy:
        import numpy as np

        includes.append(f"-I{np.get_include()}")
    cc = shlex.split(os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc")
    shared = shlex.split(sysconfig.get_config_var("CCSHARED") or "-fPIC")
    ldshared = shlex.split(os.environ.get("LDSHARED") or sysconfig.get_config_var("LDSHARED") or "cc -shared")
    compile_command = [*cc, *shared, *CFLAGS, *includes]
    objects = [output.parent / f"{source.stem}.o" for source in sources]
    try:
        with ThreadPoolExecutor(max_workers=jobs or os.cpu_count() or 1) as pool:
            compiles = [
                pool.submit(_run, [*compile_command, "-c", str(source), "-o", str(obj)], output.parent)
                for source, obj in zip(sources, objects)
            ]
            for future in compiles:
                future.result()
        _run([*ldshared, *map(str, objects), "-pthread", "-o", str(output)], output.parent)
    except FileNotFoundError as error:
        raise RuntimeError(f"no C compiler: {error}") from error
    finally:
        for obj in objects:
            obj.unlink(missing_ok=True)
    return output


@dataclass(frozen=True)
class NativeModule:
    """One extension module built from the C sources of a folder.

    Attributes
    ----------
    name : str
        The module's name (its ``PyInit_<name>``).
    source_dir : Path
        The folder of its ``.c`` and ``.h`` files.
    digest_extra : tuple of Path
        Other files whose change means building again (how it is built).
    numpy : bool
        Whether the sources include NumPy's headers.
    """

    name: str
    source_dir: Path
    digest_extra: tuple = field(default=())
    numpy: bool = False

    @property
    def digest_name(self) -> str:
        return f"{self.name}.digest"

    def sources(self) -> list[Path]:
        """The sources and headers, in a stable order (for the digest)."""
        return sorted([*self.source_dir.glob("*.c"), *self.source_dir.glob("*.h")])

    def digest(self) -> str:
        """SHA-256 of the sources, of :attr:`digest_extra`, of this module and of the Python ABI."""
        digest = hashlib.sha256(importlib.machinery.EXTENSION_SUFFIXES[0].encode())
        for source in [*self.sources(), *self.digest_extra, Path(__file__)]:
            digest.update(source.name.encode() + b"\0" + source.read_bytes() + b"\0")
        return digest.hexdigest()

    def directories(self) -> list[Path]:
        """Where the built module may live, in the order looked at: beside the sources (a checkout
        or a writable install), then the user's cache (``$XDG_CACHE_HOME/ursim``)."""
        xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        folder = hashlib.sha1(str(self.source_dir).encode()).hexdigest()[:16]
        own = self.source_dir / "__pycache__"
        user = Path(xdg) / "ursim" / f"{self.name}-{folder}"
        return [own, user] if os.access(self.source_dir, os.W_OK) else [user, own]

    def module_path(self, folder: Path) -> Path:
        return Path(folder) / (self.name + importlib.machinery.EXTENSION_SUFFIXES[0])

    def built_path(self, directories=None, digest=None) -> Path | None:
        """The built module of these sources, or None when it is missing or stale.

        ``directories`` (default :meth:`directories`) and ``digest`` (a callable, default
        :meth:`digest`, called only when a digest file is found) let a caller substitute its own.
        """
        wanted = None
        for folder in self.directories() if directories is None else directories:
            try:
                recorded = (Path(folder) / self.digest_name).read_text(encoding="ascii").strip()
            except OSError:
                continue
            wanted = wanted or (self.digest if digest is None else digest)()
            if recorded == wanted and self.module_path(folder).is_file():
                return self.module_path(folder)
        return None

    def build(self, directory: str | Path | None = None, *, digest: str | None = None) -> Path:
        """Compile the sources into ``directory`` (default: the first writable of
        :meth:`directories`); return the module's path. ``digest``: what to record (default
        :meth:`digest`).

        The old digest is removed first, then the module and the new digest are put in place by
        a rename, so a reader never sees a digest without its module.
        """
        import tempfile

        target = Path(directory) if directory is not None else self.directories()[0]
        target.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix=f"{self.name}-", dir=target) as scratch:
            sources = sorted(self.source_dir.glob("*.c"))
            built = compile_extension(
                sources, self.module_path(Path(scratch)), include_dirs=[self.source_dir], numpy=self.numpy
            )
            (target / self.digest_name).unlink(missing_ok=True)
            os.replace(built, self.module_path(target))
            digest_path = Path(scratch) / "digest"
            digest_path.write_text((self.digest() if digest is None else digest) + "\n", encoding="ascii")
            os.replace(digest_path, target / self.digest_name)
        return self.module_path(target)

    def load(self, path: Path) -> ModuleType:
        """The module at ``path`` (ImportError or OSError when it cannot be loaded)."""
        spec = importlib.util.spec_from_file_location(self.name, path)
        if spec is None or spec.loader is None:
            raise ImportError(f"{path} is not an extension module")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
