"""Builds synthgen._core by driving CMake from setuptools (scikit-build-core is not
packaged in Debian). `pip install --no-build-isolation .` works in any Python
environment that has the system libraries listed in README.md."""
import os
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        out_dir = Path(self.get_ext_fullpath(ext.name)).parent.resolve()
        # In-place (editable) builds share the developer build tree with `make`;
        # regular installs build in setuptools' temporary directory.
        if self.inplace:
            build_dir = ROOT / "build"
            tests = "ON"
        else:
            build_dir = Path(self.build_temp).resolve() / "cmake"
            tests = "OFF"
        build_dir.mkdir(parents=True, exist_ok=True)
        cfg = [
            "cmake", "-S", str(ROOT), "-B", str(build_dir),
            "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}",
            f"-DSYNTHGEN_PYTHON_OUTPUT_DIR={out_dir}",
            f"-DSYNTHGEN_BUILD_TESTS={tests}",
        ]
        subprocess.run(cfg, check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 2))
        targets = ["_core", "synthgen_image_io", "synthgen_vdb", "synthgen_reader"]
        subprocess.run(["cmake", "--build", str(build_dir), *[a for t in targets for a in ("--target", t)], "-j", jobs],
                       check=True)


setup(
    ext_modules=[CMakeExtension("synthgen._core")],
    cmdclass={"build_ext": CMakeBuild},
)
