"""glint.render: shapes, finiteness, reproducibility and the checks before any work."""
import numpy as np
import pytest

import glint


def test_cornell_image():
    img, var = glint.render("cornell", width=40, height=30, spp=8, seed=1)
    assert img.shape == var.shape == (30, 40, 3) and img.dtype == var.dtype == np.float32
    assert np.all(np.isfinite(img)) and np.all(np.isfinite(var)) and np.all(var >= 0)
    assert 0.02 < img.mean() < 1.0  # a lit box, not black, not blown out
    # The red wall is on the left (columns 5 to 10 at this size), the green wall on the right (29 to 34).
    assert img[10:20, 6:10, 0].mean() > 2 * img[10:20, 6:10, 1].mean()
    assert img[10:20, 30:34, 1].mean() > 2 * img[10:20, 30:34, 0].mean()
    again, _ = glint.render("cornell", width=40, height=30, spp=8, seed=1, threads=1)
    np.testing.assert_array_equal(img, again)


def test_stats_and_first_hit_layers():
    img, var, info = glint.render("cornell", width=40, height=30, spp=4, seed=1, threads=1, aov=True)
    plain, _ = glint.render("cornell", width=40, height=30, spp=4, seed=1, threads=1)
    np.testing.assert_array_equal(img, plain)  # the layers leave the beauty pass alone
    assert info["paths"] == 40 * 30 * 4 and info["rays"] > info["paths"] and info["seconds"] > 0
    assert info["albedo"].shape == info["normal"].shape == (30, 40, 3) and info["depth"].shape == (30, 40)
    # Pixels on the red wall: one material. Its albedo the same in every pixel and red; its
    # normal (a pixel's mean over its hits; the wall's two triangles differ by 0.3 degrees)
    # of unit length to 1e-4, pointing right (+x, into the box); a finite depth.
    wall = (slice(10, 20), slice(6, 10))
    albedo = info["albedo"][wall].reshape(-1, 3)
    assert np.ptp(albedo, axis=0).max() < 1e-6 and albedo[0, 0] > 2 * albedo[0, 1]
    normal = info["normal"][wall].reshape(-1, 3)
    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1, atol=1e-4)
    assert normal[:, 0].min() > 0.99
    assert np.all(np.isfinite(info["depth"][wall])) and info["depth"][wall].min() > 0
    _, _, stats = glint.render("cornell", width=8, height=8, spp=1, stats=True)
    assert set(stats) == {"seconds", "rays", "paths", "capped_walks"}


def test_spp_lowers_the_variance():
    _, var4 = glint.render("cornell", width=16, height=16, spp=4)
    _, var64 = glint.render("cornell", width=16, height=16, spp=64)
    # The variance of a mean falls as 1/spp: 16 times, well above 4 over the whole image.
    assert var4.mean() > 4 * var64.mean()


def test_camera_and_inserted_mesh(tmp_path):
    f = tmp_path / "tetra.obj"
    f.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    img, _ = glint.render("cornell", width=16, height=16, spp=2, insert_mesh=str(f),
                          eye=(0, 1, 3.5), look_at=(0, 1, 0), fov=40)
    assert np.all(np.isfinite(img))


def test_obj_as_the_scene(tmp_path):
    # An OBJ whose material emits lights itself; one without lights gets a sky. Both framed.
    (tmp_path / "lamp.mtl").write_text("newmtl lamp\nKd 0 0 0\nKe 4 4 4\nnewmtl grey\nKd 0.5 0.5 0.5\n")
    (tmp_path / "lit.obj").write_text("mtllib lamp.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
                                      "v -0.2 1 -0.2\nv 0.2 1 -0.2\nv 0.2 1 0.2\nv -0.2 1 0.2\n"
                                      "usemtl grey\nf 1 4 3 2\nusemtl lamp\nf 5 6 7 8\n")
    (tmp_path / "dark.obj").write_text("v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 4 3 2\n")
    images = {}
    for name in ("lit.obj", "dark.obj"):
        img, var = glint.render(str(tmp_path / name), width=16, height=12, spp=4)
        assert img.shape == (12, 16, 3) and np.all(np.isfinite(img)) and np.all(var >= 0)
        images[name] = img
    # The lamp (Ke 4, 0.4 x 0.4, 1 above the floor) lights the floor in view: radiance up to
    # kd / pi * 4 * 0.16 = 0.10 below it; the lamp's back and the sky-less rest are black.
    lit = images["lit.obj"].sum(2)
    assert lit.max() > 0.02 * 3 and 0.05 < (lit > 0).mean() < 0.9
    # Without a light the sky lights everything: no black pixel.
    assert np.all(images["dark.obj"].sum(2) > 0)


@pytest.mark.parametrize("kwargs, message", [
    (dict(scene="nowhere"), "unknown scene 'nowhere'"),
    (dict(direct="best"), "unknown direct lighting 'best'"),
    (dict(width=0), r"width = 0 is outside \[1, 16384\]"),
    (dict(scene="/no/such/room.obj"), "cannot read the file"),
    (dict(scene="/no/such/room.gltf"), "cannot read the file"),
    (dict(scene="furnace", insert_mesh="x.obj"), "not one"),
    (dict(eye=(0, 0, 0), look_at=(0, 0, 0)), "eye and look_at must differ"),
])
def test_bad_arguments(kwargs, message):
    with pytest.raises(glint.Error, match=message):
        glint.render(**{"width": 8, "height": 8, "spp": 1, **kwargs})
