"""Tests of the Python module `stex` (python/stex_module.cpp), run by ctest (`python`) with PYTHONPATH at the
built module: analysis from files and NumPy arrays, save/load, renders as float32 (H, W, C) arrays, point
queries equal to renders bit for bit at pixel centres, errors (stex.Error with status), progress and
cancellation, the GIL released during device work, and threads sharing one context."""
import os
import sys
import threading
import time

import numpy as np
import pytest

import stex

SOURCE_DIR = os.environ.get("STEX_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
GRAVEL = os.path.join(SOURCE_DIR, "data", "gravel.png")


def colour_exemplar(width=48, height=40):
    y, x = np.mgrid[0:height, 0:width].astype(np.float32)
    rng = np.random.default_rng(5)
    channels = [0.3 + 0.1 * c + 0.2 * np.sin(0.7 * x + 0.3 * y + c) + 0.1 * rng.random((height, width))
                for c in range(3)]
    return np.stack(channels, axis=-1).astype(np.float32)


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


@pytest.fixture(scope="module")
def ctx():
    return stex.Context(os.environ.get("STEX_TEST_DEVICE", ""))  # the test device (conftest.py)


@pytest.fixture(scope="module")
def gravel():
    return stex.analyse(GRAVEL, support=16, iterations=8)


@pytest.fixture(scope="module")
def colour():
    return stex.analyse(colour_exemplar(), support=8, iterations=6)


def test_model_properties(gravel, colour):
    assert gravel.channels == 1 and colour.channels == 3
    assert gravel.support == 16
    info = gravel.info
    assert info["exemplar_size"] == (512, 512)
    assert info["iterations"] == 8
    assert len(colour.info["mean"]) == 3
    assert "support 16" in repr(gravel)
    assert stex.__version__


def test_render_is_float32_hwc_and_not_constant(ctx, colour):
    img = ctx.render(colour, -100, 50, 40, 24, seed=3)
    assert img.shape == (24, 40, 3) and img.dtype == np.float32
    assert img.flags["C_CONTIGUOUS"]
    assert float(img.max() - img.min()) > 0.05
    # Tiles join bit for bit, the seed changes the realisation, strategies agree.
    left = ctx.render(colour, -100, 50, 17, 24, seed=3)
    right = ctx.render(colour, -83, 50, 23, 24, seed=3)
    assert np.array_equal(bits(np.concatenate([left, right], axis=1)), bits(img))
    assert not np.array_equal(img, ctx.render(colour, -100, 50, 40, 24, seed=4))
    gather = ctx.render(colour, -100, 50, 40, 24, seed=3, strategy="gather")
    assert np.array_equal(bits(gather), bits(img))


def test_minified_renders_are_filtered_by_default(ctx, colour):
    # scale < 1: filtered (S1 §5 for a texton model of order 1), as stex render and stex serve do
    auto = ctx.render(colour, -10, 5, 24, 16, seed=2, scale=0.25)
    assert np.array_equal(bits(ctx.render(colour, -10, 5, 24, 16, seed=2, scale=0.25, filter="on")), bits(auto))
    point = ctx.render(colour, -10, 5, 24, 16, seed=2, scale=0.25, filter="off")
    assert not np.array_equal(bits(point), bits(auto))
    # filtered tiles join bit for bit
    left = ctx.render(colour, -10, 5, 9, 16, seed=2, scale=0.25)
    right = ctx.render(colour, -1, 5, 15, 16, seed=2, scale=0.25)
    assert np.array_equal(bits(np.concatenate([left, right], axis=1)), bits(auto))
    with pytest.raises(ValueError):
        ctx.render(colour, 0, 0, 8, 8, filter="sometimes")


def test_points_at_pixel_centres_equal_the_render(ctx, gravel, colour):
    for model in (gravel, colour):
        x0, y0, w, h = 1_000_003, -77, 31, 19
        img = ctx.render(model, x0, y0, w, h, mni=20, seed=9)
        ys, xs = np.mgrid[0:h, 0:w]
        xy = np.stack([x0 + xs + 0.5, y0 + ys + 0.5], axis=-1)  # (h, w, 2)
        vals = ctx.eval_points(model, xy, mni=20, seed=9)
        assert vals.shape == (h, w, model.channels) and vals.dtype == np.float32
        assert np.array_equal(bits(vals), bits(img))
    # Lists work, and (N, 2) gives (N, C).
    v = ctx.eval_points(gravel, [[0.5, 0.5], [3.25, -7.75]])
    assert v.shape == (2, 1)


def test_analyse_arrays_2d_and_3d_agree_and_save_load(ctx, tmp_path):
    grey = colour_exemplar()[..., 1]
    a = stex.analyse(grey, support=8, iterations=4)
    b = stex.analyse(grey[..., None], support=8, iterations=4)
    assert np.array_equal(bits(ctx.render(a, 0, 0, 16, 16)), bits(ctx.render(b, 0, 0, 16, 16)))
    # Non-contiguous and float64 input is converted.
    c = stex.analyse(np.asfortranarray(grey.astype(np.float64)), support=8, iterations=4)
    assert np.array_equal(bits(ctx.render(a, 0, 0, 16, 16)), bits(ctx.render(c, 0, 0, 16, 16)))
    path = str(tmp_path / "m.stex")
    a.save(path)
    loaded = stex.load(path)
    assert np.array_equal(bits(ctx.render(loaded, 5, 5, 16, 16)), bits(ctx.render(a, 5, 5, 16, 16)))
    stex.save(loaded, str(tmp_path / "n.stex"))
    assert os.path.getsize(tmp_path / "n.stex") == os.path.getsize(path)


def test_errors_carry_status(ctx, gravel, tmp_path):
    with pytest.raises(stex.Error) as e:
        stex.load(str(tmp_path / "missing.stex"))
    assert e.value.status == "STEX_INPUT" and e.value.code == 3
    assert "missing.stex" in str(e.value)
    assert isinstance(e.value, RuntimeError)
    with pytest.raises(stex.Error) as e:
        ctx.render(gravel, 0, 0, 8, 8, mni=-1.0)
    assert e.value.status == "STEX_USAGE"
    with pytest.raises(stex.Error) as e:
        ctx.eval_points(gravel, [[0.5, float("nan")]])
    assert e.value.status == "STEX_USAGE" and "point 0" in str(e.value)
    with pytest.raises(stex.Error) as e:
        stex.analyse(np.zeros((4, 4), np.float32), support=8)
    assert e.value.status == "STEX_INPUT"
    with pytest.raises(stex.Error) as e:
        stex.Context("no-such-device-xyz")
    assert e.value.status == "STEX_DEVICE"
    with pytest.raises(ValueError):
        ctx.render(gravel, 0, 0, 8, 8, strategy="fastest")
    with pytest.raises(ValueError):
        ctx.eval_points(gravel, np.zeros((4, 3)))
    with pytest.raises(ValueError):
        stex.analyse(np.zeros((2, 2, 2, 2), np.float32))


def test_progress_reports_cancels_and_propagates(ctx, gravel):
    seen = []
    ctx.render(gravel, 0, 0, 64, 160, progress=seen.append)
    assert seen[0] == 0.0 and seen[-1] == 1.0 and len(seen) >= 3
    assert all(b >= a for a, b in zip(seen, seen[1:]))

    with pytest.raises(stex.Error) as e:
        ctx.render(gravel, 0, 0, 64, 160, progress=lambda f: f > 0.3)
    assert e.value.status == "STEX_CANCELLED"

    class Stop(Exception):
        pass

    calls = []

    def stop(f):
        calls.append(f)
        if f > 0:
            raise Stop("from the callback")

    with pytest.raises(Stop):
        ctx.render(gravel, 0, 0, 64, 160, progress=stop)
    assert len(calls) == 2
    assert ctx.render(gravel, 0, 0, 8, 8).shape == (8, 8, 1)  # still usable


def test_gil_is_released_during_device_work(ctx, gravel):
    # With a huge switch interval a thread holding the GIL is never preempted: the counter thread (which
    # gives the GIL up voluntarily in sleep(0)) can only run while eval_points is inside stex if the module
    # released the GIL there.
    counter = [0]
    running = threading.Event()
    stop = threading.Event()

    def spin():
        running.set()
        while not stop.is_set():
            counter[0] += 1
            time.sleep(0)

    xy = np.random.default_rng(1).uniform(-1e6, 1e6, size=(200_000, 2))
    ctx.eval_points(gravel, xy[:10])  # kernels built outside the measured call
    old = sys.getswitchinterval()
    thread = threading.Thread(target=spin)
    try:
        thread.start()
        running.wait()
        sys.setswitchinterval(1000.0)
        before = counter[0]
        ctx.eval_points(gravel, xy)
        after = counter[0]
    finally:
        sys.setswitchinterval(old)
        stop.set()
        thread.join()
    assert after > before


def test_threads_share_one_context(ctx, gravel, colour):
    jobs = [(gravel if k % 2 else colour, k * 1001 - 3000, -k * 7, 24 + 4 * (k % 3), 16 + k, k) for k in range(8)]
    serial = [ctx.render(m, x, y, w, h, seed=s) for (m, x, y, w, h, s) in jobs]
    results = [[None] * len(jobs) for _ in range(4)]
    errors = []

    def work(t):
        try:
            for n in range(len(jobs)):
                k = (n * 3 + t) % len(jobs)
                m, x, y, w, h, s = jobs[k]
                results[t][k] = ctx.render(m, x, y, w, h, seed=s)
        except Exception as exc:  # reported below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(t,)) for t in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not errors
    for t in range(4):
        for k in range(len(jobs)):
            assert np.array_equal(bits(results[t][k]), bits(serial[k])), (t, k)


def surface_grid(n=40, m=50, spacing=20.0, seed=4):
    """Points on an n x m grid of the plane z = 0.3 x - 0.2 y, `spacing` world units apart, with random unit
    normals: (n, m, 3) positions and normals."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:n, 0:m].astype(np.float64) * spacing
    pos = np.stack([x, y, 0.3 * x - 0.2 * y], axis=-1)
    nrm = rng.normal(size=(n, m, 3))
    return pos, nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)


def test_surface_points_shape_statistics_and_frames(ctx, colour):
    assert colour.kind == "texton" and colour.info["kind"] == "texton"
    pos, nrm = surface_grid()
    vals = ctx.eval_surface_points(colour, pos, nrm, seed=5)
    assert vals.shape == (40, 50, 3) and vals.dtype == np.float32
    # Proposition 3: E g^s = the model mean. The points are 20 texels apart, more than the cube diagonal
    # r sqrt(3) = 9 sqrt(3) = 15.6 (support 8, bilinear), so they share no impulse: 2000 independent samples,
    # and the sample mean is within 4.5 standard errors (sample std / sqrt(2000)) of the model mean.
    flat = vals.reshape(-1, 3).astype(np.float64)
    mean = np.asarray(colour.info["mean"])
    stderr = flat.std(axis=0, ddof=1) / np.sqrt(flat.shape[0])
    assert np.all(flat.std(axis=0) > 1e-3)
    assert np.all(np.abs(flat.mean(axis=0) - mean) < 4.5 * stderr), (flat.mean(axis=0), mean, stderr)
    # A point's value does not depend on the other points of the call.
    one = ctx.eval_surface_points(colour, pos[3, 7], nrm[3, 7], seed=5)
    assert one.shape == (3,)
    assert np.array_equal(bits(one), bits(vals[3, 7]))
    part = ctx.eval_surface_points(colour, pos[5:9], nrm[5:9], seed=5)
    assert np.array_equal(bits(part), bits(vals[5:9]))
    # tangents=None takes the world X axis projected on the tangent plane: passing X itself is the same frame.
    x_axis = np.broadcast_to(np.array([1.0, 0.0, 0.0]), pos.shape)
    assert np.array_equal(bits(ctx.eval_surface_points(colour, pos, nrm, x_axis, seed=5)), bits(vals))
    # Another tangent turns the texton in the tangent plane; another seed is another realisation.
    y_axis = np.broadcast_to(np.array([0.0, 1.0, 0.0]), pos.shape)
    assert np.mean(bits(ctx.eval_surface_points(colour, pos, nrm, y_axis, seed=5)) != bits(vals)) > 0.5
    assert np.mean(bits(ctx.eval_surface_points(colour, pos, nrm, seed=6)) != bits(vals)) > 0.5
    # texel scales the texture: world positions scaled by 2 with texel 2 are the same texton positions
    # (exact: scaling by a power of two).
    assert np.array_equal(bits(ctx.eval_surface_points(colour, 2.0 * pos, nrm, seed=5, texel=2.0)), bits(vals))


def test_surface_points_errors(ctx, gravel):
    pos, nrm = surface_grid(2, 3)
    with pytest.raises(ValueError):
        ctx.eval_surface_points(gravel, pos, nrm[:1])
    with pytest.raises(ValueError):
        ctx.eval_surface_points(gravel, pos[..., :2], nrm[..., :2])
    with pytest.raises(ValueError):
        ctx.eval_surface_points(gravel, pos, nrm, nrm[:1])
    bad = nrm.copy()
    bad[1, 2] = 0.0
    with pytest.raises(stex.Error) as e:
        ctx.eval_surface_points(gravel, pos, bad)
    assert e.value.status == "STEX_USAGE" and "point 5: the normal is zero" in str(e.value)
    far = pos.copy()
    far[0, 0, 2] = 1e9
    with pytest.raises(stex.Error) as e:
        ctx.eval_surface_points(gravel, far, nrm)
    assert e.value.status == "STEX_USAGE" and "point 0" in str(e.value)
    with pytest.raises(stex.Error) as e:
        ctx.eval_surface_points(gravel, pos, nrm, mni=-1.0)
    assert e.value.status == "STEX_USAGE"
    assert ctx.eval_surface_points(gravel, np.zeros((0, 3)), np.zeros((0, 3))).shape == (0, 1)


def test_gil_is_released_during_surface_queries(ctx, gravel):
    counter = [0]
    running = threading.Event()
    stop = threading.Event()

    def spin():
        running.set()
        while not stop.is_set():
            counter[0] += 1
            time.sleep(0)

    rng = np.random.default_rng(2)
    pos = rng.uniform(-1e4, 1e4, size=(20_000, 3))
    nrm = rng.normal(size=(20_000, 3))
    ctx.eval_surface_points(gravel, pos[:10], nrm[:10])  # kernel built outside the measured call
    old = sys.getswitchinterval()
    thread = threading.Thread(target=spin)
    try:
        thread.start()
        running.wait()
        sys.setswitchinterval(1000.0)
        before = counter[0]
        ctx.eval_surface_points(gravel, pos, nrm)
        after = counter[0]
    finally:
        sys.setswitchinterval(old)
        stop.set()
        thread.join()
    assert after > before
