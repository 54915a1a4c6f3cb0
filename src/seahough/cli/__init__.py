"""The ``seahough`` command line: detect, odometry, simulate, demo, survey.

Errors a user can cause (a missing or broken file, a bad parameter) print
one line ``seahough: error: ...`` on stderr and exit with status 2, never a
traceback. See ``seahough COMMAND --help``.

One module per command (:mod:`.detect`, :mod:`.odometry`, :mod:`.simulate`,
:mod:`.demo`, :mod:`.survey`), what they share in :mod:`._common`; the work
itself is the library's. A command's module (and what it needs: Numba,
OpenCV, matplotlib, Dask) is imported only when that command runs, inside
:func:`main`, so ``seahough --help`` starts at once and a Ctrl-C during the
imports is an interruption like any other.
"""

from __future__ import annotations

import importlib
import os
import signal
import warnings
import sys
import threading
import time

import click

from .. import __version__
from ..errors import SeahoughError
from ._common import PROG, _err, _Fail, _interrupted, _Terminated

__all__ = ["cli", "main"]

#: Every command: its one-line help as ``seahough --help`` lists it (the
#: command's own ``short_help`` or first docstring sentence: a test keeps
#: them equal), and the extra that installs what it needs beyond the base.
#: The command is the attribute of the same name of ``seahough.cli.<name>``.
COMMANDS = {
    "demo": ("A tour that needs no files: simulate, detect, dead-reckon.", None),
    "detect": ("Find PATTERN in each IMAGE.", None),
    "odometry": ("Dead reckoning: the camera's path from overlapping frames.", None),
    "simulate": ("Write synthetic underwater scenes with exact ground truth.", None),
    "survey": ("Thousands of photos on every core or a Dask cluster, into Parquet.", "survey"),
}


class CommandUnavailable(click.ClickException):
    """A command whose module, or a module it needs, is not installed."""

    exit_code = 2


def load_command(name: str) -> click.Command:
    """Import ``seahough.cli.<name>`` and return its command ``name``.

    Raises
    ------
    CommandUnavailable
        The module, or one it imports, is missing (one line, exit status 2).

    Examples
    --------
    >>> load_command("simulate").name
    'simulate'
    """
    module = f"{__name__}.{name}"
    try:
        return getattr(importlib.import_module(module), name)
    except ModuleNotFoundError as e:
        if e.name == module:
            raise CommandUnavailable(f"{name}: this installation has no such command "
                                     f"(no module {module})") from None
        extra = COMMANDS.get(name, (None, None))[1]
        hint = (f"pip install 'seahough[{extra}]'" if extra else
                "reinstall seahough with its dependencies")
        raise CommandUnavailable(f"{name}: {e.msg} ({hint})") from None


class _LazyGroup(click.Group):
    """A group whose commands are imported on first use.

    ``seahough --help`` lists them from :data:`COMMANDS` without importing
    any; commands added with :meth:`add_command` (or put in ``commands``)
    come first, as in a plain :class:`click.Group`.
    """

    _listing = False

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(set(self.commands) | set(COMMANDS))

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        cmd = self.commands.get(cmd_name)
        if cmd is not None or cmd_name not in COMMANDS:
            return cmd
        if self._listing:   # the help's list: a stand-in with the one-line help
            return click.Command(cmd_name, short_help=COMMANDS[cmd_name][0])
        cmd = load_command(cmd_name)
        self.add_command(cmd, cmd_name)
        return cmd

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        self._listing = True
        try:
            super().format_commands(ctx, formatter)
        finally:
            self._listing = False


