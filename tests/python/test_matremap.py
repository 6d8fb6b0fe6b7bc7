"""The Python package (python/matremap, docs/python.md) against the command line it mirrors: the same pixels, fits,
conversions and figures, the library's messages as exceptions, threads that change nothing, the GIL released."""
import json
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import matremap
from conftest import BUILD, ROOT, SHARED

CLI = os.path.join(BUILD, "bin", "matremap")
TABAC = os.path.join(SHARED, "assets", "hdri", "tabac_plant_vogl.hdr")
AVOCADO = os.path.join(SHARED, "assets", "specgloss", "Avocado-pbrSpecularGlossiness", "glTF-pbrSpecularGlossiness")


def cli(*args, code=0):
    run = subprocess.run([CLI] + [str(a) for a in args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True)
    assert run.returncode == code, run.stderr
    return run


def test_loads_the_build_tree_library():
    assert os.path.realpath(matremap.library_path) == os.path.realpath(os.path.join(BUILD, "lib",
                                                                                     "libmatremap.so.0.1.0"))
    assert "matremap %s" % matremap.version() in cli("--version").stdout


def test_models_are_the_cli_models():
    ours = matremap.models()
    theirs = json.loads(cli("models", "--json").stdout)
    theirs = theirs["models"] if isinstance(theirs, dict) else theirs
    assert [m["name"] for m in ours] == [m["name"] for m in theirs]
    ggx = next(m for m in ours if m["name"] == "ggx")
    assert [p["name"] for p in ggx["params"]] == ["alpha", "f0", "diffuse"]
    assert {"name", "channels", "default", "min", "max", "role", "meaning"} <= set(ggx["params"][0])


@pytest.mark.parametrize("args,kwargs", [
    (["ggx", "alpha=0.2", "f0=0.9,0.6,0.3", "--size", "48"], dict(size=48, alpha=0.2, f0=(0.9, 0.6, 0.3))),
    (["ward", "alpha=0.15", "--size", "40", "--light", "frontal", "--component", "specular"],
     dict(size=40, alpha=0.15, light="frontal", component="specular")),
    (["ggx", "alpha=0.3", "--size", "32", "--env", TABAC], dict(size=32, alpha=0.3, env=TABAC)),
])
def test_render_equals_the_cli_bit_for_bit(tmp_path, args, kwargs):
    out = tmp_path / "cli.exr"
    cli("render", *args, "-o", out)
    ours = matremap.render(args[0], **kwargs)
    assert ours.dtype == np.float32 and ours.shape == (kwargs["size"], kwargs["size"], 3)
    theirs = matremap.read_image(str(out))
    assert np.array_equal(ours, theirs)
    assert ours.max() > 0


def test_remap_equals_the_cli():
    theirs = json.loads(cli("remap", "--from", "ward", "alpha=0.2", "--to", "ggx", "--size", "32", "--json").stdout)
    r = matremap.remap("ward", {"alpha": 0.2}, "ggx", size=32)
    assert r.outcome == theirs["outcome"] and r.detail == theirs["detail"]
    assert r.values == {k: tuple(v) if isinstance(v, list) else v for k, v in theirs["values"].items()}
    assert (r.rmse, r.relative_rmse, r.ssim, r.renders) == (theirs["rmse"], theirs["relative_rmse"], theirs["ssim"],
                                                          theirs["renders"])


def test_remap_hold_and_strategy_as_the_cli():
    theirs = json.loads(cli("remap", "--from", "ggx", "alpha=0.3", "--to", "ward", "--hold", "alpha=0.25",
                            "--strategy", "single", "--size", "24", "--json").stdout)
    r = matremap.remap("ggx", {"alpha": 0.3}, "ward", size=24, hold={"alpha": 0.25}, strategy="single")
    assert r.values["alpha"] == 0.25 == theirs["values"]["alpha"]
    assert r.values["specular"] == tuple(theirs["values"]["specular"]) and r.strategy == "single"


def avocado_crop():
    d = matremap.read_image(os.path.join(AVOCADO, "Avocado_diffuse.png"))[900:1012, 900:1028, :3]
    sg = matremap.read_image(os.path.join(AVOCADO, "Avocado_specularGlossiness.png"))[900:1012, 900:1028]
    return np.ascontiguousarray(d), np.ascontiguousarray(sg[:, :, :3]), np.ascontiguousarray(sg[:, :, 3])


@pytest.mark.parametrize("method", ["weighted", "mlp"])
def test_spec2metal_on_avocado_equals_the_cli(tmp_path, method):
    d, s, g = avocado_crop()
    for name, a in (("d", d), ("s", s), ("g", g[:, :, None])):
        matremap.write_image(str(tmp_path / (name + ".exr")), a)
    cli("spec2metal", "--diffuse", tmp_path / "d.exr", "--specular", tmp_path / "s.exr", "--glossiness",
        tmp_path / "g.exr", "--method", method, "--format", "exr", "-o", str(tmp_path / "out") + "/")
    ours = matremap.spec2metal(d, s, g, method=method)
    assert set(ours) == {"base_color", "metallic", "roughness"}
    assert ours["base_color"].shape == (112, 128, 3) and ours["metallic"].shape == (112, 128)
    for key, file in (("base_color", "basecolor"), ("metallic", "metallic"), ("roughness", "roughness")):
        theirs = matremap.read_image(str(tmp_path / "out" / (file + ".exr")))
        theirs = theirs[:, :, 0] if ours[key].ndim == 2 else theirs
        assert np.array_equal(ours[key], theirs), key
    assert np.array_equal(ours["roughness"], (1 - g).astype(np.float32)) or method == "mlp"


def test_metal2spec_known_answer_and_constants():
    out = matremap.metal2spec(np.full((2, 3, 3), 0.5, np.float32), 0.0, np.full((2, 3), 0.25, np.float32))
    assert out["diffuse"].shape == (2, 3, 3) and out["glossiness"].shape == (2, 3)
    assert np.allclose(out["specular"], 0.04) and np.allclose(out["glossiness"], 0.75)
    # glTF's convention: base colour = diffuse (1 - max specular) on a dielectric, so diffuse = 0.5 / 0.96
    assert np.allclose(out["diffuse"], 0.5 / 0.96, atol=1e-6)


def test_ssim_equals_the_cli(tmp_path):
    a = matremap.render("ggx", size=40, alpha=0.2)
    b = matremap.render("ggx", size=40, alpha=0.35)
    matremap.write_image(str(tmp_path / "a.exr"), a)
    matremap.write_image(str(tmp_path / "b.exr"), b)
    theirs = json.loads(cli("ssim", tmp_path / "a.exr", tmp_path / "b.exr", "--json").stdout)
    assert matremap.ssim(a, b) == theirs["ssim"] < 1.0
    assert matremap.ssim_map(a, b).shape == (30, 30)
    mask = (a.max(axis=2) > 0).astype(np.float32)
    assert matremap.ssim(a, b, mask=mask) != matremap.ssim(a, b)


def test_array_conversions_and_zero_copy():
    a = matremap.render("ggx", size=24, alpha=0.2)
    assert matremap._as_image_array(a, "a") is a  # float32, C-contiguous: the library reads the caller's buffer
    u8 = (np.clip(a, 0, 1) * 255).astype(np.uint8)
    assert matremap.ssim(u8, u8.astype(np.float32) / np.float32(255)) == 1.0
    assert matremap.ssim(a.astype(np.float64), a) == 1.0
    assert matremap.ssim(a[:, ::-1], np.ascontiguousarray(a[:, ::-1])) == 1.0  # a strided view is copied


def library_message(*args):
    """The message the CLI prints after 'error: '."""
    err = cli(*args, code=2).stderr
    return err.split("error: ", 1)[1].strip()


def test_errors_carry_the_library_message(tmp_path):
    with pytest.raises(matremap.Error) as e:
        matremap.render("nosuch")
    assert str(e.value).startswith("unknown BRDF model 'nosuch' (valid: lambert, ward")
    assert str(e.value) == library_message("render", "nosuch", "-o", tmp_path / "x.exr")
    with pytest.raises(matremap.Error) as e:
        matremap.render("ggx", nosuch=1)
    assert str(e.value) == "model 'ggx' has no parameter 'nosuch' (valid: alpha, f0, diffuse)"
    with pytest.raises(matremap.Error) as e:
        matremap.render("ggx", alpha="abc")
    assert str(e.value) == "parameter 'alpha' of model 'ggx': 'abc' is not a number"
    with pytest.raises(matremap.Error) as e:
        matremap.render("ggx", env=str(tmp_path / "missing.hdr"))
    assert str(e.value) == library_message("render", "ggx", "--env", tmp_path / "missing.hdr", "-o",
                                           tmp_path / "x.exr")
    assert "missing.hdr': cannot open: No such file or directory" in str(e.value)
    with pytest.raises(matremap.Error, match="unknown BRDF model 'nosuch'"):
        matremap.remap("ward", {"alpha": 0.2}, "nosuch")
    with pytest.raises(matremap.Error, match="no method 'nosuch'|'nosuch'"):
        matremap.spec2metal(np.zeros((2, 2, 3), np.float32), 0.04, 0.5, method="nosuch")
    assert isinstance(e.value, RuntimeError)


def test_bad_arrays_are_value_errors_naming_the_argument():
    good = np.zeros((8, 8, 3), np.float32)
    with pytest.raises(ValueError, match=r"^a: dtype int32 is not accepted"):
        matremap.ssim(np.zeros((8, 8, 3), np.int32), good)
    with pytest.raises(ValueError, match=r"^b: shape \(8, 8, 2\): expected \(H, W\) or \(H, W, C\) with C in 1/3/4"):
        matremap.ssim(good, np.zeros((8, 8, 2), np.float32))
    d = np.full((4, 4, 3), 0.5, np.float32)
    d[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"^diffuse: pixel \(2, 1\), channel 0 holds nan: expected finite values$"):
        matremap.spec2metal(d, 0.04, 0.5)
    with pytest.raises(ValueError, match=r"^glossiness: shape \(4, 4, 3\)"):
        matremap.spec2metal(np.full((4, 4, 3), 0.5, np.float32), 0.04, np.zeros((4, 4, 3), np.float32))
    with pytest.raises(ValueError, match=r"^specular: shape \(4, 4\) differs from the other maps' \(2, 2\)"):
        matremap.spec2metal(np.zeros((2, 2, 3), np.float32), np.zeros((4, 4), np.float32), 0.5)
    with pytest.raises(ValueError, match=r"^alpha: inf is not a finite number"):
        matremap.render("ggx", alpha=float("inf"))
    with pytest.raises(ValueError, match=r"^threads: -1"):
        matremap.render("ggx", threads=-1)


def test_threads_change_nothing():
    one = matremap.render("ggx", size=200, alpha=0.2, threads=1)
    two = matremap.render("ggx", size=200, alpha=0.2, threads=2)
    assert np.array_equal(one, two)
    d, s, g = avocado_crop()
    assert all(np.array_equal(a, b) for a, b in zip(matremap.spec2metal(d, s, g, method="mlp", threads=1).values(),
                                                   matremap.spec2metal(d, s, g, method="mlp", threads=2).values()))
    assert matremap.remap("ward", {"alpha": 0.2}, "ggx", size=24, threads=1).values == \
        matremap.remap("ward", {"alpha": 0.2}, "ggx", size=24, threads=2).values


def test_a_call_releases_the_gil():
    times = {}

    def work():
        times["start"] = time.monotonic()
        matremap.render("ggx", size=400, alpha=0.2, env=TABAC, threads=1)
        times["end"] = time.monotonic()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.monotonic())
        time.sleep(0.001)
    worker.join()
    start, end = times["start"], times["end"]
    assert end - start > 0.1
    middle = [t for t in ticks if start + 0.25 * (end - start) < t < start + 0.75 * (end - start)]
    assert len(middle) >= 10  # Python ran in this thread while the render ran in C


