"""python3 -m matremap ARGS...: the matremap command line (the `matremap` executable beside the library found,
build/bin or PREFIX/bin, run in this process's place; MATREMAP_CLI names another)."""
import os
import sys

from . import _native


def main():
    exe = os.environ.get("MATREMAP_CLI") or os.path.join(os.path.dirname(os.path.dirname(os.path.realpath(
        _native.path))), "bin", "matremap")
    if not os.access(exe, os.X_OK):
        sys.stderr.write("python3 -m matremap: the matremap executable is not at %s (set MATREMAP_CLI)\n" % exe)
        return 3
    os.execv(exe, ["matremap"] + sys.argv[1:])


if __name__ == "__main__":
    sys.exit(main())
