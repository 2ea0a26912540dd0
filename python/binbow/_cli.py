"""The `binbow` command of the Python package: the C++ CLI itself.

The console script `binbow` and `python -m binbow` replace this Python process
with the compiled `binbow` executable installed with the package (os.execv),
rather than calling the CLI's main inside the extension module or running it
as a child process. Replaced, the process *is* the CLI: its exit status,
stdout and stderr reach the caller unchanged, Ctrl-C and other signals go to
it and end it as they end the C++ command, no interpreter stays in between,
and the CLI finds its bundled vocabularies and sample frames relative to its
own executable (<exe>/../share/binbow) exactly as when installed by CMake.
Inside the extension none of that would hold: Python's SIGINT handler would
turn Ctrl-C into a KeyboardInterrupt only after the C++ call returns, C and
Python buffers would interleave, and the executable found from
/proc/self/exe would be the interpreter.
"""
import os
import signal
import sys

from . import _data_location


def executable():
    """The path of the binbow CLI installed with this package."""
    package = os.path.dirname(os.path.abspath(__file__))
    return os.path.normpath(os.path.join(package, _data_location.CLI_EXECUTABLE))


def main():
    path = executable()
    if not os.access(path, os.X_OK):
        sys.stderr.write(
            f"binbow: error: {path}: the binbow command is not installed with this Python "
            "package; reinstall it (pip install builds it) or run a binbow built with CMake\n"
        )
        return 1
    # Python ignores SIGPIPE and SIGXFSZ for itself; an exec'd program would
    # inherit that, so `binbow ... | head` would end with write errors instead
    # of quietly, as the C++ command does.
    for name in ("SIGPIPE", "SIGXFSZ"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        os.execv(path, ["binbow", *sys.argv[1:]])
    except OSError as error:
        sys.stderr.write(f"binbow: error: cannot run {path}: {error.strerror}\n")
        return 1
