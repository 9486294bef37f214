"""The scenes of bench/vs_cycles.py: moved to the package (``synthgen.bench.scenes``, shared
with ``synthgen bench``); this module re-exports all its names (underscored ones too) for the
scripts in bench/ and the tests."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))

from synthgen.bench import scenes as _scenes  # noqa: E402

globals().update({k: v for k, v in vars(_scenes).items() if not k.startswith("__")})
