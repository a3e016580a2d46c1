"""The rays files of glint_python_hits (python/src/hits_tool.cpp): the same mesh and rays
traced by MeshBvh's own C++ loop, for the tests' comparison and bench_throughput.py."""
import os
import pathlib
import subprocess
import tempfile

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[2]


def hits_tool():
    """The glint_python_hits executable: $GLINT_HITS_TOOL, else next to the module."""
    if os.environ.get("GLINT_HITS_TOOL"):
        return os.environ["GLINT_HITS_TOOL"]
    import glint
    return str(pathlib.Path(glint.__file__).parent / "glint_python_hits")


def scenes_dir():
    """The shared meshes: $GLINT_SCENES, else ../shared/scenes beside the repository."""
    return pathlib.Path(os.environ.get("GLINT_SCENES", REPO.parent / "shared" / "scenes"))


def sphere_mesh(rings=100, segments=200, seed=1):
    """A bumpy UV sphere (2 * rings * segments triangles, some at the poles degenerate)."""
    rng = np.random.default_rng(seed)
    theta = np.linspace(0, np.pi, rings + 1)[:, None]
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)[None, :]
    r = 1 + 0.05 * rng.standard_normal((rings + 1, segments))
    p = np.stack([r * np.sin(theta) * np.cos(phi), r * np.cos(theta) * np.ones_like(phi),
                  r * np.sin(theta) * np.sin(phi)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a, b = i * segments + j, i * segments + (j + 1) % segments
    c, d = a + segments, b + segments
    tris = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    return p.astype(np.float32), tris.astype(np.uint32)


def comparison_mesh():
    """The shared bunny if it is there, else the generated sphere: (vertices, indices, name)."""
    bunny = scenes_dir() / "bunny.obj"
    if bunny.exists():
        import glint
        m = glint.load_obj(str(bunny))
        return m["vertices"], m["indices"], "bunny.obj"
    v, i = sphere_mesh()
    return v, i, "generated sphere"


def random_rays(vertices, n, seed=7):
    """n rays from points around the mesh's bounding box toward points inside it (float32)."""
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(0), vertices.max(0)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    u = rng.standard_normal((n, 3))
    origins = centre + 1.5 * radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    targets = lo + (hi - lo) * rng.random((n, 3))
    return origins.astype(np.float32), (targets - origins).astype(np.float32)


def cpp_hits(vertices, indices, origins, directions, tmin=0.0, tmax=np.inf):
    """Runs glint_python_hits; returns (hits dict as closest_hit's without normal plus 'any',
    closest-hit loop seconds, any-hit loop seconds)."""
    n = len(origins)
    with tempfile.TemporaryDirectory() as tmp:
        rays, out = os.path.join(tmp, "rays.bin"), os.path.join(tmp, "hits.bin")
        with open(rays, "wb") as f:
            f.write(b"GLNTRAYS")
            f.write(np.array([len(vertices), len(indices), n], np.uint64).tobytes())
            f.write(np.array([tmin, tmax], np.float32).tobytes())
            for a, t in ((vertices, np.float32), (indices, np.uint32), (origins, np.float32), (directions, np.float32)):
                f.write(np.ascontiguousarray(a, t).tobytes())
        text = subprocess.run([hits_tool(), rays, out], check=True, capture_output=True, text=True).stdout.split()
        data = open(out, "rb").read()
    hits, offset = {}, 0
    for name, t in (("t", np.float32), ("u", np.float32), ("v", np.float32), ("id", np.int32), ("any", np.uint8)):
        hits[name] = np.frombuffer(data, t, n, offset)
        offset += n * np.dtype(t).itemsize
    hits["any"] = hits["any"].astype(bool)
    return hits, float(text[1]), float(text[3])
