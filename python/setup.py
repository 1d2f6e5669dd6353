"""Builds the s2kf extension module with the project's CMake (no other build system, nothing
downloaded): configure the repository one level up with only the Python module switched on, build
the s2kf_python target, and hand the resulting .so to setuptools."""
import os
import pathlib
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = pathlib.Path(__file__).resolve().parent
PROJECT = HERE.parent


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, extension):
        build = pathlib.Path(self.build_temp).resolve() / "cmake"
        target = pathlib.Path(self.get_ext_fullpath(extension.name)).resolve()
        subprocess.run(["cmake", "-S", str(PROJECT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                        "-DS2KF_BUILD_PYTHON=ON", "-DS2KF_BUILD_TESTS=OFF", "-DS2KF_BUILD_EXAMPLES=OFF",
                        "-DS2KF_BUILD_BENCHMARKS=OFF", "-DS2KF_INSTALL=OFF",
                        f"-DPython3_EXECUTABLE={sys.executable}"], check=True)
        jobs = str(os.cpu_count() or 2)
        subprocess.run(["cmake", "--build", str(build), "--target", "s2kf_python", "-j", jobs], check=True)
        built = next((build / "python").glob("s2kf*.so"))
        target.parent.mkdir(parents=True, exist_ok=True)
        self.copy_file(str(built), str(target))


setup(ext_modules=[CMakeExtension("s2kf")], cmdclass={"build_ext": CMakeBuild}, zip_safe=False)
