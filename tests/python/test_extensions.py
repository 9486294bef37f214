"""User extensions in C (synthgen.scene.extensions, synthgen_ext.h): the rust preset as an
extension against the built-in one, shapes' exact labels against analytic intersections,
and bad extensions' errors."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P, wear
from synthgen.scene import extensions, wear_ext
from synthgen.scene.extensions import ExtensionError

HEADER = "#include <synthgen_ext.h>\n#include <math.h>\n"


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    # Every test compiles into a fresh cache (and never into the user's).
    monkeypatch.setenv("SYNTHGEN_CACHE", str(tmp_path_factory.mktemp("cache")))


def _psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = float(np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2))
    peak = float(max(a.max(), b.max()))
    return float("inf") if mse == 0.0 else 10.0 * np.log10(peak * peak / mse)


def _rust_scene(preset, width=160, height=120):
    s = sg.Scene()
    g = P.plane(20.0, 20.0)
    s.add_instance(s.add_mesh(g["positions"], g["indices"], normals=g["normals"]), np.eye(4),
                   material_id=s.add_material("diffuse", {"albedo": 0.3}))
    b = P.box((1.8, 1.2, 3.0))
    grey = s.add_material("principled", {"base_color": [0.5, 0.5, 0.55], "roughness": 0.4})
    mat = preset(s, grey, seed=5, amount=0.4)
    s.add_instance(s.add_mesh(b["positions"], b["indices"], normals=b["normals"]),
                   P.translate([0.0, 0.6, 0.0]) @ P.rotate([0, 1, 0], 35.0), class_id=1, material_id=mat)
    s.add_light("sky", {"elevation": 40.0, "azimuth": 130.0, "turbidity": 3.0, "strength": 0.02})
    pose = sg.PinholeCamera.look_at((2.6, 2.0, -3.8), (0.0, 0.6, 0.0), (0.0, 1.0, 0.0))
    s.set_camera(sg.PinholeCamera.from_fov(40.0, width, height, pose))
    return s


def test_rust_extension_matches_the_builtin_preset():
    a = _rust_scene(wear.rust).render(spp=8, max_depth=5, seed=3).rgb
    b = _rust_scene(wear_ext.rust).render(spp=8, max_depth=5, seed=3).rgb
    psnr = _psnr(a, b)
    print(f"PSNR of the extension rust against the built-in: {psnr:.2f} dB")
    assert psnr >= 50.0
    # The rust is there: the box is not the plain grey of its base.
    plain = _rust_scene(lambda s, base, **k: base).render(spp=8, max_depth=5, seed=3).rgb
    assert _psnr(plain, b) < 35.0


def test_extension_arguments_change_without_recompiling():
    s = sg.Scene()
    first = s.load_extension(extensions.example("rust"))
    assert not first["cached"] and first["textures"] == ["rust_mask", "rust_color", "rust_bump"]
    pts = np.random.default_rng(0).random((256, 3)).astype(np.float32)
    v = [s.texture_values(s.add_texture("rust_mask", {"seed": seed}), pts)[:, 0] for seed in (1, 2)]
    assert not np.allclose(v[0], v[1])
    again = s.load_extension(extensions.example("rust"))
    assert again["cached"] and again["library"] == first["library"]
    assert len([x for x in extensions.loaded_extensions() if x["library"] == first["library"]]) == 1
    # Declared parameters are checked like any plugin's.
    with pytest.raises(sg.SynthgenError, match=r"did you mean 'seed'"):
        s.add_texture("rust_mask", {"sead": 1})
    with pytest.raises(sg.SynthgenError, match=r"bottom_bias"):
        s.add_texture("rust_mask", {"bottom_bias": 9.0})


# ---- shapes: exact labels -------------------------------------------------------------------

W, H, FX, FY, CX, CY = 128, 96, 150.0, 150.0, 61.7, 49.2


def _camera():
    wfc = sg.PinholeCamera.look_at((0.4, 1.1, -3.4), (0.0, 0.2, 0.0), (0.0, 1.0, 0.0))
    return sg.PinholeCamera(fx=FX, fy=FY, cx=CX, cy=CY, width=W, height=H, world_from_camera=wfc)


def _rays(cam, world_from_object):
    """Per pixel centre: object-space origin, unit world direction's object-space image (not
    unit: the instance scales) and the z of the world direction in camera space (depth per t)."""
    m = np.asarray(cam.world_from_camera, dtype=np.float64)
    j, i = np.mgrid[0:H, 0:W].astype(np.float64)
    d_cam = np.stack([(i + 0.5 - CX) / FX, (j + 0.5 - CY) / FY, np.ones_like(i)], axis=-1)
    d_cam /= np.linalg.norm(d_cam, axis=-1, keepdims=True)
    d_world = d_cam @ m[:3, :3].T
    inv = np.linalg.inv(np.asarray(world_from_object, dtype=np.float64))
    o = inv[:3, :3] @ m[:3, 3] + inv[:3, 3]
    return o, d_world @ inv[:3, :3].T, d_cam[..., 2]


def _march(sdf, o, d, t_max=20.0, tol=1e-12):
    """Float64 sphere tracing of every ray; inf where it misses."""
    t = np.zeros(d.shape[:-1])
    dl = np.linalg.norm(d, axis=-1)
    live = np.ones(t.shape, bool)
    hit = np.zeros(t.shape, bool)
    for _ in range(20000):
        if not live.any():
            break
        dist = sdf(o + t[live][:, None] * d[live])
        done = dist < tol
        idx = np.flatnonzero(live)
        hit[idx[done]] = True
        t[idx[~done]] += dist[~done] / dl[live][~done]
        live[idx[done]] = False
        live[live] = t[live] < t_max
    return np.where(hit, t, np.inf)


def _torus(R, r):
    return lambda p: np.hypot(np.hypot(p[:, 0], p[:, 2]) - R, p[:, 1]) - r


def _rounded_box(size, rad):
    half = 0.5 * np.asarray(size) - rad

    def f(p):
        q = np.abs(p) - half
        return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0) - rad
    return f


def _sphere(radius):
    return lambda p: np.linalg.norm(p, axis=1) - radius


SHAPES = [
    ("ext_sphere", {"radius": 0.5}, _sphere, (0.5,), 1.0),
    ("torus", {"major_radius": 0.6, "minor_radius": 0.2}, _torus, (0.6, 0.2), 1.6),
    ("rounded_box", {"size": [1.2, 0.7, 0.9], "radius": 0.15}, _rounded_box, ((1.2, 0.7, 0.9), 0.15), 1.2),
]


def _grown(make, args, delta):
    """The shape's surface moved outwards by delta (an offset surface of a distance field)."""
    f = make(*args)
    return lambda p: f(p) - delta


