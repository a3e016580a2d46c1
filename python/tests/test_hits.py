"""glint.MeshBvh against the C++ API (the same mesh and 10^6 rays through MeshBvh's own loop:
the same hits, bit for bit) and against a brute-force numpy reference on a small mesh."""
import numpy as np
import pytest

import glint
from hits_io import comparison_mesh, cpp_hits, random_rays, sphere_mesh


@pytest.fixture(scope="module")
def mesh():
    return comparison_mesh()


@pytest.fixture(scope="module")
def rays(mesh):
    return random_rays(mesh[0], 10**6)


def test_same_hits_as_cpp(mesh, rays):
    vertices, indices, _ = mesh
    origins, directions = rays
    ref, _, _ = cpp_hits(vertices, indices, origins, directions)
    bvh = glint.MeshBvh(vertices, indices)
    hits = bvh.closest_hit(origins, directions, threads=1)
    assert (ref["id"] >= 0).mean() > 0.2  # the rays hit and miss
    for k in ("t", "u", "v", "id"):
        np.testing.assert_array_equal(hits[k], ref[k], err_msg=k)
    np.testing.assert_array_equal(bvh.any_hit(origins, directions, threads=1), ref["any"])


def test_threads_and_interval_agree_with_cpp(mesh, rays):
    vertices, indices, _ = mesh
    origins, directions = (a[:200000] for a in rays)
    tmin, tmax = 0.3, 0.9
    ref, _, _ = cpp_hits(vertices, indices, origins, directions, tmin, tmax)
    bvh = glint.MeshBvh(vertices, indices.astype(np.int32))
    hits = bvh.closest_hit(origins, directions, tmin, tmax, threads=3)
    np.testing.assert_array_equal(hits["t"], ref["t"])
    np.testing.assert_array_equal(hits["id"], ref["id"])
    hit = hits["id"] >= 0
    assert np.all((hits["t"][hit] > tmin) & (hits["t"][hit] < tmax)) and np.all(np.isinf(hits["t"][~hit]))
    np.testing.assert_array_equal(bvh.any_hit(origins, directions, tmin, tmax, threads=3), ref["any"])


def test_normals_are_the_hit_triangles(mesh, rays):
    vertices, indices, _ = mesh
    origins, directions = (a[:50000] for a in rays)
    hits = glint.MeshBvh(vertices, indices).closest_hit(origins, directions)
    hit = hits["id"] >= 0
    tri = vertices[indices[hits["id"][hit]]].astype(np.float64)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    np.testing.assert_allclose(hits["normal"][hit], n, atol=1e-5)
    assert np.all(hits["normal"][~hit] == 0)
    # The hit point o + t d is where the barycentrics put it.
    p = origins[hit] + hits["t"][hit, None] * directions[hit]
    q = tri[:, 0] + hits["u"][hit, None] * (tri[:, 1] - tri[:, 0]) + hits["v"][hit, None] * (tri[:, 2] - tri[:, 0])
    np.testing.assert_allclose(p, q, atol=1e-4)


def brute_force(vertices, indices, origins, directions):
    """Nearest hit of each ray over every triangle (Moller-Trumbore in float64): (t, id)."""
    tri = vertices[indices].astype(np.float64)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    t_best = np.full(len(origins), np.inf)
    id_best = np.full(len(origins), -1)
    for s in range(0, len(origins), 1000):
        o, d = origins[s:s + 1000, None].astype(np.float64), directions[s:s + 1000, None].astype(np.float64)
        p = np.cross(d, e2)
        det = np.einsum("rtk,tk->rt", p, e1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1 / det
            s_ = o - tri[:, 0]
            u = np.einsum("rtk,rtk->rt", s_, p) * inv
            q = np.cross(s_, e1)
            v = np.einsum("rtk,rtk->rt", d, q) * inv
            t = np.einsum("tk,rtk->rt", e2, q) * inv
        t = np.where((det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0), t, np.inf)
        id_best[s:s + 1000] = np.where(np.isinf(t.min(1)), -1, t.argmin(1))
        t_best[s:s + 1000] = t.min(1)
    return t_best, id_best


def test_brute_force_reference():
    vertices, indices = sphere_mesh(rings=8, segments=16, seed=3)
    origins, directions = random_rays(vertices, 20000, seed=11)
    hits = glint.MeshBvh(vertices, indices).closest_hit(origins, directions)
    t, ids = brute_force(vertices, indices, origins, directions)
    assert 0.3 < (ids >= 0).mean() < 1
    same = hits["id"] == ids
    # Rays through an edge may pick either neighbour (at the same t); nothing else may differ.
    assert same.mean() > 0.999
    np.testing.assert_allclose(hits["t"], t.astype(np.float32), rtol=1e-4)
