"""The ``ursim`` command line: the parser and the entry point.

Each subcommand is a module of this package (:mod:`~ursim_core.cli.segment`,
:mod:`~ursim_core.cli.match`, :mod:`~ursim_core.cli.match_batch`, :mod:`~ursim_core.cli.evaluate`, :mod:`~ursim_core.cli.convert`,
:mod:`~ursim_core.cli.bench`) with ``HELP``, ``EXAMPLES``, ``configure(parser)`` and ``run(args)``.
Only the subcommand being run is configured, and heavy imports happen inside ``run``, so
``ursim --help`` loads nothing heavy.

Exit codes: 0 success, 1 bad input or a file-system error (one line on stderr, never a
traceback), 2 usage error, 130 interrupted.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import os
import sys
from collections.abc import Sequence

from ursim_core.cli.common import UsageError
from ursim_core.errors import UrsimError

#: Subcommand name -> module, in the order of ``ursim --help``.
COMMANDS = {
    "segment": "ursim_core.cli.segment",
    "match": "ursim_core.cli.match",
    "match-batch": "ursim_core.cli.match_batch",
    "evaluate": "ursim_core.cli.evaluate",
    "convert": "ursim_core.cli.convert",
    "goal": "ursim_core.cli.goal",
    "route": "ursim_core.cli.route",
    "bench": "ursim_core.cli.bench",
}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``ursim`` parser; with ``command``, only that subcommand's options are configured.

    ``None`` configures every subcommand; ``""`` none (enough for ``ursim --help``).

    Examples
    --------
    >>> build_parser("convert").parse_args(["convert", "a.dat", "a.json"]).input
    'a.dat'
    """
    from ursim_core import __version__

    parser = argparse.ArgumentParser(
        prog="ursim",
        description="Match hand-drawn sketch maps to metric maps (URSIM): segment, match, evaluate.",
        epilog="Run 'ursim COMMAND --help' for examples. Pixel coordinates are (row, col).",
    )
    parser.add_argument("--version", action="version", version=f"ursim {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, module_name in COMMANDS.items():
        module = importlib.import_module(module_name)
        sub = commands.add_parser(
            name,
            help=module.HELP,
            description=module.HELP,
            epilog=module.EXAMPLES,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        sub.set_defaults(run=module.run, parser=sub)
        if command is None or command == name:
            module.configure(sub)
    return parser


def _command_of(argv: Sequence[str]) -> str | None:
    # The first word that is not an option names the subcommand (the top level has no valued option).
    for word in argv:
        if not word.startswith("-"):
            return word
    return None


#: OpenBLAS's idle threads spin for 2**28 cycles (about 0.1 s) after numpy loads them before they
#: sleep; 2**4 lets them sleep at once. Only how they wait changes, not their number nor any result:
#: on the 2-CPU machine of the project the spinning thread cost every ``ursim`` process about
#: 40 ms of CPU, taken from the main thread when the other CPU is busy. A value already set wins.
_QUIET_BLAS_THREADS = {"OPENBLAS_THREAD_TIMEOUT": "4"}


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``ursim`` on ``argv`` (default: this process's command line); return the exit code.

    Without ``argv`` (the ``ursim`` command, ``python -m ursim_core.cli``) the process exits
    next, so the objects it made are frozen (:func:`gc.freeze`) before returning: Python's
    shutdown would otherwise run the cyclic garbage collector over every one of them (numpy,
    OpenCV, networkx: a few hundred thousand), which took 80-100 ms of every ``ursim
    segment`` after its outputs were written, 13 ms frozen. Every output is written, flushed
    and closed by then; only cyclic garbage left at exit is not collected, which the exit frees.
    A caller that passes ``argv`` (a test, an embedding program) keeps collecting as usual.
    """
    code = _main(list(sys.argv[1:] if argv is None else argv))
    if argv is None:
        gc.freeze()
    return code


def _main(argv: list[str]) -> int:
    for name, value in _QUIET_BLAS_THREADS.items():
        os.environ.setdefault(name, value)  # before numpy is first imported (by the subcommand)
    command = _command_of(argv)
    parser = build_parser(command if command in COMMANDS else "")
    args = parser.parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except UsageError as error:
        args.parser.print_usage(sys.stderr)
        print(f"ursim {args.command}: error: {error}", file=sys.stderr)
        return 2
    except UrsimError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    except BrokenPipeError as error:
        if not _output_gone():
            print(f"error: {os_error_text(error)}", file=sys.stderr)
            return 1
        # The reader of the output left (``ursim match ... | head -1``): the outputs are written
        # before anything is printed, so end quietly, as other commands do when their pipe
        # closes (128 + SIGPIPE). Standard output goes to devnull: the flush at exit would fail again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as error:
        print(f"error: {os_error_text(error)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def _output_gone() -> bool:
    """Whether standard output is a pipe whose reader has closed it (poll reports an error on it)."""
    try:
        import select

        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(event & select.POLLERR for _, event in poller.poll(0))
    except (AttributeError, OSError, ValueError):  # no poll (Windows), no file descriptor
        return False


def os_error_text(error: OSError) -> str:
    """``PATH: problem`` of a file-system error, on one line."""
    problem = error.strerror or str(error) or type(error).__name__
    where = error.filename if error.filename is not None else None
    if error.filename2 is not None:
        where = f"{error.filename} -> {error.filename2}"
    return f"{where}: {problem}" if where is not None else problem


if __name__ == "__main__":
    sys.exit(main())
