"""How the add-on finds the `matremap` Python package and its library (docs/blender-addon.md).

The package: the copy bundled in this add-on's `_vendor/` folder (put there by `make`, the one the add-on was
built and tested with), else an installed `matremap` on Blender's sys.path (`make install`).

The library (libmatremap.so.0), the first of:
  1. the add-on preference "Library" (a path),
  2. $MATREMAP_LIBRARY,
  3. the package's own lookup (the installed PREFIX/lib, ldconfig),
  4. the build tree that made the zip (recorded in _build.py by `make`), if it still exists.
"""

import importlib
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
VENDOR = os.path.join(HERE, "_vendor")

_state = {"module": None, "error": None, "library": None}


def _build_hint():
    try:
        from . import _build
    except ImportError:
        return None
    path = getattr(_build, "LIBRARY", None)
    return path if path and os.path.isfile(path) else None


def _drop_loaded():
    for name in [n for n in sys.modules if n == "matremap" or n.startswith("matremap.")]:
        del sys.modules[name]


def _import():
    """Imports matremap, the bundled copy first; returns the module (raises what the import raises)."""
    bundled = os.path.isdir(os.path.join(VENDOR, "matremap"))
    if bundled:
        sys.path.insert(0, VENDOR)
    try:
        return importlib.import_module("matremap")
    finally:
        if bundled and VENDOR in sys.path:
            sys.path.remove(VENDOR)


def load(library=""):
    """The matremap module, or None with error() saying why. LIBRARY (the preference) wins over the rest."""
    if _state["module"] is not None:
        return _state["module"]
    if _state["error"] is not None:  # failed already: panels redraw often; reset() (the preference) tries again
        return None
    previous = os.environ.get("MATREMAP_LIBRARY")
    if library:
        os.environ["MATREMAP_LIBRARY"] = bpy_abspath(library)
    try:
        mod = _import()
        mod.version()  # the library really loads and answers
    except Exception as exc:  # the package's own lookup failed: try the build tree that made the zip
        hint = _build_hint()
        _drop_loaded()
        if library or previous or hint is None:
            _restore(previous, library)
            _state["error"] = "cannot load matremap: %s" % exc
            return None
        os.environ["MATREMAP_LIBRARY"] = hint
        try:
            mod = _import()
            mod.version()
        except Exception as exc2:
            _drop_loaded()
            _restore(previous, True)
            _state["error"] = "cannot load matremap: %s (and with the build tree's %s: %s)" % (exc, hint, exc2)
            return None
    _state["module"] = mod
    _state["error"] = None
    _state["library"] = os.environ.get("MATREMAP_LIBRARY") or "(the package's own lookup)"
    return mod


def _restore(previous, changed):
    if not changed:
        return
    if previous is None:
        os.environ.pop("MATREMAP_LIBRARY", None)
    else:
        os.environ["MATREMAP_LIBRARY"] = previous


def bpy_abspath(path):
    try:
        import bpy
        return bpy.path.abspath(path)
    except ImportError:
        return path


def error():
    return _state["error"]


def where():
    mod = _state["module"]
    if mod is None:
        return None
    return "matremap %s from %s, library %s" % (mod.version(), os.path.dirname(mod.__file__), _state["library"])


def reset():
    """Forgets the loaded package (after the preference changed); the next load() imports it again."""
    _drop_loaded()
    _state.update(module=None, error=None, library=None)
