"""The ``clsolid`` command: ``synth``, ``devices``, ``evaluate`` and ``validate``.

Exit statuses, one table for every subcommand (:data:`clsolid.errors.EXIT_CODES`): each
error class carries its own, so a refusal reads the same from any command.
"""

from __future__ import annotations

import argparse
import difflib
import sys
import warnings

from ..errors import (
    EXIT_CODES,
    ClsolidError,
    DeviceMemoryError,
    InputError,
    KernelBuildError,
    MissingDependencyError,
    NoDeviceError,
    OutputError,
)
from .evaluate import add_evaluate, run_evaluate
from .synth import add_synth, run_synth
from .validate import add_validate, run_validate

EXIT_OK, EXIT_FAIL = 0, 1
EXIT_USAGE, EXIT_NO_DEVICE = InputError.exit_code, NoDeviceError.exit_code
EXIT_MEMORY, EXIT_BUILD = DeviceMemoryError.exit_code, KernelBuildError.exit_code
EXIT_MISSING, EXIT_OUTPUT, EXIT_INTERRUPTED = MissingDependencyError.exit_code, OutputError.exit_code, 130

__all__ = ["main", "build_parser", "EXIT_CODES"]


class _Parser(argparse.ArgumentParser):
    """An argparse parser whose usage errors are one line, not the whole usage first, and
    name the closest flag to one it does not know."""

    def error(self, message: str):
        if message.startswith("unrecognized arguments:"):
            known = [flag for parser in self._parsers() for flag in parser._option_string_actions]
            close = [difflib.get_close_matches(word, known, n=1) for word in message.split(":", 1)[1].split()
                     if word.startswith("--")]
            hints = sorted({match[0] for match in close if match})
            if hints:
                message += f" (did you mean {', '.join(hints)}?)"
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def _parsers(self) -> list[argparse.ArgumentParser]:
        """This parser and its subcommands'."""
        subs = [a for a in self._actions if isinstance(a, argparse._SubParsersAction)]
        return [self] + [parser for sub in subs for parser in sub.choices.values()]


def build_parser(show_all: bool = False) -> argparse.ArgumentParser:
    """The ``clsolid`` parser; *show_all* shows the advanced groups of ``synth --help`` too."""
    epilog = "exit statuses:\n" + "\n".join(f"  {code:>3}  {what}" for code, what in EXIT_CODES.items())
    parser = _Parser(prog="clsolid", description="Solid textures from a 2D exemplar, on OpenCL.", epilog=epilog,
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    add_synth(sub, show_all)
    sub.add_parser("devices", help="list OpenCL devices", description="List every OpenCL device clsolid can use.")
    add_evaluate(sub)
    add_validate(sub)
    return parser


def run_devices() -> int:
    """``clsolid devices``: a table of every OpenCL device, and whether it compiles."""
    from ..core.device import INSTALL_HINT, list_devices

    devices = list_devices()
    print(f"{'index':<6} {'type':<11} {'compiles':<8} {'vec':>3} {'CUs':>4} {'memory':>10} {'max buffer':>11} "
          f"{'fp64':<4}  {'OpenCL C':<10} {'driver':<24} platform / name")
    for d in devices:
        opencl_c = d["opencl_c"].removeprefix("OpenCL C").split()[0] if d["opencl_c"] else "?"
        print(f"{d['index']:<6} {d['type']:<11} {'yes' if d['compiles'] else 'NO':<8} "
              f"{d['vector_width'] or '-':>3} {d['compute_units']:>4} "
              f"{d['global_mem'] / 2**30:>8.1f}Gi {d['max_alloc'] / 2**30:>9.2f}Gi {'yes' if d['fp64'] else 'no':<4}  "
              f"{opencl_c:<10} {d['driver'][:24]:<24} {d['platform']} / {d['name']}")
    for d in devices:
        if not d["compiles"]:
            print(f"{d['index']}: cannot compile kernels: {d['probe_message']}")
    if not any(d["compiles"] for d in devices):
        print(f"No device compiles. {INSTALL_HINT}.")
    return EXIT_OK


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"clsolid: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``clsolid`` command; returns the exit status (:data:`clsolid.errors.EXIT_CODES`)."""
    args = vars(build_parser().parse_args(argv))
    command = args.pop("command")
    debug = args.get("debug", False)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always", UserWarning)  # each said once, as a line of its own
            if not debug:
                warnings.showwarning = _show_warning
            if command == "synth":
                return run_synth(args)
            if command == "devices":
                return run_devices()
            if command == "validate":
                return run_validate(argparse.Namespace(**args))
            return run_evaluate(argparse.Namespace(**args))
    except ClsolidError as exc:
        if debug:
            raise
        print(f"clsolid {command}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        folder = args.get("resume") or args.get("checkpoint")
        hint = f"; the last checkpoint is in {folder}: go on with --resume {folder}" if folder else ""
        print(f"clsolid: interrupted{hint}", file=sys.stderr)
        return EXIT_INTERRUPTED
