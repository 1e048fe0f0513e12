"""One line for every expected failure: the message the CLI prints before exiting with status 1.

Also the CLI's standard output: a failure to write it (a full device, ``> /dev/full``) is one line naming
standard output, and a reader that went away (``| head -0``) ends the command quietly with status 1; after
either, stdout is pointed at the null device so that the interpreter's final flush cannot fail again.
"""

from __future__ import annotations

import errno
import os
import sys

__all__ = ["one_line_message", "write_stdout", "stdout_failure", "STDOUT_NAME"]

STDOUT_NAME = "standard output"


def one_line_message(exc: BaseException) -> str:
    """The user-facing one-line message of an expected failure.

    A `GyrodriftError` already carries its message (file, row, column, option). An `OSError` is described
    by its path(s) and a plain reason, e.g. ``out/model.json: read-only file system``.
    """
    from gyrodrift.files.output_errors import os_error_reason

    if isinstance(exc, OSError) and not _has_own_message(exc) and (exc.errno is not None or exc.filename):
        reason = os_error_reason(exc)
        paths = [p for p in (exc.filename, exc.filename2) if p is not None]
        where = " -> ".join(os.fsdecode(p) for p in paths)
        return f"{where}: {reason}" if where else reason
    text = str(exc).strip()
    return " ".join(text.split()) if text else type(exc).__name__


def _has_own_message(exc: OSError) -> bool:
    """True for the package's own OSError subclasses, whose message is already written for the user."""
    from gyrodrift.errors import GyrodriftError

    return isinstance(exc, GyrodriftError)


def _silence_stdout() -> None:
    try:
        fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, sys.stdout.fileno())
        os.close(fd)
    except (OSError, ValueError, AttributeError):  # pragma: no cover - stdout without a descriptor
        pass


def _raised_by_echo_to_stdout(exc: BaseException) -> bool:
    """True if `exc` came out of ``click.echo`` writing to standard output (its stream is fd 1 or "<stdout>")."""
    tb = exc.__traceback__
    while tb is not None:
        code = tb.tb_frame.f_code
        if code.co_name == "echo" and os.path.join("click", "utils.py") in code.co_filename:
            stream = tb.tb_frame.f_locals.get("file")
            try:
                return stream is not None and (getattr(stream, "name", None) == "<stdout>" or stream.fileno() == 1)
            except (OSError, ValueError):
                return False
        tb = tb.tb_next
    return False


def stdout_failure(exc: OSError | None = None) -> OSError | None:
    """If standard output cannot be written (`exc` came from writing it, or flushing it fails now), silence
    it and return the error to report: an `OSError` naming standard output, with ``errno`` EPIPE when the
    reader went away. None if stdout is fine."""
    failure = exc if exc is not None and (exc.errno == errno.EPIPE or _raised_by_echo_to_stdout(exc)) else None
    if failure is None:
        try:
            sys.stdout.flush()
        except OSError as flush_error:
            failure = flush_error
        except ValueError:  # pragma: no cover - stdout closed
            return None
    if failure is None:
        return None
    _silence_stdout()
    return OSError(failure.errno, failure.strerror or str(failure), STDOUT_NAME)


def write_stdout(text: str) -> None:
    """Write `text` to standard output and flush it, so that a failure happens here, inside the command."""
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except OSError as exc:
        raise (stdout_failure(exc) or OSError(exc.errno, exc.strerror, STDOUT_NAME)) from None
