"""The ``mobmanip`` command.

Each subcommand lives in :mod:`mobmanip.commands` and registers itself. Every error caused by
bad input prints one line ``mobmanip: error: ...`` on standard error and exits with code 2.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import signal
import sys
import threading
import time
import warnings

# Only the standard library at module level: the console script imports this module, and
# Ctrl-C while NumPy or Pinocchio is still loading must end in one line too (see main).


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit code 2)."""

    def error(self, message):  # noqa: D401 - argparse API
        self.exit(2, f"mobmanip: error: {message}\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``mobmanip`` parser: every subcommand, or only ``command`` (a name as typed).

    A command line names one command, and its parser is all :func:`main` needs: the other
    commands' modules (and what they import) are then not imported, which keeps a command's
    start-up short. Without a command (``--help``, ``--version``, a typo) every command is
    registered, so the help lists them all and an unknown name is refused with the full list.
    """
    from .commands import NAMES, command_module

    parser = _Parser(prog="mobmanip", description="What a wheeled mobile manipulator can do at the end effector.")
    parser.add_argument("--version", action=_VersionAction, help="show program's version number and exit")
    parser.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="say what is being done on standard error (-vv: in more detail); quiet by default",
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    for name in [command] if command in NAMES else NAMES:
        command_module(name).register(sub)
    return parser


class _VersionAction(argparse.Action):
    """``--version``: the installed version, read only when asked for (reading the installed
    distribution's metadata costs every other command line its time)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings=option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from .support.version import installed_version

        parser._print_message(f"mobmanip {installed_version()}\n", sys.stdout)
        parser.exit()


def command_named(argv: list[str]) -> str | None:
    """The command an argument list names: its first word when only ``-v``/``--verbose`` come
    before it (``None`` otherwise, e.g. ``--help`` first: then every command is registered)."""
    for word in argv:
        if not word.startswith("-"):
            return word
        if word != "--verbose" and not (len(word) > 1 and set(word[1:]) == {"v"}):
            return None
    return None


def main(argv: list[str] | None = None) -> int:
    """Run the command; every failure is one ``mobmanip: error: ...`` line and exit code 2.

    Files given as inputs are never replaced by outputs, and the files a command writes are
    published together once it has succeeded (none if it fails midway). NumPy's floating-point
    warnings (overflow, division by zero, invalid value) are not shown: inputs outside the
    ranges mobmanip supports are refused with a message of their own, and no result that is not
    finite is printed or written. A failure that is not one of mobmanip's
    errors (a bug) is reported in one line too, saying so; set ``MOBMANIP_TRACEBACK=1`` in the
    environment to see its traceback instead.

    Ctrl-C and SIGTERM end the run with one line at any moment, including while the packages
    mobmanip needs are still being imported (this module imports them only here). Called from
    Python, ``main`` then returns 130 (Ctrl-C) or 143 (SIGTERM). Called as the program (``argv``
    None: the console script and ``python -m mobmanip``), SIGTERM exits with 143 and Ctrl-C
    ends the process by SIGINT itself once Python has shut down, as Python does for an
    interrupted program: the shell reports 130, and a shell script running mobmanip in a loop
    stops too (a plain exit code of 130 would let it go on). Ctrl-C or SIGTERM after the
    command has returned (while its outputs are published, and while Python shuts down) is
    ignored: its outputs are complete.

    The command runs with one thread in each BLAS and OpenMP pool, and so do the worker
    processes it starts (:func:`mobmanip.support.threads.limit_threads`: its matrices are small,
    and its parallel work runs in processes); a pool the user sized in the environment
    (``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS``, ...) keeps that size. Called from Python,
    ``main`` leaves the environment and the pools already loaded as it found them.
    """
    program = argv is None and threading.current_thread() is threading.main_thread()
    if program:
        sys.excepthook = _quiet_interrupts(sys.excepthook)
        sys.unraisablehook = _redeliver_interrupts(sys.unraisablehook)
    _RECEIVED.clear()
    _FINISHED.clear()
    from .support.threads import limit_threads

    try:
        with _terminate_as_interrupt(), limit_threads():
            try:
                return _main(argv)
            except Exception:
                if _RECEIVED:  # an interrupt that a library turned into an error of its own
                    raise _interrupt_received() from None
                raise
    except Terminated:
        return _interrupted("mobmanip: terminated; no output was written", 128 + signal.SIGTERM)
    except KeyboardInterrupt:
        code = _interrupted("mobmanip: interrupted; no output was written", 130)
        if program:
            raise  # Python ends the process by SIGINT after its shutdown; the hook prints nothing
        return code
    finally:
        if program:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)


def _interrupted(line: str, code: int) -> int:
    """Say that the run was interrupted (a closed standard error is no reason for a traceback)."""
    with contextlib.suppress(OSError, ValueError):
        print(line, file=sys.stderr)
    return code


def _quiet_interrupts(previous):
    """``sys.excepthook`` that prints nothing for an interrupt (its one line is printed already)."""

    def hook(kind, value, traceback):
        if not issubclass(kind, KeyboardInterrupt):
            previous(kind, value, traceback)

    return hook


def _redeliver_interrupts(previous):
    """``sys.unraisablehook`` that passes on a signal Python could not raise where it arrived.

    Ctrl-C or SIGTERM that arrives while a finaliser or a garbage-collector callback runs (e.g.
    one of matplotlib's weak references) raises in that callback, where Python cannot propagate
    it: it would print "Exception ignored in ..." with a traceback and carry on as if nothing
    had happened. The hook has the same signal sent to the main thread again a moment later,
    from a helper thread (sent from the hook itself, it would be raised inside the hook and be
    swallowed the same way), so it ends the run in its one line from the command's own code.
    """

    def hook(unraisable):
        kind = unraisable.exc_type
        if kind is None or not issubclass(kind, KeyboardInterrupt):
            previous(unraisable)
            return
        signum = signal.SIGTERM if issubclass(kind, Terminated) else signal.SIGINT
        main = threading.main_thread().ident
        assert main is not None

        def resend():
            time.sleep(0.01)  # until the hook has returned
            signal.pthread_kill(main, signum)

        threading.Thread(target=resend, name="mobmanip-resend-signal", daemon=True).start()

    return hook


def _main(argv: list[str] | None) -> int:
    parser = build_parser(command_named(sys.argv[1:] if argv is None else argv))
    with _escaped_output():
        args = _parse(parser, argv)
        _configure_logging(args.verbose)
        return _run(args)


def _parse(parser: argparse.ArgumentParser, argv: list[str] | None) -> argparse.Namespace:
    """``parser.parse_args(argv)``, except that a command's optional positional given after its
    options is taken: argparse matches ``retime ROBOT --ground TRAJ.csv``'s TRAJ.csv to nothing
    when it reads ROBOT, then refused TRAJ.csv as an unrecognized argument."""
    args, extra = parser.parse_known_args(argv)
    if extra and not extra[0].startswith("-"):
        commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        for action in commands.choices[args.command]._get_positional_actions():
            if extra and action.nargs == "?" and getattr(args, action.dest) is None and not extra[0].startswith("-"):
                setattr(args, action.dest, extra.pop(0))
    if extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    return args


@contextlib.contextmanager
def _escaped_output():
    """Standard output and error escape the control characters of what is printed (a robot
    named with ESC or BEL bytes must not drive the user's terminal)."""
    from .support.text import EscapingStream

    stdout, stderr = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = EscapingStream(stdout), EscapingStream(stderr)
    try:
        yield
    finally:
        sys.stdout, sys.stderr = stdout, stderr


def _run(args) -> int:
    import numpy as np

    from .errors import MobmanipError
    from .support.files import protect_inputs, publish_together
    from .support.notices import notice_session

    try:
        # A command's output files are published together when it succeeds, all or none.
        with (
            warnings.catch_warnings(),
            np.errstate(all="ignore"),
            protect_inputs(),
            publish_together(),
            notice_session(),
        ):
            warnings.simplefilter("ignore", RuntimeWarning)
            _check_outputs_first(args)
            code = args.func(args)
            _FINISHED.append(True)  # its "wrote ..." lines are out: publish them, whatever arrives now
        _log_thread_pools()
        return code
    except MobmanipError as exc:
        if _RECEIVED:  # e.g. "install xacro" after the import of xacro was interrupted
            raise _interrupt_received() from None
        return _fail(str(exc))
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return 0
    except RecursionError:
        return _fail("an input is nested too deeply to read")
    except MemoryError:
        return _fail("out of memory: the request is too large for this machine")
    except Exception as exc:
        if _RECEIVED:  # an interrupt that a library turned into an error of its own
            raise _interrupt_received() from None
        if os.environ.get("MOBMANIP_TRACEBACK"):
            raise
        return _fail(f"internal error ({type(exc).__name__}: {exc}); please report it with the command that caused it")


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so the same clean-up runs (temporary files and created
    directories removed, nothing published)."""


#: The signals received during the current :func:`main` call (SIGINT, SIGTERM), in order.
_RECEIVED: list[int] = []
#: Not empty once the current command has returned: the outputs it has said it wrote are then
#: published and the run ends as finished, a signal from then on ignored (as during Python's
#: shutdown). Before, an interrupt that arrived while the files were being published ended the
#: run as interrupted with none written, after the command had printed "wrote ...".
_FINISHED: list[bool] = []


def _interrupt_received() -> KeyboardInterrupt:
    """The interrupt to raise in place of an error that followed a signal: an extension module
    whose import was interrupted reports "ImportError: initialization failed", and other
    libraries may turn a KeyboardInterrupt into an error of their own."""
    return Terminated() if _RECEIVED[-1] == signal.SIGTERM else KeyboardInterrupt()


@contextlib.contextmanager
def _terminate_as_interrupt():
    """While a command runs in the main thread, SIGTERM raises :class:`Terminated` and Ctrl-C
    KeyboardInterrupt, as Python's own handler does; both are remembered in :data:`_RECEIVED`."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def terminate(signum, frame):
        if not _FINISHED:
            _RECEIVED.append(signal.SIGTERM)
            raise Terminated()

    def interrupt(signum, frame):
        if not _FINISHED:
            _RECEIVED.append(signal.SIGINT)
            raise KeyboardInterrupt()

    previous = signal.signal(signal.SIGTERM, terminate)
    previous_int = signal.getsignal(signal.SIGINT)
    if previous_int is signal.default_int_handler:  # not when SIGINT is ignored (e.g. a background job)
        signal.signal(signal.SIGINT, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
        if previous_int is signal.default_int_handler:
            signal.signal(signal.SIGINT, previous_int)


def _log_thread_pools() -> None:
    """With ``-vv``: the BLAS and OpenMP pools the command ran with, and their threads."""
    log = logging.getLogger("mobmanip.cli")
    if log.isEnabledFor(logging.DEBUG):
        from .support.threads import describe_pools

        log.debug("thread pools: %s", describe_pools())


def _configure_logging(verbosity: int) -> None:
    """Show mobmanip's log records on standard error: warnings only by default, ``-v`` adds
    what is being done (INFO), ``-vv`` the details (DEBUG)."""
    level = {0: logging.WARNING, 1: logging.INFO}.get(verbosity, logging.DEBUG)
    logger = logging.getLogger("mobmanip")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("mobmanip: %(levelname)s: %(message)s"))
    logger.handlers = [h for h in logger.handlers if not getattr(h, "_mobmanip_cli", False)]
    handler._mobmanip_cli = True  # type: ignore[attr-defined]
    logger.addHandler(handler)
    logger.setLevel(level)


#: Options that name one output file (a directory or prefix option is checked when written).
_OUTPUT_FILES = ("json", "save_q", "export")
#: Options that name a figure to write (its suffix must name a format matplotlib writes).
_FIGURE_FILES = ("figure", "plot")
#: Options that name an output directory or prefix: never taken for an input.
_OUTPUT_PLACES = ("out", "map", "output")


def _check_outputs_first(args) -> None:
    """Refuse a bad output file before any work: one that is also a file the command was
    given, or a directory, FIFO or device, or a figure of an unknown format (so a long
    computation is not thrown away)."""
    from .support.files import check_figure_output, check_output, note_input

    outputs = [(dest, getattr(args, dest, None)) for dest in (*_OUTPUT_FILES, *_FIGURE_FILES)]
    outputs = [(dest, value) for dest, value in outputs if isinstance(value, str) and value]
    for dest, value in vars(args).items():
        if dest in _OUTPUT_FILES or dest in _FIGURE_FILES or dest in _OUTPUT_PLACES:
            continue  # an output written by an earlier run is not an input of this one
        if isinstance(value, str) and os.path.isfile(value):
            note_input(value)
    for dest, path in outputs:
        if dest in _FIGURE_FILES:
            check_figure_output(path, "--" + dest.replace("_", "-"))
        else:
            check_output(path)


def _fail(message: str) -> int:
    """Print ``message`` as the one line ``mobmanip: error: ...`` on standard error; return 2."""
    line = " ".join(part.strip() for part in str(message).splitlines() if part.strip())
    print(f"mobmanip: error: {line}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main())