@click.group(cls=_LazyGroup,
             context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(__version__, "--version", "-V", prog_name=PROG,
                      message="%(prog)s %(version)s")
def cli():
    """Find objects in underwater photos by the shape of their edges, and
    measure the camera's motion between photos (photo dead reckoning).

    \b
    Exit status: 0 success; 1 detect: the pattern was not found in some
    image, odometry: some frames are flagged; 2 bad input (missing or
    unreadable file, bad parameter), one line on stderr.
    Try `seahough demo` for a tour that needs no files.
    """




_TERM_MESSAGE = ("terminated (SIGTERM); what was done is kept (seahough survey: the same "
                 "command goes on where it stopped; seahough odometry: the same command "
                 "with --resume)")


#: A second interruption within this many seconds of the first is the same
#: one sent twice (``timeout`` signals the command, then its process group)
#: and is ignored while the first one's ``finally`` clauses save the work; a
#: later one (Ctrl-C pressed again) stops at once.
_REPEAT_S = 3.0
_first_signal: list = []


def _on_signal(signum, frame):
    """SIGINT: KeyboardInterrupt; SIGTERM: :class:`_Terminated`. Only the
    first: a repeat within :data:`_REPEAT_S` is ignored (it interrupted the
    saving of a survey's shard: the work done was lost, or the cluster's
    shutdown hung), a later one ends the process at once."""
    now = time.monotonic()
    if _first_signal:
        if now - _first_signal[0] < _REPEAT_S:
            return
        try:   # (not click.echo: stderr may be mid-write, or a closed pipe)
            os.write(2, b"seahough: error: interrupted again: stopping at once (what was not "
                        b"yet saved is lost)\n")
        finally:
            os._exit(130 if signum == signal.SIGINT else 143)
    _first_signal.append(now)
    raise KeyboardInterrupt() if signum == signal.SIGINT else _Terminated()


def _catch_signals() -> dict:
    """Install :func:`_on_signal` for SIGINT and SIGTERM (main thread only;
    a signal the caller ignores stays ignored); returns the old handlers."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    _first_signal.clear()
    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            if signal.getsignal(sig) is signal.SIG_IGN:   # (the caller's choice)
                continue
            old[sig] = signal.signal(sig, _on_signal)
        except (ValueError, OSError):   # pragma: no cover  (no signals here)
            pass
    return old


def main(argv=None) -> None:
    """Entry point of the ``seahough`` command (and ``python -m seahough``).

    Runs the command line ``argv`` (default: ``sys.argv[1:]``) and exits
    with its status (``SystemExit``): 0 success, 1 not found or flagged,
    2 bad input (one line on stderr), 130 interrupted (Ctrl-C), 143
    terminated (SIGTERM: handled as Ctrl-C is, what was done is kept).

    Examples
    --------
    >>> try:
    ...     main(["frobnicate"])         # "seahough: error: No such command ..." on stderr
    ... except SystemExit as e:
    ...     print("exit status", e.code)
    exit status 2
    """
    global _PYTHON_SHOWWARNING
    old = _catch_signals()
    shown = _PYTHON_SHOWWARNING = warnings.showwarning
    warnings.showwarning = _show_warning
    try:
        rv = _run(argv)
    finally:
        warnings.showwarning = shown
        for sig, handler in old.items():
            signal.signal(sig, handler)
    sys.exit(rv)


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning about an input on the command line: one line, ``seahough:
    warning: ...`` (not the Python form, "FILE:LINE: Category: message",
    whose file and line are the command's own); others as Python shows them."""
    from ..errors import BitDepthWarning, LevelsWarning

    if issubclass(category, (BitDepthWarning, LevelsWarning)):
        click.echo(f"{PROG}: warning: {' '.join(str(message).split())}", err=True)
    else:
        _PYTHON_SHOWWARNING(message, category, filename, lineno, file, line)


_PYTHON_SHOWWARNING = warnings.showwarning


def _run(argv) -> int:
    """The command line's exit status (:func:`main`)."""
    try:
        rv = cli.main(args=argv, prog_name=PROG, standalone_mode=False)
    except click.exceptions.NoArgsIsHelpError as e:
        click.echo(e.ctx.get_help())
        rv = 0
    except click.ClickException as e:
        msg = e.format_message()
        ctx = getattr(e, "ctx", None)
        if isinstance(e, click.UsageError) and ctx is not None:
            msg += f" (see '{ctx.command_path} --help')"
        _err(msg)
        rv = e.exit_code
    except _Terminated as e:   # (a command may say what it kept, as for Ctrl-C)
        _err(f"terminated (SIGTERM): {e.args[0]}" if e.args and e.args[0] else _TERM_MESSAGE)
        rv = 143
    except (click.exceptions.Abort, KeyboardInterrupt) as e:
        # (a command may say what it kept: a survey's images searched)
        ki = e if isinstance(e, KeyboardInterrupt) else e.__cause__   # (click's Abort wraps it)
        said = ki.args[0] if isinstance(ki, KeyboardInterrupt) and ki.args else ""
        _err(f"interrupted: {said}" if said else "interrupted")
        rv = 130
    except SystemError as e:
        # Ctrl-C inside a compiled (Numba) kernel: the KeyboardInterrupt is
        # raised while its results are converted, and surfaces as a
        # SystemError ("returned a result with an exception set") caused by it
        if _interrupted(e, _Terminated):
            _err(_TERM_MESSAGE)
            rv = 143
        elif not _interrupted(e):
            raise
        else:
            click.echo(err=True)  # as click does for a KeyboardInterrupt (after the ^C)
            _err("interrupted")
            rv = 130
    except (_Fail, SeahoughError) as e:
        _err(str(e))
        rv = 2
    except BrokenPipeError:
        # the reader went away (e.g. `| head`): stop quietly
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except OSError:
            pass
        rv = 141
    except OSError as e:
        where = f"{e.filename}: " if getattr(e, "filename", None) else ""
        _err(f"{where}{e.strerror or e}")
        rv = 2
    return rv if isinstance(rv, int) else 0


if __name__ == "__main__":  # pragma: no cover
    main()