@pytest.mark.parametrize("name,params,make,args,size", SHAPES, ids=[s[0] for s in SHAPES])
def test_shape_labels_are_exact(name, params, make, args, size):
    s = sg.Scene()
    s.load_extension(extensions.example("shapes"))
    # A rotated, translated and scaled instance: the shape sees object-space rays of non-unit
    # direction, as Embree hands them to user geometry.
    wfo = P.translate([0.1, 0.3, 0.2]) @ P.rotate([1, 0.3, 0], 50.0) @ P.scale(1.3)
    s.add_instance(s.add_shape(name, params), wfo, class_id=3, instance_id=77)
    cam = _camera()
    s.set_camera(cam)
    r = s.render(spp=1, labels_only=True)
    o, d, zc = _rays(cam, wfo)
    flat = d.reshape(-1, 3)
    delta = 2e-5 * size  # the shape's accuracy (sphere tracing's stop, float32), object units
    t_in = _march(_grown(make, args, -delta), o, flat).reshape(H, W)
    t_out = _march(_grown(make, args, delta), o, flat).reshape(H, W)
    t_exact = _march(make(*args), o, flat).reshape(H, W)
    inside, outside = np.isfinite(t_in), ~np.isfinite(t_out)
    mask = r.instance_id == 77
    assert inside.sum() > 800 and outside.sum() > 2000
    assert np.all(mask[inside]), f"{(~mask[inside]).sum()} pixels that surely hit are not labelled"
    assert not np.any(mask[outside]), f"{mask[outside].sum()} pixels that surely miss are labelled"
    assert (mask != np.isfinite(t_exact)).sum() <= 3  # only rays grazing within delta may differ
    np.testing.assert_array_equal(r.class_id[mask], 3)
    # Depth: between the entries of the inner and outer offset surfaces, and at the surface to
    # 1e-5 of the shape's size (t is in world units: the unit world direction's parameter).
    both = inside & mask
    dist = r.distance[both].astype(np.float64)
    assert np.all(dist >= t_out[both] * (1 - 1e-6)) and np.all(dist <= t_in[both] * (1 + 1e-6))
    err = np.abs(dist - t_exact[both])
    print(f"{name}: {both.sum()} pixels, depth error median {np.median(err):.2e} m, max {err.max():.2e} m")
    assert np.median(err) < 1e-5 * size
    np.testing.assert_allclose(r.depth[both], r.distance[both] * zc[both], rtol=1e-5)


