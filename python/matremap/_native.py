"""Loading libmatremap.so.0 and the C declarations the package calls (ctypes; no compiled extension)."""
import ctypes
import ctypes.util
import os

_HERE = os.path.dirname(os.path.abspath(__file__))
_SONAME = "libmatremap.so.0"


class Image(ctypes.Structure):
    """struct mr_image (src/mr_image.h): width, height, channels, float *pixels."""
    _fields_ = [("width", ctypes.c_int), ("height", ctypes.c_int), ("channels", ctypes.c_int),
                ("pixels", ctypes.POINTER(ctypes.c_float))]


class SsimOptions(ctypes.Structure):
    """struct mr_ssim_options (src/metrics/metrics.h)."""
    _fields_ = [("exposure", ctypes.c_double), ("downsample", ctypes.c_int), ("mask", ctypes.POINTER(Image)),
                ("threads", ctypes.c_int)]


class ReadOptions(ctypes.Structure):
    """struct mr_img_read_options (src/io/image_io.h)."""
    _fields_ = [("encoding", ctypes.c_int), ("channels", ctypes.c_int), ("max_dimension", ctypes.c_int)]


class WriteOptions(ctypes.Structure):
    """struct mr_img_write_options (src/io/image_io.h)."""
    _fields_ = [("encoding", ctypes.c_int), ("bits", ctypes.c_int), ("jpeg_quality", ctypes.c_int)]


class LearnedHead(ctypes.Structure):
    """The first fields of struct mr_learned (src/learn/learned.h): its source and target models, whose first
    field is the name (struct mr_brdf_model, src/brdf/brdf.h)."""
    _fields_ = [("source", ctypes.POINTER(ctypes.c_char_p)), ("target", ctypes.POINTER(ctypes.c_char_p))]


def _candidates():
    """Where the library is looked for, in order (docs/python.md, "Install")."""
    found = []
    env = os.environ.get("MATREMAP_LIBRARY")
    if env:
        return [env]
    # The source tree: python/matremap -> build/lib (MATREMAP_BUILD names another build directory).
    tree = os.path.dirname(os.path.dirname(_HERE))
    if os.path.isfile(os.path.join(tree, "Makefile")) and os.path.isdir(os.path.join(tree, "src")):
        build = os.environ.get("MATREMAP_BUILD", os.path.join(tree, "build"))
        found.append(os.path.join(build, "lib", _SONAME))
    # An installed package: the prefix `make install` wrote into _config.py, then PREFIX/lib/pythonX.Y/... ->
    # PREFIX/lib.
    try:
        from . import _config
        found.append(os.path.join(_config.LIBDIR, _SONAME))
    except ImportError:
        pass
    found.append(os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(_HERE))), _SONAME))
    name = ctypes.util.find_library("matremap")
    found.append(name if name else _SONAME)
    return found


def _load():
    tried = []
    for path in _candidates():
        if os.path.isabs(path) and not os.path.exists(path):
            tried.append(path)
            continue
        try:
            return ctypes.CDLL(path), path
        except OSError as e:
            tried.append("%s (%s)" % (path, e))
    raise ImportError("matremap: cannot load %s; tried %s. Build it (make) or set MATREMAP_LIBRARY to its path"
                      % (_SONAME, ", ".join(tried)))


lib, path = _load()

_c = ctypes
_str = _c.c_char_p
_strs = _c.POINTER(_c.c_char_p)
_img = _c.POINTER(Image)
_decl = {
    "mr_version": (_str, []),
    "mr_last_error": (_str, []),
    "mr_api_free": (None, [_c.c_void_p]),
    "mr_api_models_json": (_c.c_int, [_c.POINTER(_c.c_void_p)]),
    "mr_api_render": (_c.c_int, [_str, _strs, _c.c_int, _c.c_int, _str, _str, _str, _c.c_int, _img]),
    "mr_api_remap": (_c.c_int, [_str, _strs, _c.c_int, _str, _strs, _c.c_int, _c.c_int, _str, _str, _str, _str, _str,
                                _c.c_int, _c.POINTER(_c.c_void_p)]),
    "mr_api_transform_describe": (_c.c_int, [_str, _str, _str, _c.POINTER(_c.c_void_p)]),
    "mr_api_transform_convert": (_c.c_int, [_str, _str, _str, _c.c_double, _c.c_int, _c.POINTER(_img),
                                            _c.POINTER(_img)]),
    "mr_api_gltf_convert": (_c.c_int, [_str, _str, _str, _str, _c.c_int, _c.c_int, _c.POINTER(_c.c_void_p)]),
    "mr_learned_read": (_c.c_int, [_str, _c.POINTER(_c.c_void_p)]),
    "mr_learned_free": (None, [_c.c_void_p]),
    "mr_learned_apply_batch": (_c.c_int, [_c.c_void_p, _c.c_size_t, _c.POINTER(_c.c_double),
                                          _c.POINTER(_c.c_double), _c.POINTER(_c.c_uint)]),
    "mr_api_report": (_c.c_int, [_strs, _strs, _c.c_int, _str, _c.c_int, _str, _c.c_int, _c.c_int, _str]),
    "mr_ssim": (_c.c_int, [_img, _img, _c.POINTER(SsimOptions), _c.POINTER(_c.c_double), _c.POINTER(_img)]),
    "mr_image_free": (None, [_img]),
    "mr_img_read": (_c.c_int, [_str, _c.POINTER(ReadOptions), _c.POINTER(_img)]),
    "mr_img_write": (_c.c_int, [_str, _img, _c.POINTER(WriteOptions)]),
}
for _name, (_res, _args) in _decl.items():
    _f = getattr(lib, _name)
    _f.restype = _res
    _f.argtypes = _args
