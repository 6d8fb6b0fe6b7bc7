"""matremap — image-based remapping of material appearance, from Python (docs/python.md).

A ctypes layer over libmatremap.so.0 (no compiled extension: it loads in any Python 3 with NumPy, Blender's
included). Arrays in and out are NumPy float32, H x W x C, C-contiguous, linear values; an array already in that
form is passed to the library without a copy. Errors of the library raise matremap.Error with its message; bad
arrays raise ValueError naming the argument. Long calls release the GIL and take threads= (0 = automatic).
"""
import ctypes
import json
import math
import os

import numpy as np

from . import _native
from ._native import Image as _Image, lib as _lib

__all__ = ["Error", "Result", "Transform", "report", "version", "models", "render", "remap", "transform",
           "spec2metal", "metal2spec", "convert_gltf", "ssim", "ssim_map", "read_image", "write_image",
           "srgb_to_linear", "linear_to_srgb", "library_path"]

library_path = _native.path


class Error(RuntimeError):
    """A failed library call; str(e) is the library's one-line message (mr_last_error()), e.status its mr_status."""

    def __init__(self, message, status=0):
        RuntimeError.__init__(self, message)
        self.status = status


def _check(status):
    if status != 0:
        message = _lib.mr_last_error()
        raise Error(message.decode("utf-8", "replace") if message else "matremap: error %d" % status, status)


def _b(text):
    return None if text is None else str(text).encode("utf-8")


def _json_call(function, *args):
    out = ctypes.c_void_p()
    _check(function(*(args + (ctypes.byref(out),))))
    try:
        return json.loads(ctypes.string_at(out.value).decode("utf-8"))
    finally:
        _lib.mr_api_free(out)


def _strings(items):
    array = (ctypes.c_char_p * max(1, len(items)))()
    for k, item in enumerate(items):
        array[k] = item.encode("utf-8")
    return array


def version():
    """The library's version, "MAJOR.MINOR.PATCH"."""
    return _lib.mr_version().decode()


def models():
    """Every BRDF model: [{"name", "summary", "params": [{"name", "channels", "default", "min", "max", "role",
    "lobe", "fit", "meaning"}]}], as `matremap models --json` lists them."""
    return _json_call(_lib.mr_api_models_json)


# ---- arrays ---------------------------------------------------------------------------------------------------

def _as_image_array(a, name, channels=(1, 3, 4)):
    """`a` as a C-contiguous float32 array of shape (H, W, C) (a 2-D array is one channel), its values finite.
    Conversions: float32 as it is (no copy when C-contiguous); other floating types (float16, float64) to float32;
    uint8 and uint16 divided by 255 and 65535 (the stored code as a fraction, no sRGB decoding: use
    srgb_to_linear for colour). Anything else (bool, signed integers, complex, objects) is a ValueError."""
    if not isinstance(a, np.ndarray):
        try:
            a = np.asarray(a)
        except Exception:
            raise ValueError("%s: expected a NumPy array, got %s" % (name, type(a).__name__))
    if a.dtype == np.float32:
        pass
    elif a.dtype == np.uint8:
        a = a.astype(np.float32) / np.float32(255)
    elif a.dtype == np.uint16:
        a = a.astype(np.float32) / np.float32(65535)
    elif a.dtype.kind == "f":
        with np.errstate(over="ignore"):
            a = a.astype(np.float32)
    else:
        raise ValueError("%s: dtype %s is not accepted (float32; float16/float64 are converted, uint8/uint16 "
                         "scaled to [0, 1])" % (name, a.dtype))
    if a.ndim == 2:
        a = a[:, :, np.newaxis]
    if a.ndim != 3 or a.shape[2] not in channels or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError("%s: shape %s: expected (H, W) or (H, W, C) with C in %s" % (name, tuple(a.shape),
                                                                                     "/".join(map(str, channels))))
    a = np.ascontiguousarray(a)
    finite = np.isfinite(a)
    if not finite.all():
        y, x, c = np.argwhere(~finite)[0]
        raise ValueError("%s: pixel (%d, %d), channel %d holds %s: expected finite values"
                         % (name, x, y, c, a[y, x, c]))
    return a


def _wrap(a):
    """An mr_image over the array's own buffer (the array must stay alive while the struct is used)."""
    return _Image(a.shape[1], a.shape[0], a.shape[2], a.ctypes.data_as(ctypes.POINTER(ctypes.c_float)))


