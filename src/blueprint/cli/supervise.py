"""The program as two processes, so that Ctrl-C stops it at once in every phase: the command
runs in a child, in a process group of its own with a scratch folder of its own as ``TMPDIR``;
the parent only waits. A NumPy call or a GL call holds the interpreter for as long as it runs
(a sort of 60 M keys, a draw of 20 M triangles on llvmpipe), and Python runs a signal's handler
only between calls, so the child could not be asked to stop; the parent, idle in ``waitpid``,
takes SIGINT at once, kills the child's whole group (the STEP mesher, ffmpeg and Dask's
workers with it), removes the scratch folder, prints ``blueprint: interrupted`` and exits 130.
Outputs are published whole by ``blueprint.export.files`` from unnamed temporaries, which die
with the process that holds them, so a killed child leaves no partial output.
"""

from __future__ import annotations

import os
import shutil
import signal
import sys
import tempfile
from collections.abc import Callable

__all__ = ["INTERRUPTED", "supervised"]

INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a command stopped by Ctrl-C
_STOPS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class _Stopped(Exception):
    def __init__(self, signum: int) -> None:
        self.signum = signum


def _stop(signum, frame) -> None:
    raise _Stopped(signum)


def supervised(work: Callable[[], None]) -> None:
    """Run ``work`` (which ends by ``sys.exit``) in a child process and exit as it did; SIGINT,
    SIGTERM or SIGHUP to this process kill the child's process group and exit with 128 plus
    the signal (SIGINT with the one line ``blueprint: interrupted``). Ctrl-Z stops both."""
    scratch = tempfile.mkdtemp(prefix="blueprint-")
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    child = os.fork()
    if child == 0:
        os.setpgid(0, 0)
        # temporaries of the child and of its own children (the STEP mesher's folder, Dask's
        # spill) go where the parent removes them, however the child ends
        os.environ["TMPDIR"] = tempfile.tempdir = scratch
        work()
        return
    # set on both sides of the fork: whichever runs first, the group exists before a kill
    try:
        os.setpgid(child, child)
    except (PermissionError, ProcessLookupError):
        pass  # the child set it already, or has exec'd or exited
    for signum in _STOPS:
        signal.signal(signum, _stop)
    signal.signal(signal.SIGTSTP, _suspend(child))
    try:
        status = _wait(child)
    except (_Stopped, KeyboardInterrupt) as stopped:
        status = None
        signum = stopped.signum if isinstance(stopped, _Stopped) else signal.SIGINT
    # from here on this process only cleans up and exits, whatever else it is sent
    for stop in _STOPS:
        signal.signal(stop, signal.SIG_IGN)
    if status is None:
        _kill(child)
        shutil.rmtree(scratch, ignore_errors=True)
        _restore_terminal()
        if signum == signal.SIGINT:
            print("blueprint: interrupted", file=sys.stderr, flush=True)
        os._exit(128 + signum)
    shutil.rmtree(scratch, ignore_errors=True)
    code = os.waitstatus_to_exitcode(status)
    if code < 0:  # killed by a signal: the kernel's out-of-memory killer sends SIGKILL
        _restore_terminal()
        name = signal.Signals(-code).name
        print(f"blueprint: error: the drawing was killed ({name})", file=sys.stderr, flush=True)
        code = 128 - code
    # the parent holds nothing to clean up; its exit handlers would report on the child's behalf
    os._exit(code)


def _wait(child: int) -> int:
    """The child's wait status, waiting through its stops (Ctrl-Z)."""
    while True:
        pid, status = os.waitpid(child, os.WUNTRACED)
        if pid == child and not os.WIFSTOPPED(status):
            return status


def _kill(child: int) -> None:
    """Kill the child's process group, then reap the child."""
    try:
        os.killpg(child, signal.SIGKILL)
    except ProcessLookupError:
        pass
    try:
        os.waitpid(child, 0)
    except ChildProcessError:
        pass


def _suspend(child: int):
    """A SIGTSTP handler: the child's group is stopped with this process (the terminal's
    Ctrl-Z reaches only this one, the group in front) and continued with it."""

    def handler(signum, frame) -> None:
        os.killpg(child, signal.SIGSTOP)
        signal.signal(signal.SIGTSTP, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTSTP)
        # running again (SIGCONT)
        signal.signal(signal.SIGTSTP, handler)
        os.killpg(child, signal.SIGCONT)

    return handler


def _restore_terminal() -> None:
    """Clear the progress bar's line and show the cursor the killed child's bar hid."""
    if sys.stderr.isatty():
        sys.stderr.write("\r\x1b[2K\x1b[?25h")
        sys.stderr.flush()