def test_shapes_cast_shadows_and_render():
    s = sg.Scene()
    s.load_extension(extensions.example("shapes"))
    g = P.plane(10.0, 10.0)
    s.add_instance(s.add_mesh(g["positions"], g["indices"], normals=g["normals"]), np.eye(4),
                   material_id=s.add_material("diffuse", {"albedo": 0.5}))
    s.add_light("sun", {"direction": [0.0, 1.0, 0.0], "irradiance": 3.0})
    cam = sg.PinholeCamera.look_at((0.0, 3.0, -0.01), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 64, 64, cam))
    lit = s.render(spp=4, max_depth=2, seed=1).rgb.mean()
    # A torus hovering above the ground under an overhead sun: its ring of shadow darkens the
    # ground, and through the hole the sun still reaches it.
    s.add_instance(s.add_shape("torus", {"major_radius": 0.5, "minor_radius": 0.15}), P.translate([0, 1.0, 0]))
    r = s.render(spp=4, max_depth=2, seed=1)
    ground = r.instance_id == 1
    assert ground[32, 32], "the ground is seen through the torus' hole"
    assert r.rgb[32, 32].mean() == pytest.approx(lit, rel=0.2)
    assert r.rgb[ground].mean() < 0.9 * lit


# ---- bad extensions ---------------------------------------------------------------------------


def _write(tmp_path, name, body) -> str:
    p = tmp_path / name
    p.write_text(HEADER + textwrap.dedent(body))
    return str(p)


GOOD_TEX = """
static void f(const sg_ext_point* q, const float* a, const sg_ext_host* h, float* out) { out[0] = %s; }
static const sg_ext_texture tex[] = {{"%s", "doc", %d, 0, 0, 0, f, 0}};
SG_EXT_EXPORT const sg_ext_library* synthgen_extension(void) {
  static const sg_ext_library lib = {%s, tex, 1, 0, 0};
  return &lib;
}
"""


def test_syntax_error_names_file_and_line(tmp_path):
    path = _write(tmp_path, "broken.c", "static int f(void) { return 1 }\n")
    with pytest.raises(ExtensionError, match=r"broken\.c:3:\d+: error") as e:
        sg.Scene().load_extension(path)
    assert "does not compile" in str(e.value)


def test_missing_entry_symbol(tmp_path):
    path = _write(tmp_path, "nosym.c", "int unrelated(void) { return 2; }\n")
    with pytest.raises(ExtensionError, match=r"nosym\.c: no function 'synthgen_extension'"):
        sg.Scene().load_extension(path)


def test_wrong_abi_version(tmp_path):
    path = _write(tmp_path, "abi.c", GOOD_TEX % ("1.f", "abi_tex", 1, "99u"))
    with pytest.raises(ExtensionError, match=r"abi\.c: built for extension ABI version 99; this synthgen has "
                                             r"version 1"):
        sg.Scene().load_extension(path)


