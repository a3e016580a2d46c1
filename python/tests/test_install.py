"""`cmake --install` puts a module that `import glint` finds (the component 'python' into a
scratch prefix; run by ctest, which says where the build tree is)."""
import os
import subprocess
import sys

import pytest

import glint


@pytest.mark.skipif("GLINT_BUILD_DIR" not in os.environ, reason="ctest gives the build tree")
def test_installed_module_imports(tmp_path):
    prefix = tmp_path / "prefix"
    subprocess.run([os.environ["GLINT_CMAKE"], "--install", os.environ["GLINT_BUILD_DIR"], "--component", "python",
                    "--prefix", str(prefix)], check=True, capture_output=True)
    site = prefix / os.environ["GLINT_PYTHON_INSTALL_DIR"]
    env = dict(os.environ, PYTHONPATH=str(site))
    out = subprocess.run([sys.executable, "-c", "import glint; print(glint.__version__, glint.__file__)"],
                         check=True, capture_output=True, text=True, env=env, cwd=tmp_path).stdout.split()
    assert out[0] == glint.__version__ and out[1].startswith(str(site))
