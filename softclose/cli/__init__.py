"""The command line: ``softclose COMMAND [--config FILE] [--set KEY=VALUE ...] [--json]``.

This package sits on top of the library: it parses arguments, loads the config, calls the
library, formats text, writes files and picks the exit code. Nothing in the library imports
it. Each command family is one module with ``register(subparsers)``; a command's handler is
``run(cfg, args) -> Outcome``.

Exit codes: 0 success; 2 invalid input (one line naming the culprit); 3 a numerical or
optimiser failure that was detected and reported (with what to change); 130 interrupted
(Ctrl-C, or SIGTERM sent to the process: what was finished is kept). Every error line
starts ``softclose: error:``.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import ConfigError, SoftcloseError
from .common import Outcome

#: command modules, in the order ``--help`` lists them
COMMAND_MODULES = ("state", "simulate", "optimise", "prepare", "sweep", "bench", "robust",
                   "select", "fit", "spring", "report", "docs")
#: the module of each command (a command line names one: only its module is imported and
#: only its parser built -- the others' cost ~10 ms of start-up)
COMMANDS = {"state": "state", "simulate": "simulate", "optimise": "optimise",
            "optimize": "optimise", "pareto": "optimise", "prepare": "prepare", "sweep": "sweep",
            "bench": "bench",
            "yield": "robust", "sensitivity": "robust", "select": "select", "fit": "fit",
            "spring": "spring", "report": "report", "docs": "docs"}

#: the program's name: every error line starts ``softclose: error:``
PROG = "softclose"

DESCRIPTION = """\
Design soft-closing lids, on a four-bar linkage or a hinge (one pivot): simulate the closing
stroke, optimise the spring and damper, sweep any config keys, and judge a design under
manufacturing tolerances.