def test_bad_declarations(tmp_path):
    with pytest.raises(ExtensionError, match=r"texture 'two': channels must be 1 or 3 \(is 2\)"):
        sg.Scene().load_extension(_write(tmp_path, "ch.c", GOOD_TEX % ("1.f", "two", 2, "SG_EXT_ABI_VERSION")))
    with pytest.raises(ExtensionError, match=r"'noise' has the name of a built-in texture"):
        sg.Scene().load_extension(_write(tmp_path, "clash.c", GOOD_TEX % ("1.f", "noise", 1, "SG_EXT_ABI_VERSION")))
    with pytest.raises(ExtensionError, match=r"name must match"):
        sg.Scene().load_extension(_write(tmp_path, "nm.c", GOOD_TEX % ("1.f", "Bad-Name", 1, "SG_EXT_ABI_VERSION")))
    assert "two" not in sg.plugin_names("texture") and "noise" in sg.plugin_names("texture")


def test_undeclared_function_is_a_compile_error(tmp_path):
    path = _write(tmp_path, "undecl.c", GOOD_TEX % ("not_a_function(q->p[0])", "undecl", 1, "SG_EXT_ABI_VERSION"))
    with pytest.raises(ExtensionError, match=r"undecl\.c:\d+:\d+: error: implicit declaration"):
        sg.Scene().load_extension(path)


def test_a_crash_while_loading_is_an_error_naming_the_file(tmp_path):
    """synthgen_extension() is the extension's code too: a new library is loaded in a child
    process first, so that its crash is an error here instead of this process's end."""
    path = _write(tmp_path, "load_crash.c", """
        #include <stdint.h>
        SG_EXT_EXPORT const sg_ext_library* synthgen_extension(void) {
          volatile uintptr_t zero = 0;
          return *(const sg_ext_library* volatile*)zero;  /* a null-pointer read: SIGSEGV */
        }
        """)
    with pytest.raises(ExtensionError, match=r"load_crash\.c: loading the extension crashed its process \(killed by "
                                             r"SIGSEGV\) \(its synthgen_extension\(\) or a constructor"):
        sg.Scene().load_extension(path)


def test_nan_output_fails_the_render_naming_the_extension(tmp_path):
    path = _write(tmp_path, "nan_tex.c", GOOD_TEX % ("q->p[0] < -0.5f ? NAN : 0.5f", "nan_tex", 1,
                                                       "SG_EXT_ABI_VERSION"))
    s = sg.Scene()
    s.load_extension(path)
    tex = s.add_texture("nan_tex")  # the average's points lie in [0, 16]^3: finite there
    b = P.box((2.0, 2.0, 2.0))
    s.add_instance(s.add_mesh(b["positions"], b["indices"], normals=b["normals"]), np.eye(4),
                   material_id=s.add_material("diffuse", {"albedo": sg.TextureRef(tex)}))
    s.add_light("sun", {"direction": [0.3, 1.0, -0.5], "irradiance": 2.0})
    s.set_camera(sg.PinholeCamera.from_fov(40.0, 32, 32, sg.PinholeCamera.look_at((0, 1, -5), (0, 0, 0), (0, 1, 0))))
    with pytest.raises(sg.SynthgenError, match=r"texture \d+: extension texture 'nan_tex' \(.*nan_tex\.c\): "
                                               r"returned NaN \(channel 0\) at world point"):
        s.render(spp=2, max_depth=2)


def test_nan_at_creation_is_an_error(tmp_path):
    path = _write(tmp_path, "nan_all.c", GOOD_TEX % ("NAN", "nan_all", 1, "SG_EXT_ABI_VERSION"))
    s = sg.Scene()
    s.load_extension(path)
    with pytest.raises(sg.SynthgenError, match=r"nan_all.*returned NaN.*while estimating its average"):
        s.add_texture("nan_all")