def test_python_m_matremap_runs_the_cli():
    env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "python"))
    run = subprocess.run([sys.executable, "-m", "matremap", "models", "--json"], stdout=subprocess.PIPE, env=env,
                         universal_newlines=True)
    assert run.returncode == 0 and run.stdout == cli("models", "--json").stdout
    run = subprocess.run([sys.executable, "-m", "matremap", "render", "nosuch", "-o", "x.exr"], env=env,
                         stderr=subprocess.PIPE, universal_newlines=True)
    assert run.returncode == 2 and "unknown BRDF model 'nosuch'" in run.stderr


def test_modules_and_data_are_found_beside_the_library(tmp_path):
    # No matremap executable in this process: the OpenImageIO module (TIFF) and the network (mlp) are found from
    # libmatremap.so's own place (build/lib/matremap, build/share/matremap).
    a = np.random.default_rng(1).random((5, 7, 3), dtype=np.float32)
    matremap.write_image(str(tmp_path / "a.tif"), a, encoding="data", bits=16)
    assert np.abs(matremap.read_image(str(tmp_path / "a.tif"), encoding="data") - a).max() <= 0.5 / 65535 + 1e-7
    out = matremap.spec2metal(np.full((1, 1, 3), 0.5, np.float32), 0.04, 0.5, method="mlp")
    assert 0 <= out["metallic"][0, 0] < 0.01