def srgb_to_linear(a):
    """sRGB-encoded values in [0, 1] (or uint8 codes) to linear float32 (IEC 61966-2-1's curve)."""
    a = np.asarray(a)
    a = a.astype(np.float32) / np.float32(255) if a.dtype == np.uint8 else a.astype(np.float32)
    return np.where(a <= 0.04045, a / 12.92, ((a + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(a):
    """Linear values to sRGB-encoded float32 in [0, 1] (clamped first)."""
    a = np.clip(np.asarray(a, dtype=np.float32), 0.0, 1.0)
    return np.where(a <= 0.0031308, a * 12.92, 1.055 * a ** (1.0 / 2.4) - 0.055).astype(np.float32)


# ---- materials as text ----------------------------------------------------------------------------------------

def _value_text(name, value):
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        raise ValueError("%s: expected a number or (r, g, b), got a bool" % name)
    values = [value] if np.ndim(value) == 0 else list(np.ravel(value))
    if len(values) not in (1, 3):
        raise ValueError("%s: expected a number or (r, g, b), got %d values" % (name, len(values)))
    out = []
    for v in values:
        v = float(v)
        if not math.isfinite(v):
            raise ValueError("%s: %r is not a finite number" % (name, v))
        out.append(repr(v))
    return ",".join(out)


def _assignments(params, what="params"):
    if params is None:
        return []
    if not isinstance(params, dict):
        raise ValueError("%s: expected a dict name -> value, got %s" % (what, type(params).__name__))
    return ["%s=%s" % (k, _value_text(k, v)) for k, v in params.items()]


def _threads(threads):
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or not 0 <= threads <= 1024:
        raise ValueError("threads: %r: expected an integer 0 .. 1024 (0 = automatic)" % (threads,))
    return int(threads)


# ---- render, remap --------------------------------------------------------------------------------------------

def render(model, size=64, light=None, env=None, threads=0, component="full", **params):
    """Render `model` with `params` (name=number, name=(r, g, b), or a string as the CLI takes it: "@map.png") in the
    paper's fit scene: a size x size float32 RGB array of linear radiance, the pixels `matremap render` writes.
    light: "45" (default) or "frontal"; env: an environment map file (then no point light unless light is given);
    component: "full", "diffuse" or "specular"."""
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or not 1 <= size <= 16384:
        raise ValueError("size: %r: expected an integer 1 .. 16384" % (size,))
    size = int(size)
    items = _assignments(params)
    out = np.empty((size, size, 3), dtype=np.float32)
    image = _wrap(out)
    _check(_lib.mr_api_render(_b(model), _strings(items), len(items), size, _b(light), _b(env), _b(component),
                              _threads(threads), ctypes.byref(image)))
    return out


class Result(object):
    """A remap's answer: values (name -> float or (r, g, b)), outcome, detail, rmse, relative_rmse, ssim, renders,
    seconds; json holds the whole answer as `matremap remap --json` prints it."""

    def __init__(self, answer):
        self.json = answer
        self.values = {k: tuple(v) if isinstance(v, list) else v for k, v in answer["values"].items()}
        for key in ("outcome", "detail", "rmse", "relative_rmse", "ssim", "renders", "seconds", "strategy"):
            setattr(self, key, answer[key])

    def __repr__(self):
        return "Result(%s, outcome=%r, ssim=%.4f)" % (self.values, self.outcome, self.ssim)


def _list_text(value, what, pairs=False):
    if value is None:
        return None
    if isinstance(value, str):
        return value
    if isinstance(value, dict):
        return ",".join("%s=%s" % (k, v if pairs else _value_text(k, v)) for k, v in value.items())
    try:
        return ",".join(str(v) for v in value)
    except TypeError:
        raise ValueError("%s: expected a string, a list of names or a dict" % what)


def remap(from_model, params, to_model, size=64, light="45", strategy="auto", hold=None, tie=None, free=None,
          threads=0, to_params=None):
    """Fit `to_model` to the look of `from_model` with `params` (dict), as `matremap remap --from ... --to ...`.
    hold: names ("alpha") or a dict name -> value the target keeps; tie: "target=source,..." or a dict; free: names
    of parameters the target model holds by default to fit too; to_params: the target's values for what is held."""
    src = _assignments(params)
    dst = _assignments(to_params, "to_params")
    answer = _json_call(_lib.mr_api_remap, _b(from_model), _strings(src), len(src), _b(to_model), _strings(dst),
                        len(dst), int(size or 0), _b(light), _b(strategy), _b(_list_text(hold, "hold")),
                        _b(_list_text(tie, "tie", pairs=True)), _b(_list_text(free, "free")), _threads(threads))
    return Result(answer)


# ---- transforms on arrays -------------------------------------------------------------------------------------

def transform(source, target, method, threads=0, f0=None, **maps):
    """Convert maps of workflow `source` into `target` through the transform `method` (`matremap spec2metal
    --list-methods`): keyword arrays named after the transform's inputs, all of one H x W (an RGB input takes
    (H, W, 3|4) or a grey (H, W); a scalar one (H, W) or (H, W, 1); a number or (r, g, b) is broadcast). Returns a
    dict output name -> array ((H, W, 3) or (H, W)), linear values."""
    kind = _json_call(_lib.mr_api_transform_describe, _b(source), _b(target), _b(method))
    names = [s["name"] for s in kind["inputs"]]
    unknown = [k for k in maps if k not in names]
    if unknown:
        raise ValueError("%s: not an input of %s -> %s %s (its inputs: %s)" % (unknown[0], source, target,
                                                                              kind["name"], ", ".join(names)))
    arrays, shape = {}, None
    for slot in kind["inputs"]:
        value = maps.get(slot["name"])
        if value is None:
            raise ValueError("%s: missing (inputs of %s: %s)" % (slot["name"], kind["name"], ", ".join(names)))
        if isinstance(value, np.ndarray) and value.ndim >= 2:
            a = _as_image_array(value, slot["name"], (1, 3, 4) if slot["channels"] == 3 else (1,))
            if shape is not None and a.shape[:2] != shape:
                raise ValueError("%s: shape %s differs from the other maps' %s" % (slot["name"], a.shape[:2], shape))
            shape = a.shape[:2]
            arrays[slot["name"]] = a
    if shape is None:
        shape = (1, 1)
    for slot in kind["inputs"]:
        if slot["name"] not in arrays:  # a constant: broadcast over the maps' size
            v = np.asarray(maps[slot["name"]], dtype=np.float64).ravel()
            if v.size not in ((1, 3) if slot["channels"] == 3 else (1,)):
                raise ValueError("%s: expected an array, a number%s" % (slot["name"],
                                                                       " or (r, g, b)" if slot["channels"] == 3
                                                                       else ""))
            const = np.empty(shape + (slot["channels"],), dtype=np.float32)
            const[...] = v.astype(np.float32)
            arrays[slot["name"]] = _as_image_array(const, slot["name"])
    ins = [_wrap(arrays[n]) for n in names]
    outs, results = [], {}
    for slot in kind["outputs"]:
        a = np.empty(shape + (slot["channels"],), dtype=np.float32)
        results[slot["name"]] = a
        outs.append(_wrap(a))
    in_ptrs = (ctypes.POINTER(_Image) * len(ins))(*[ctypes.pointer(i) for i in ins])
    out_ptrs = (ctypes.POINTER(_Image) * len(outs))(*[ctypes.pointer(o) for o in outs])
    _check(_lib.mr_api_transform_convert(_b(source), _b(target), _b(method), float(f0 or 0.0), _threads(threads),
                                         in_ptrs, out_ptrs))
    return {k: (v[:, :, 0] if v.shape[2] == 1 else v) for k, v in results.items()}


def spec2metal(diffuse, specular, glossiness, method="weighted", threads=0, f0=None):
    """glTF spec-gloss maps (linear diffuse and specular RGB, glossiness) to metal-rough: {"base_color" (H, W, 3),
    "metallic" (H, W), "roughness" (H, W)}; the methods of `matremap spec2metal` (weighted, mean, mlp, khronos, ...)."""
    return transform("gltf-specgloss", "gltf", method, threads=threads, f0=f0, diffuse=diffuse, specular=specular,
                     glossiness=glossiness)


def metal2spec(base_color, metallic, roughness, method="eq2", threads=0, f0=None):
    """glTF metal-rough maps (linear base colour, metallic, roughness) to spec-gloss: {"diffuse", "specular",
    "glossiness"}; the methods of `matremap metal2spec` (eq2, khronos)."""
    return transform("gltf", "gltf-specgloss", method, threads=threads, f0=f0, base_color=base_color,
                     metallic=metallic, roughness=roughness)


def convert_gltf(src, dst, direction="spec2metal", method=None, threads=0, overwrite=False):
    """Convert a glTF asset's materials as `matremap gltf DIRECTION SRC -o DST` does (.gltf with its files beside it,
    or .glb; never over an input): {"input", "output", "direction", "method", "materials": [{"name", "outcome",
    "reason", "width", "height", "flagged", "off_manifold", "nonfinite", "clamped", "failed", "seconds",
    "extension"}]}. method None: the command's default (weighted for spec2metal, eq2 for metal2spec); overwrite:
    convert spec-gloss materials that carry metal-rough values of their own (--overwrite-metal-rough)."""
    folder = os.path.dirname(os.fspath(dst))
    if folder and not os.path.isdir(folder):
        os.makedirs(folder)  # as the command: the output's missing folders made
    return _json_call(_lib.mr_api_gltf_convert, _b(os.fspath(src)), _b(os.fspath(dst)), _b(direction), _b(method),
                      1 if overwrite else 0, _threads(threads))


class Transform(object):
    """A learned transform (`matremap learn`'s .mrt file): Transform.load(path); t.source, t.target (model names);
    t.apply(**maps) converts texel by texel as `matremap convert --transform` does."""

    def __init__(self, handle, path):
        self._handle = handle
        self.path = path
        head = ctypes.cast(handle, ctypes.POINTER(_native.LearnedHead)).contents
        self.source = head.source[0].decode()
        self.target = head.target[0].decode()

    @classmethod
    def load(cls, path):
        handle = ctypes.c_void_p()
        _check(_lib.mr_learned_read(_b(os.fspath(path)), ctypes.byref(handle)))
        return cls(handle, os.fspath(path))

    def __del__(self):
        if getattr(self, "_handle", None) is not None and _lib is not None:
            _lib.mr_learned_free(self._handle)
            self._handle = None

    def apply(self, flags=False, **maps):
        """Source parameters by name: (H, W) arrays for scalars, (H, W, 3) or grey (H, W) for colours, numbers or
        (r, g, b) broadcast; the rest keep the model's defaults. Returns {target parameter: (H, W) or (H, W, 3)
        float32} (and the MR_WF_* flag bits per texel, (H, W) uint32, as a second value with flags=True)."""
        table = {m["name"]: m["params"] for m in models()}
        src, dst = table[self.source], table[self.target]
        names = [p["name"] for p in src]
        unknown = [k for k in maps if k not in names]
        if unknown:
            raise ValueError("%s: not a parameter of %s (%s)" % (unknown[0], self.source, ", ".join(names)))
        shape = None
        arrays = {}
        for p in src:
            v = maps.get(p["name"])
            if isinstance(v, np.ndarray) and v.ndim >= 2:
                a = _as_image_array(v, p["name"], (1, 3) if p["channels"] == 3 else (1,))
                if shape is not None and a.shape[:2] != shape:
                    raise ValueError("%s: shape %s differs from the other maps' %s" % (p["name"], a.shape[:2], shape))
                shape = a.shape[:2]
                arrays[p["name"]] = a
        shape = shape or (1, 1)
        n = shape[0] * shape[1]
        width = sum(p["channels"] for p in src)
        rows = np.empty((n, width), dtype=np.float64)
        offset = 0
        for p in src:
            c = p["channels"]
            if p["name"] in arrays:
                rows[:, offset:offset + c] = arrays[p["name"]].reshape(n, -1)
            else:
                v = p["default"] if p["name"] not in maps else maps[p["name"]]
                v = np.asarray(v, dtype=np.float64).ravel()
                if v.size not in ((1, c) if c == 3 else (1,)) or not np.isfinite(v).all():
                    raise ValueError("%s: expected an array or a finite number%s" % (p["name"],
                                                                                     " or (r, g, b)" if c == 3 else ""))
                rows[:, offset:offset + c] = v.astype(np.float32)  # a constant is a float map's value, as in convert
            offset += c
        out_width = sum(p["channels"] for p in dst)
        out = np.empty((n, out_width), dtype=np.float64)
        bits = np.zeros(n, dtype=np.uint32)
        _check(_lib.mr_learned_apply_batch(self._handle, n, rows.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                                           out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                                           bits.ctypes.data_as(ctypes.POINTER(ctypes.c_uint))))
        result, offset = {}, 0
        for p in dst:
            c = p["channels"]
            a = out[:, offset:offset + c].astype(np.float32).reshape(shape + (c,))
            result[p["name"]] = a[:, :, 0] if c == 1 else a
            offset += c
        return (result, bits.reshape(shape)) if flags else result


def report(inputs, output_dir, size=0, env=None, rotations=0, threads=0, title=None, labels=None):
    """`matremap report`: each input, a (model, params) pair, a dict {"model", "params"[, "label"]} or a glTF asset's
    path, rendered and compared with the first; writes output_dir/index.html, its pictures and summary.json (the
    folder is made if missing) and returns summary.json's contents. size, rotations, threads 0: the defaults."""
    texts, names = [], []
    for k, item in enumerate(inputs):
        label = labels[k] if labels is not None else None
        if isinstance(item, (str, os.PathLike)):
            texts.append(os.fspath(item))
        elif isinstance(item, dict):
            texts.append("\n".join([item["model"]] + _assignments(item.get("params"), "inputs[%d]" % k)))
            label = item.get("label", label)
        else:
            model, params = item
            texts.append("\n".join([model] + _assignments(params, "inputs[%d]" % k)))
        names.append(label)
    if not texts:
        raise ValueError("inputs: expected at least one material or asset")
    output_dir = os.fspath(output_dir)
    if not os.path.isdir(output_dir):
        os.makedirs(output_dir)
    label_array = (ctypes.c_char_p * len(names))(*[_b(n) for n in names])
    _check(_lib.mr_api_report(_strings(texts), label_array, len(texts), _b(output_dir), int(size), _b(env),
                              int(rotations), _threads(threads), _b(title)))
    with open(os.path.join(output_dir, "summary.json")) as f:
        return json.load(f)


# ---- metrics --------------------------------------------------------------------------------------------------

def _ssim(a, b, mask, exposure, threads, want_map):
    a = _as_image_array(a, "a")
    b = _as_image_array(b, "b")
    opts = _native.SsimOptions(float(exposure), 0, None, _threads(threads))
    keep = None
    if mask is not None:
        keep = _as_image_array(mask, "mask", (1,))
        mask_image = _wrap(keep)
        opts.mask = ctypes.pointer(mask_image)
    ia, ib = _wrap(a), _wrap(b)
    value = ctypes.c_double()
    out = ctypes.POINTER(_Image)()
    _check(_lib.mr_ssim(ctypes.byref(ia), ctypes.byref(ib), ctypes.byref(opts), ctypes.byref(value),
                        ctypes.byref(out) if want_map else None))
    if not want_map:
        return value.value
    try:
        m = out.contents
        return np.ctypeslib.as_array(m.pixels, shape=(m.height, m.width)).copy()
    finally:
        _lib.mr_image_free(out)


def ssim(a, b, mask=None, exposure=1.0, threads=0):
    """Mean SSIM of two linear images as `matremap ssim` computes it (display-referred: exposure, clamp, sRGB,
    luma); mask: the object's coverage (H, W) in [0, 1]."""
    return _ssim(a, b, mask, exposure, threads, False)


def ssim_map(a, b, exposure=1.0, threads=0):
    """The SSIM map ((H - 10) x (W - 10) float32) of the two images."""
    return _ssim(a, b, None, exposure, threads, True)


# ---- image files ----------------------------------------------------------------------------------------------

_ENCODINGS = {"color": 0, "data": 1}


def _encoding(encoding):
    if encoding not in _ENCODINGS:
        raise ValueError("encoding: %r: expected 'color' or 'data'" % (encoding,))
    return _ENCODINGS[encoding]


def read_image(path, encoding="color"):
    """An image file as a float32 (H, W, C) array of linear values, read as every command reads it: 8/16-bit files
    sRGB-decoded with encoding "color" (alpha linear), taken as they are with "data"; EXR/HDR always linear."""
    out = ctypes.POINTER(_Image)()
    opts = _native.ReadOptions(_encoding(encoding), 0, 0)
    _check(_lib.mr_img_read(_b(path), ctypes.byref(opts), ctypes.byref(out)))
    try:
        m = out.contents
        return np.ctypeslib.as_array(m.pixels, shape=(m.height, m.width, m.channels)).copy()
    finally:
        _lib.mr_image_free(out)


def write_image(path, array, encoding="color", bits=0):
    """Write a linear (H, W, C) array in the format of path's extension (EXR 32-bit float by default; 8/16-bit
    formats sRGB-encoded with encoding "color"); the file is written atomically."""
    a = _as_image_array(array, "array")
    image = _wrap(a)
    opts = _native.WriteOptions(_encoding(encoding), int(bits), 0)
    _check(_lib.mr_img_write(_b(path), ctypes.byref(image), ctypes.byref(opts)))