def test_the_header_is_installed_with_the_package_and_its_example_works(tmp_path):
    header = open(os.path.join(extensions.header_dir(), "synthgen_ext.h")).read()
    assert sg._core.EXTENSION_ABI_VERSION == 1
    # The example of the header's comment, as a user would copy it.
    start = header.index(" *   #include <math.h>")
    end = header.index(" *   }\n", header.index("synthgen_extension(void) {", start)) + len(" *   }\n")
    code = "\n".join(line[5:] for line in header[start:end].splitlines())
    path = tmp_path / "stripes.c"
    path.write_text(code)
    s = sg.Scene()
    assert s.load_extension(str(path))["textures"] == ["stripes"]
    t = s.add_texture("stripes", {"frequency": 2.0, "color": [1.0, 0.5, 0.0]})
    v = s.texture_values(t, np.zeros((2, 3), np.float32), uvs=np.array([[0.1, 0.0], [0.4, 0.0]], np.float32))
    np.testing.assert_array_equal(v, [[1.0, 0.5, 0.0], [0.0, 0.0, 0.0]])  # sin(4 pi u) > 0 at 0.1, < 0 at 0.4


# ---- consent: scene files and scenarios -----------------------------------------------------

SCENE = """
version: 1
{allow}
extensions: [{path}]
camera: {{width: 32, height: 24, fov_y: 40, look_at: {{eye: [0, 1, -4], target: [0, 0.5, 0]}}}}
objects:
  - shape: {{type: torus, major_radius: 0.5, minor_radius: 0.2}}
    class_id: 1
    translate: [0, 0.5, 0]
lights: [{{type: sun, direction: [0, 1, 0], irradiance: 2}}]
render: {{spp: 2}}
"""


def test_scene_files_compile_extensions_only_with_both_consents(tmp_path):
    shapes = extensions.example("shapes")
    denied = tmp_path / "denied.yaml"
    denied.write_text(SCENE.format(allow="", path=shapes))
    with pytest.raises(sg.SceneFileError, match=r"denied\.yaml:4:1: extensions: extensions run with your rights: "
                                                r"compiling and running shapes\.c needs .*lacks 'allow_extensions"):
        sg.load_scene(str(denied), allow_extensions=True)
    allowed = tmp_path / "allowed.yaml"
    allowed.write_text(SCENE.format(allow="allow_extensions: true", path=shapes))
    with pytest.raises(sg.SceneFileError, match=r"lacks --allow-extensions"):
        sg.load_scene(str(allowed))
    scene, settings, meta = sg.load_scene(str(allowed), allow_extensions=True)
    assert meta["objects"][0]["shape"] == "torus"
    assert (scene.render(**settings).class_id == 1).sum() > 20


def test_a_broken_extension_in_a_scene_file_points_at_its_entry(tmp_path):
    bad = _write(tmp_path, "bad.c", "int x = ;\n")
    f = tmp_path / "scene.yaml"
    f.write_text(SCENE.format(allow="allow_extensions: true", path=bad))
    with pytest.raises(sg.SceneFileError, match=r"(?s)scene\.yaml:4:\d+: extensions\[0\]: .*bad\.c:3:\d+: error"):
        sg.load_scene(str(f), allow_extensions=True)


