"""Errors every part of hand_codesign shares."""

import os
import select
import sys

# The status of a process that SIGPIPE ended, which `cmd | head` reports for programs that
# keep the signal's default action; Python ignores SIGPIPE and gets BrokenPipeError instead.
CLOSED_STDOUT_STATUS = 141


class UserError(Exception):
    """A mistake of the user's (bad file, bad flag): printed as one clear line, no traceback."""


def closed_stdout_status(error):
    """
    Return the exit status for a BrokenPipeError raised because stdout's reader has gone.

    `hand-codesign ... | head` closes the pipe once head has its lines; that is the user's
    choice to stop reading, so the process ends quietly (stdout pointed at /dev/null, so the
    flush at exit does not raise again) with the status a SIGPIPE would give. A BrokenPipeError
    from another pipe (to a child process) is a real failure: re-raised.

    error: the BrokenPipeError caught by an entry point.
    """
    if not _stdout_reader_has_gone():
        raise error
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    return CLOSED_STDOUT_STATUS


def _stdout_reader_has_gone():
    """Return True if stdout is a pipe whose reading end is closed (poll reports POLLERR)."""
    poller = select.poll()
    poller.register(sys.stdout.fileno(), select.POLLOUT)
    return any(events & select.POLLERR for _, events in poller.poll(0))
