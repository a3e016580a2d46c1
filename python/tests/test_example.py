"""python/examples/render_and_plot.py runs and writes its figure (matplotlib, Agg)."""
import os
import pathlib
import subprocess
import sys

import pytest

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "render_and_plot.py"


def test_render_and_plot(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "cornell.png"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    subprocess.run([sys.executable, str(EXAMPLE), str(out)], check=True, env=env, cwd=tmp_path, timeout=120)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10000