Start with `softclose optimise --out D`: it writes the optimal design as D/design.toml,
which every command takes with `--config D/design.toml` (e.g. `softclose yield --config
D/design.toml`). Every config key, its default, unit and range: `softclose docs keys`."""

EPILOG = """\
exit codes: 0 success, 2 invalid input, 3 a numerical or optimiser failure (reported, with
what to change), 130 interrupted. `softclose COMMAND --help` describes a command;
`softclose docs` the commands, the design problem and every config key."""


def _columns() -> int:
    """The terminal's width as argparse's help formatter takes it (``COLUMNS``, else the
    terminal of stdout, else 80) -- without importing shutil, which argparse would import
    (with bz2 and lzma) for every parser it builds."""
    import os
    try:
        columns = int(os.environ["COLUMNS"])
    except (KeyError, ValueError):
        columns = 0
    if columns > 0:
        return columns
    try:
        return os.get_terminal_size(sys.__stdout__.fileno()).columns or 80
    except (AttributeError, ValueError, OSError):
        return 80


class _Parser(argparse.ArgumentParser):
    def _get_formatter(self):
        return self.formatter_class(prog=self.prog, width=_columns() - 2)

    def error(self, message):  # one line, exit code 2; the prefix is main's
        where = self.prog.removeprefix(PROG).strip()
        if not where and "required: COMMAND" in message:
            message = (f"no command given (commands: {', '.join(_commands(self))}; "
                       "`softclose --help` says what each does)")
        raise ConfigError(f"{where}: {message}" if where else message)

    def _check_value(self, action, value):
        """An unknown command is refused by name, with the nearest command."""
        if isinstance(action, argparse._SubParsersAction) and value not in action.choices:
            import difflib
            near = difflib.get_close_matches(str(value), list(action.choices), n=1, cutoff=0.6)
            hint = f"did you mean '{near[0]}'? " if near else ""
            raise ConfigError(f"unknown command '{value}' ({hint}commands: "
                              f"{', '.join(_names(action))}; `softclose --help` says what "
                              "each does)")
        super()._check_value(action, value)


def _names(action) -> list[str]:
    """The commands, each once (an alias after its command's name: 'optimise (optimize)')."""
    names: dict[int, list[str]] = {}
    for name, p in action.choices.items():
        names.setdefault(id(p), []).append(name)
    return [n[0] + (f" ({', '.join(n[1:])})" if len(n) > 1 else "") for n in names.values()]


def _commands(parser) -> list[str]:
    sub = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return _names(sub[0]) if sub else []


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The parser of every command, or -- ``argv`` starting with a command's name -- of
    that command's family only (the same parser for that command line)."""
    from ..version import __version__
    parser = _Parser(prog=PROG, description=DESCRIPTION, epilog=EPILOG,
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    first = argv[0] if argv else None
    for name in ((COMMANDS[first],) if first in COMMANDS else COMMAND_MODULES):
        try:
            mod = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:  # a command family not installed in this build
            if exc.name != f"{__name__}.{name}":
                raise
            continue
        mod.register(sub)
    return parser


def _new_line() -> str:
    """A newline when a progress line on stderr is unfinished, so a message starts a line."""
    from ..interrupt import line_open
    return "\n" if line_open() else ""


def _error(msg: str, code: int, as_json: bool) -> int:
    from ..jsonio import dumps
    if as_json:
        print(dumps({"error": msg, "exit_code": code}))
    print(f"{_new_line()}softclose: error: {msg}", file=sys.stderr)
    return code


def _interrupted() -> int:
    from ..interrupt import signal_name
    print(f"{_new_line()}softclose: interrupted ({signal_name()}); what was finished is kept",
          file=sys.stderr)
    return 130


def main(argv: list[str] | None = None) -> int:
    """Run one command: ``argv`` (a list) returns its exit code; with no ``argv`` this is the
    program (``softclose ...``): it reads ``sys.argv`` and ends the process with that code
    (:func:`softclose.interrupt.exit_program`), and a signal after the command changes
    nothing."""
    if argv is not None:
        return _main(list(argv))
    from ..interrupt import exit_program, handle_until_exit
    handle_until_exit()
    exit_program(_main(sys.argv[1:]))


def free_overrides(args) -> list[str]:
    """``--free KEY=LO:HI`` options as overrides of ``optimise.free.KEY``."""
    from ..config.free import parse_free_option
    out = []
    for text in getattr(args, "free", None) or ():
        key, (lo, hi) = parse_free_option(text)
        out.append(f"optimise.free.{key}=[{lo!r}, {hi!r}]")
    return out


def _main(argv: list[str]) -> int:
    as_json = "--json" in argv
    from .. import interrupt
    try:
        with interrupt.guard():   # Ctrl-C ends the command even inside a compiled solver
            args = build_parser(argv).parse_args(argv)
            from .common import set_figures
            set_figures(args)
            from ..config import load_config
            cfg = load_config(args.config, args.overrides + free_overrides(args))
            outcome: Outcome = args.run(cfg, args)
    except SoftcloseError as exc:
        if interrupt.interrupted():   # a solver turned the Ctrl-C into an error
            return _interrupted()
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return _error(msg, exc.exit_code, as_json)
    except KeyboardInterrupt:
        return _interrupted()
    except Exception:
        if interrupt.interrupted():
            return _interrupted()
        raise
    # a command that kept what was finished (select, sweep: exit 130) shows it; else a Ctrl-C
    # swallowed by a solver while the command ran to its end
    if interrupt.interrupted() and outcome.exit_code != 130:
        return _interrupted()
    from ..jsonio import dumps
    try:
        if args.json:
            print(dumps(outcome.payload))
        elif outcome.text:
            print(outcome.text)
        sys.stdout.flush()
    except BrokenPipeError:  # the reader went away (``softclose ... | head``): not an error
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    if outcome.error:
        print(f"{_new_line()}softclose: error: {outcome.error.splitlines()[0]}", file=sys.stderr)
    return outcome.exit_code


__all__ = ["main", "build_parser", "Outcome"]
