"""The module's version, its exception and the checks of its arguments."""
import pathlib
import re

import numpy as np
import pytest

import glint

REPO = pathlib.Path(__file__).resolve().parents[2]
TRIANGLE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32), np.array([[0, 1, 2]], np.uint32)


def test_version_is_the_headers():
    text = (REPO / "include" / "glint" / "version.hpp").read_text()
    assert glint.__version__ == re.search(r'version_string = "([0-9.]+)"', text).group(1)


def test_error_is_a_runtime_error_with_the_message(tmp_path):
    assert issubclass(glint.Error, RuntimeError)
    with pytest.raises(glint.Error, match=r"load_obj\(/no/such/file.obj\): cannot read the file"):
        glint.load_obj("/no/such/file.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n")
    with pytest.raises(glint.Error, match=re.escape(f"{bad}:3") + ".*not a finite number"):
        glint.load_obj(str(bad))
    with pytest.raises(glint.Error, match="face refers to vertex 4"):
        bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
        glint.load_obj(str(bad))


def test_load_obj_arrays(tmp_path):
    f = tmp_path / "quad.obj"
    f.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    m = glint.load_obj(str(f))
    assert m["vertices"].dtype == np.float32 and m["vertices"].shape == (4, 3)
    assert m["indices"].tolist() == [[0, 1, 2], [0, 2, 3]]
    assert m["line"].tolist() == [5, 5] and m["materials"][m["material"][0]]["name"] == "default"


@pytest.mark.parametrize("vertices, indices, message", [
    (TRIANGLE[0].astype(np.float64), TRIANGLE[1], "vertices: dtype float64, expected float32"),
    (TRIANGLE[0][:, :2].copy(), TRIANGLE[1], r"vertices: shape \(3, 2\), expected \(n, 3\)"),
    (np.asfortranarray(np.tile(TRIANGLE[0], (2, 1))), TRIANGLE[1], "vertices: not C-contiguous"),
    (TRIANGLE[0].tolist(), TRIANGLE[1], "vertices: expected a numpy array.*got list"),
    (TRIANGLE[0], TRIANGLE[1].astype(np.int64), "indices: dtype int64, expected int32 or uint32"),
    (TRIANGLE[0], np.array([[0, 1, -1]], np.int32), "indices: triangle 0 has vertex index -1"),
    (TRIANGLE[0], np.array([[0, 1, 3]], np.uint32), "triangle 0 has vertex index 3 but there are 3 vertices"),
])
def test_bad_mesh_arrays(vertices, indices, message):
    with pytest.raises(glint.Error, match="MeshBvh: .*" + message):
        glint.MeshBvh(vertices, indices)


def test_bad_rays():
    bvh = glint.MeshBvh(*TRIANGLE)
    o = np.zeros((4, 3), np.float32)
    with pytest.raises(glint.Error, match="origins has 4 rows but directions has 3"):
        bvh.closest_hit(o, o[:3])
    with pytest.raises(glint.Error, match="directions: dtype float64"):
        bvh.any_hit(o, o.astype(np.float64))
    with pytest.raises(glint.Error, match="need tmin <= tmax"):
        bvh.closest_hit(o, o, tmin=2, tmax=1)
    with pytest.raises(glint.Error, match="threads = -1 is negative"):
        bvh.closest_hit(o, o, threads=-1)


def test_one_ray_by_hand():
    bvh = glint.MeshBvh(*TRIANGLE)
    o = np.array([[0.25, 0.5, 1], [2, 2, 1]], np.float32)
    d = np.array([[0, 0, -2], [0, 0, -1]], np.float32)
    h = bvh.closest_hit(o, d)
    assert h["t"][0] == 0.5 and h["u"][0] == 0.25 and h["v"][0] == 0.5 and h["id"][0] == 0
    assert h["normal"][0].tolist() == [0, 0, 1]
    assert np.isinf(h["t"][1]) and h["id"][1] == -1
    assert bvh.any_hit(o, d).tolist() == [True, False]
    assert not bvh.any_hit(o, d, tmax=0.5)[0]  # t in the open interval (tmin, tmax)
    assert bvh.closest_hit(o, d, normals=False)["normal"].tolist() == [[0, 0, 0], [0, 0, 0]]


def test_empty_degenerate_and_nan_inputs_miss():
    o, d = np.zeros((5, 3), np.float32), np.ones((5, 3), np.float32)
    empty = glint.MeshBvh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32))
    assert empty.closest_hit(o, d)["id"].tolist() == [-1] * 5 and not empty.any_hit(o, d).any()
    flat = glint.MeshBvh(TRIANGLE[0], np.array([[0, 0, 1]], np.uint32))  # zero area
    assert flat.closest_hit(o, d)["id"].tolist() == [-1] * 5
    nan = np.full((2, 3), np.nan, np.float32)
    h = glint.MeshBvh(*TRIANGLE).closest_hit(nan, d[:2])
    assert h["id"].tolist() == [-1, -1] and np.all(np.isinf(h["t"])) and np.all(h["normal"] == 0)
    none = np.zeros((0, 3), np.float32)
    assert glint.MeshBvh(*TRIANGLE).closest_hit(none, none)["t"].shape == (0,)