def test_the_command_line_prints_compiler_errors_line_by_line(tmp_path, capsys):
    """The compiler's diagnostics reach the user as it printed them, one per line, each starting
    with FILE:LINE:COLUMN (they were joined onto one line after 'synthgen: error:')."""
    from synthgen import cli

    bad = _write(tmp_path, "two_errors.c", """\
        static float f(float x) {
          float y = x * undefined_scale;
          return y
        }
        """)
    f = tmp_path / "scene.yaml"
    f.write_text(SCENE.format(allow="allow_extensions: true", path=bad))
    assert cli.main(["render", str(f), "-o", str(tmp_path / "out"), "--allow-extensions"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith(f"synthgen: error: {f}:4:")
    assert "two_errors.c: the extension does not compile" in lines[0]
    errors = [ln for ln in lines if ln.startswith(f"{bad}:") and ": error: " in ln]
    assert [ln.split(":")[1] for ln in errors] == ["4", "5"], lines  # the file's lines 4 and 5 (after HEADER)
    assert "undefined_scale" in errors[0] and "undefined_scale" not in errors[1]
    assert not (tmp_path / "out").exists()


CRASH_C = """
#include <stdint.h>
static const sg_ext_param params[] = {
    {"crash", SG_EXT_FLOAT, {0.f}, 0.f, 1.f, "a per-frame draw"},
    {"above", SG_EXT_FLOAT, {2.f}, 0.f, 2.f, "crash when crash > above"},
    {"address", SG_EXT_FLOAT, {0.f}, 0.f, 0.f, "the address written to"},
    {"anywhere", SG_EXT_FLOAT, {0.f}, 0.f, 1.f, "1: also while the average is estimated (at creation)"},
    {"loop", SG_EXT_FLOAT, {0.f}, 0.f, 1.f, "1: loop forever instead of crashing"},
};
static void f(const sg_ext_point* q, const float* a, const sg_ext_host* h, float* out) {
  /* in the render, not while the average is estimated (p >= 0), unless anywhere */
  if (a[0] > a[1] && (a[3] > 0.5f || q->p[0] < -0.01f)) {
    volatile float forever = a[4];
    while (forever > 0.5f) {
    }
    volatile int* p = (volatile int*)(uintptr_t)a[2];
    *p = 1;  /* a real null-pointer write: SIGSEGV */
  }
  out[0] = 0.5f;
}
static const sg_ext_texture tex[] = {{"crash_tex", "crashes", 1, 0, params, 5, f, 0}};
SG_EXT_EXPORT const sg_ext_library* synthgen_extension(void) {
  static const sg_ext_library lib = {SG_EXT_ABI_VERSION, tex, 1, 0, 0};
  return &lib;
}
"""

TINY = os.path.join(os.path.dirname(__file__), "scenarios", "tiny.yaml")


def _crash_scenario(tmp_path, texture: str, count: int = 6) -> str:
    """tiny.yaml (``count`` frames) with the ground's albedo the texture ``{type: crash_tex,
    TEXTURE}`` of CRASH_C."""
    crash = _write(tmp_path, "crash.c", CRASH_C)
    text = open(TINY, encoding="utf-8").read().replace("count: 6", f"count: {count}")
    old = "ground: {size: 20, material: {type: diffuse, albedo: {uniform: [[0.2, 0.2, 0.2], [0.5, 0.5, 0.5]]}}}"
    assert old in text
    text = text.replace(old, "ground: {size: 20, material: {type: diffuse, albedo: {texture: {type: crash_tex, "
                             + texture + "}}}}")
    path = tmp_path / "crash.yaml"
    path.write_text(text + f"allow_extensions: true\nextensions: [{crash}]\n")
    return str(path)


def _some_frames_fail(tmp_path, options: str, count: int = 6):
    """A scenario whose extension texture crashes (or loops) in some of its frames, by a per-frame
    draw: (its path, those frames)."""
    from synthgen.scenario import load_scenario, sample_frame

    path = _crash_scenario(tmp_path, "crash: {uniform: [0, 1]}, above: 2" + options, count)
    sc = load_scenario(path, allow_extensions=True)
    draws = {k: v for k in range(sc.count) for key, v in sample_frame(sc, k).sampled.items() if "crash" in key}
    assert len(draws) == sc.count
    above = float(np.median(list(draws.values())))
    failing = {k for k, v in draws.items() if v > above}
    assert 0 < len(failing) < sc.count
    text = open(path, encoding="utf-8").read().replace("above: 2", f"above: {above!r}")
    open(path, "w", encoding="utf-8").write(text)
    return path, failing


@pytest.mark.parametrize("workers", [1, 2])
def test_a_crash_inside_an_extension_fails_only_its_frame(tmp_path, workers):
    """A segfault in a user's C code in a worker process -- with one worker (the default) too: that
    frame is reported failed (the worker died, again when rendered alone), every other frame is
    rendered and complete."""
    from synthgen import run as runner
    from synthgen.outputs.meta import frame_status

    n = 6 if workers > 1 else 4
    path, crashing = _some_frames_fail(tmp_path, "", count=n)
    out = str(tmp_path / "out")
    s = runner.run(path, out, workers=workers, progress=False, allow_extensions=True)
    failed = {f["frame"]: f["error"] for f in s["failures"]}
    assert set(failed) == crashing, s.text()
    for k, err in failed.items():
        assert "WorkerDied" in err and "SIGSEGV" in err and f"frame {k}" in err, err
    # The frame rendered alone wrote its scene's journal before rendering: replayed in a fresh
    # process, it crashes the same way (what a bug report carries).
    journals = [f["journal"] for f in s["failures"]]
    assert all(j.endswith(".journal") and os.path.isfile(j + ".bin") for j in journals), journals
    complete, broken = frame_status(out)
    assert set(complete) == set(range(n)) - crashing and not broken
    if workers == 1:
        return
    proc = subprocess.run([sys.executable, "-m", "synthgen", "replay", journals[0], "-o", str(tmp_path / "r"),
                           "--allow-extensions"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == -signal.SIGSEGV, (proc.returncode, proc.stderr[-2000:])
    assert s["task_bytes"] < 200 < s["shared_bytes"]


def test_a_crash_while_a_texture_is_created_fails_only_its_frames(tmp_path):
    """The crash in the texture's first evaluation (its average, when a frame creates it): the
    frames whose draw creates it fail, the others are written."""
    from synthgen import run as runner
    from synthgen.outputs.meta import frame_status

    path, crashing = _some_frames_fail(tmp_path, ", anywhere: 1", count=4)
    s = runner.run(path, str(tmp_path / "out"), progress=False, allow_extensions=True)
    failed = {f["frame"]: f["error"] for f in s["failures"]}
    assert set(failed) == crashing, s.text()
    assert all("WorkerDied" in e and "SIGSEGV" in e for e in failed.values()), failed
    complete, broken = frame_status(str(tmp_path / "out"))
    assert set(complete) == set(range(4)) - crashing and not broken


def test_validate_names_the_extension_that_crashes_when_first_evaluated(tmp_path, capsys):
    """A texture with constant parameters is created by `synthgen validate` (and before a run
    renders anything): a crash in its first evaluation is an error at its entry, naming the
    texture and the extension's file, instead of killing the command."""
    from synthgen import cli
    from synthgen import run as runner

    path = _crash_scenario(tmp_path, "crash: 1, above: 0, anywhere: 1", count=2)
    assert cli.main(["validate", path, "--allow-extensions"]) == 2
    err = capsys.readouterr().err
    expected = (r"crash\.yaml:14:\d+: ground\.material: the texture 'crash_tex' of the extension \S*crash\.c crashed "
                r"its process \(killed by SIGSEGV\) in its first evaluation")
    assert re.search(expected, err), err
    with pytest.raises(sg.SceneFileError, match=expected):
        runner.run(path, str(tmp_path / "out"), progress=False, allow_extensions=True)


def test_an_extension_that_loops_when_first_evaluated_is_an_error(tmp_path):
    from synthgen.scenario import check_inputs, load_scenario

    sc = load_scenario(_crash_scenario(tmp_path, "crash: 1, above: 0, anywhere: 1, loop: 1", count=2),
                       allow_extensions=True)
    with pytest.raises(sg.SceneFileError, match=r"crash\.yaml:14:\d+: ground\.material: the texture 'crash_tex' of "
                                                r"the extension \S*crash\.c did not finish its first evaluation .* "
                                                r"within 2 s"):
        check_inputs(sc, timeout=2.0)


def test_a_frame_that_loops_forever_times_out_and_the_run_goes_on(tmp_path):
    from synthgen import run as runner
    from synthgen.outputs.meta import frame_status

    path, looping = _some_frames_fail(tmp_path, ", loop: 1", count=2)
    # A limit well above a frame's time here (its worker's start included), under load too.
    s = runner.run(path, str(tmp_path / "out"), progress=False, allow_extensions=True, frame_timeout=12.0)
    failed = {f["frame"]: f for f in s["failures"]}
    assert set(failed) == looping, s.text()
    for k, f in failed.items():
        assert f["error"].startswith(f"TimedOut: frame {k} timed out after 12 s"), f["error"]
        assert f["journal"].endswith(".journal") and os.path.isfile(f["journal"] + ".bin")
    complete, broken = frame_status(str(tmp_path / "out"))
    assert set(complete) == {0, 1} - looping and not broken


def _interrupt(cmd, started) -> tuple:
    """Runs ``synthgen CMD`` in its own process group, sends it SIGINT (Ctrl-C) once
    ``started(stdout line)`` says so: (exit status, output, seconds from SIGINT to exit)."""
    # SIGINT at its default (a test run from a background job ignores it, and so would the child).
    p = subprocess.Popen([sys.executable, "-m", "synthgen", *cmd], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True, start_new_session=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        lines = []
        while not started(lines):
            line = p.stdout.readline()
            assert line or p.poll() is None, "".join(lines)
            lines.append(line)
        time.sleep(1.0)  # into the render
        t0 = time.monotonic()
        os.killpg(p.pid, signal.SIGINT)
        out, _ = p.communicate(timeout=60)
        return p.returncode, "".join(lines) + out, time.monotonic() - t0
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()


LOOP_SCENE = """
version: 1
allow_extensions: true
extensions: [{path}]
camera: {{width: 32, height: 24, fov_y: 40, look_at: {{eye: [0, 1, -4], target: [0, 0.5, 0]}}}}
textures: {{t: {{type: crash_tex, crash: 1, above: 0, loop: 1}}}}
materials: {{m: {{type: diffuse, albedo: {{texture: t}}}}}}
objects: [{{primitive: plane, size: [20, 20], class_id: 1, material: m}}]
lights: [{{type: sun, direction: [0, 1, 0], irradiance: 2}}]
render: {{spp: 2}}
"""


def test_ctrl_c_stops_a_run_and_a_render_in_an_endless_loop(tmp_path):
    """Every frame loops forever in the render: Ctrl-C still ends the run (the parent kills its
    worker) and `synthgen render` (its render in native code, in this process) at once."""
    path = _crash_scenario(tmp_path, "crash: 1, above: 0, loop: 1", count=3)
    out = tmp_path / "out"
    rc, text, seconds = _interrupt(["run", path, "-o", str(out), "--allow-extensions"],
                                   lambda lines: (out / "run_manifest.json").exists())
    assert rc == 130, text
    assert seconds < 5.0, (seconds, text)
    assert ("interrupted: 0 frame(s) finished in this run, 0 complete in the directory and kept; the same command "
            "with --resume renders the 3 missing") in text, text
    scene = tmp_path / "loop_scene.yaml"
    scene.write_text(LOOP_SCENE.format(path=_write(tmp_path, "crash.c", CRASH_C)))
    rc, text, seconds = _interrupt(["render", str(scene), "-o", str(tmp_path / "r"), "--allow-extensions"],
                                   lambda lines: any("spp" in x for x in lines))
    assert rc == 130 and "interrupted" in text, text
    assert seconds < 5.0, (seconds, text)
    assert not (tmp_path / "r").exists()


def test_a_changed_extension_replaces_its_plugins_and_old_objects_keep_their_code(tmp_path):
    path = _write(tmp_path, "ver.c", GOOD_TEX % ("0.25f", "ver_tex", 1, "SG_EXT_ABI_VERSION"))
    s = sg.Scene()
    s.load_extension(path)
    old = s.add_texture("ver_tex")
    _write(tmp_path, "ver.c", GOOD_TEX % ("0.75f", "ver_tex", 1, "SG_EXT_ABI_VERSION"))
    info = s.load_extension(path)
    assert not info["cached"]
    new = s.add_texture("ver_tex")
    pts = np.zeros((1, 3), np.float32)
    assert s.texture_values(old, pts)[0, 0] == 0.25 and s.texture_values(new, pts)[0, 0] == 0.75
