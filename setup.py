# pyproject.toml says what the package is; this adds what setuptools cannot say there: files
# beside top-level modules (not in a package). busservo_web looks for its page beside itself,
# and editors look for a module's stub (.pyi) there too.
import glob
import os

from setuptools import setup
from setuptools.command.build_py import build_py

BESIDE = ["lib/busservo_web.html.gz"] + sorted(glob.glob("lib/*.pyi"))


class BuildPy(build_py):
    def run(self):
        super().run()
        for path in BESIDE:
            self.copy_file(path, os.path.join(self.build_lib, os.path.basename(path)))


setup(cmdclass={"build_py": BuildPy})
