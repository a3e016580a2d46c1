import pathlib
import sys

# hits_io.py sits next to the tests.
sys.path.insert(0, str(pathlib.Path(__file__).parent))