def test_convert_gltf_writes_the_cli_files(tmp_path):
    duck = os.path.join(SHARED, "assets", "specgloss", "Duck-pbrSpecularGlossiness", "glTF-pbrSpecularGlossiness",
                        "Duck.gltf")
    summary = matremap.convert_gltf(duck, tmp_path / "py" / "duck.gltf", overwrite=True)
    assert summary["method"] == "weighted" and [m["outcome"] for m in summary["materials"]] == ["converted"]
    cli("gltf", "spec2metal", duck, "-o", tmp_path / "cli" / "duck.gltf", "--overwrite-metal-rough")
    files = sorted(os.listdir(tmp_path / "cli"))
    assert sorted(os.listdir(tmp_path / "py")) == files and "duck_m0_basecolor.png" in files
    for name in files:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    with pytest.raises(matremap.Error, match="'.*nosuch.gltf'"):
        matremap.convert_gltf(tmp_path / "nosuch.gltf", tmp_path / "x.gltf")


def test_learned_transform_equals_matremap_convert(tmp_path):
    cli("sweep", "--from", "ward", "diffuse=0", "--to", "ggx", "diffuse=0", "--grid",
        "alpha=0.03:0.4:4:log", "specular=0.03:0.25:3", "--size", "16", "--threads", "2", "-o", tmp_path / "wg.csv")
    cli("learn", tmp_path / "wg.csv", "-o", tmp_path / "wg.mrt")
    t = matremap.Transform.load(tmp_path / "wg.mrt")
    assert (t.source, t.target) == ("ward", "ggx")
    alpha = np.linspace(0.03, 0.4, 48, dtype=np.float32).reshape(6, 8)
    matremap.write_image(str(tmp_path / "rough.exr"), alpha)
    cli("convert", "--from", "ward", "--to", "ggx", "alpha=@%s" % (tmp_path / "rough.exr"), "specular=0.1",
        "--transform", tmp_path / "wg.mrt", "-o", str(tmp_path / "cv" / "g_"))
    ours, flags = t.apply(alpha=alpha, specular=0.1, flags=True)
    assert flags.shape == (6, 8)
    for name in ("alpha", "f0", "diffuse"):
        theirs = matremap.read_image(str(tmp_path / "cv" / ("g_%s.exr" % name)))
        assert np.array_equal(ours[name], theirs[:, :, 0] if ours[name].ndim == 2 else theirs), name
    with pytest.raises(matremap.Error, match="nosuch.mrt"):
        matremap.Transform.load(tmp_path / "nosuch.mrt")
    with pytest.raises(ValueError, match="^f0: not a parameter of ward"):
        t.apply(f0=0.1)


