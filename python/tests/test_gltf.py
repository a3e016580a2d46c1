"""A glTF 2.0 scene written by the test (a Lambertian floor quad, a camera, a point light):
load_gltf's arrays, and render's image against the closed form of the point light's direct
light (the floor's only light: nothing else is lit to bounce it back)."""
import base64
import json

import numpy as np
import pytest

import glint

KD, INTENSITY_W = 0.8, 10.0  # the floor's reflectance; the light's W/sr (glTF: candela = 683 W/sr)
EYE, LIGHT, YFOV = np.array([0.0, 1.0, 3.0]), np.array([0.0, 2.0, 0.0]), 0.8


def write_gltf(path):
    vertices = np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], np.float32)
    indices = np.array([0, 3, 2, 0, 2, 1], np.uint32)  # counter-clockwise seen from +y
    data = vertices.tobytes() + indices.tobytes()
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": EYE.tolist()},
                  {"translation": LIGHT.tolist(), "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [KD, KD, KD, 1], "metallicFactor": 0,
                                                "roughnessFactor": 1}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": YFOV, "znear": 0.01, "aspectRatio": 1.0}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 683 * INTENSITY_W}]}},
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [-1, 0, -1], "max": [1, 0, 1]},
                      {"bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR"}],
    }
    path.write_text(json.dumps(doc))


@pytest.fixture
def floor(tmp_path):
    path = tmp_path / "floor.gltf"
    write_gltf(path)
    return str(path)


def test_load_gltf(floor):
    m = glint.load_gltf(floor)
    corners = [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]]
    assert m["vertices"].shape == (4, 3)  # merged, numbered in the order they first appear
    assert m["vertices"][m["indices"]].tolist() == [[corners[0], corners[3], corners[2]], [corners[0], corners[2], corners[1]]]
    assert m["camera"]["eye"] == pytest.approx(EYE) and m["camera"]["fov"] == pytest.approx(np.degrees(YFOV))


def closed_form(size, sub=16):
    """Each pixel's mean radiance over its area: kd / pi * I cos / r^2 where the camera ray meets
    the floor inside the quad, 0 elsewhere (sub x sub points per pixel)."""
    s = (np.arange(size * sub) + 0.5) / (size * sub)
    sx, sy = np.meshgrid(s, s)
    h = np.tan(YFOV / 2)
    d = np.stack([(2 * sx - 1) * h, (1 - 2 * sy) * h, -np.ones_like(sx)], -1)  # right = +x, up = +y, ahead = -z
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -EYE[1] / d[..., 1]
    p = EYE + t[..., None] * d
    on = (t > 0) & (np.abs(p[..., 0]) <= 1) & (np.abs(p[..., 2]) <= 1)
    to_light = LIGHT - p
    r2 = (to_light ** 2).sum(-1)
    radiance = np.where(on, KD / np.pi * INTENSITY_W * to_light[..., 1] / np.sqrt(r2) / r2, 0)
    return radiance.reshape(size, sub, size, sub).mean((1, 3))


def test_render_matches_the_closed_form(floor):
    size = 24
    img, var = glint.render(floor, width=size, height=size, spp=64, seed=2)
    expected = closed_form(size)
    assert expected.max() > 0.3  # the floor is in view and lit
    # The samples' only randomness is their position in the pixel: the image's mean over all
    # pixels is within a few of its standard errors of the closed form's (16^2 points per pixel).
    grey = img.mean(2)
    standard_error = np.sqrt(var.mean(2).sum()) / grey.size
    assert abs(grey.mean() - expected.mean()) < 4 * standard_error + 2e-4 * expected.mean()
    np.testing.assert_allclose(img[..., 0], img[..., 2])  # a grey scene stays grey