def test_report_equals_matremap_report(tmp_path):
    ours = matremap.report([("ggx", {"alpha": 0.2}), {"model": "ward", "params": {"alpha": 0.25}}], tmp_path / "py",
                           size=64)
    cli("report", "-o", tmp_path / "cli", "--size", "64", "ggx", "alpha=0.2", "--", "ward", "alpha=0.25")
    with open(str(tmp_path / "cli" / "summary.json")) as f:
        theirs = json.load(f)
    for m in ours["materials"] + theirs["materials"]:
        m.pop("seconds")
    assert ours == theirs and ours["materials"][1]["description"] == "ward alpha=0.25"
    for name in sorted(os.listdir(tmp_path / "cli")):
        if name.endswith(".png"):
            assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    with pytest.raises(matremap.Error, match="unknown BRDF model 'nosuch'"):
        matremap.report([("nosuch", {})], tmp_path / "bad")


@pytest.mark.skipif(not os.path.exists("/usr/bin/blender"), reason="no Blender (scripts/install-deps.sh installs it)")
def test_imports_in_blenders_python():
    code = ("import sys; sys.path.insert(0, %r); import matremap; "
            "print('MATREMAP', matremap.version(), matremap.render('ggx', size=8, alpha=0.2).shape)"
            % os.path.join(ROOT, "python"))
    run = subprocess.run(["/usr/bin/blender", "-b", "--factory-startup", "--python-expr", code],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    assert "MATREMAP %s (8, 8, 3)" % matremap.version() in run.stdout, run.stdout[-2000:]


def test_the_shared_library_exports_only_mr_symbols():
    lib = os.path.join(BUILD, "lib", "libmatremap.so.0")
    listing = subprocess.run(["nm", "-D", "--defined-only", lib], stdout=subprocess.PIPE, universal_newlines=True,
                             check=True).stdout
    names = [line.split()[-1].split("@")[0] for line in listing.splitlines()]  # mr_x@@MATREMAP_0 -> mr_x
    assert [n for n in names if not n.startswith("mr_")] == ["MATREMAP_0"]  # the version script's node
    assert {"mr_render", "mr_remap", "mr_api_render", "mr_last_error"} <= set(names) and len(names) > 500
    dynamic = subprocess.run(["readelf", "-d", lib], stdout=subprocess.PIPE, universal_newlines=True).stdout
    assert "Library soname: [libmatremap.so.0]" in dynamic
    assert os.readlink(lib) == "libmatremap.so.0.1.0" and os.readlink(os.path.join(BUILD, "lib", "libmatremap.so")) \
        == "libmatremap.so.0.1.0"
