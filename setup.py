"""What the package build adds to pyproject.toml: the project's FMUs, schemas and scenarios as package data.

A wheel has no source tree beside it, so what the hub reads at run time travels inside the `hub`
package, in hub/data/, laid out as in the source tree (hub/core/resources.py says why). The FMUs
are compiled here by fmus/Makefile, as a C-extension package compiles its code: gcc and make
are all it needs, and the build requirements in pyproject.toml give the Makefile its Python
(PyYAML, jsonschema, lxml) and fmpy's FMI headers. An editable install builds nothing: it
reads schemas/ and build/fmus/ beside hub/, which `make fmus` fills.
"""
from __future__ import annotations

import glob
import os
import subprocess
import sys

from setuptools import Distribution, setup
from setuptools.command.bdist_wheel import bdist_wheel
from setuptools.command.build_py import build_py
from setuptools.command.egg_info import egg_info
from setuptools.errors import ExecError

ROOT = os.path.dirname(os.path.abspath(__file__))
# source pattern (recursive, relative to ROOT) → folder under hub/data/ it is copied to
PACKAGE_DATA = {"schemas/*.json": "schemas", "scenarios/**/*.yaml": "scenarios"}
VIEW_BUNDLE = os.path.join(ROOT, "build", "view")
# What an sdist needs beyond the packages, to build the wheel again from it.
SDIST_FOLDERS = ("fmus", "schemas", "scenarios", "hub/view/web")


class BuildPyWithData(build_py):
    """build_py, then the FMUs compiled and the package data copied into build_lib's hub/data/."""

    def run(self):
        super().run()
        self._data_outputs = []
        if self.editable_mode:
            return
        data = os.path.join(self.build_lib, "hub", "data")
        for pattern, folder in PACKAGE_DATA.items():
            base = os.path.join(ROOT, pattern.split("/")[0])
            for path in sorted(glob.glob(os.path.join(ROOT, pattern), recursive=True)):
                self._copy(path, os.path.join(data, folder, os.path.relpath(path, base)))
        for fmu in self._build_fmus():
            self._copy(fmu, os.path.join(data, "build", "fmus", os.path.basename(fmu)))
        for path in self._view_bundle():
            self._copy(path, os.path.join(data, "build", "view", os.path.relpath(path, VIEW_BUNDLE)))

    def _view_bundle(self) -> list[str]:
        """The page of `planthub view` (hub/view/web/, bundled by esbuild into build/view/): built
        here with npm when the source tree has no bundle yet. Without npm the wheel goes without it,
        and `planthub view` says how to build it."""
        index = os.path.join(VIEW_BUNDLE, "index.html")
        if not os.path.isfile(index):
            web = os.path.join(ROOT, "hub", "view", "web")
            try:
                subprocess.run(["npm", "ci", "--no-audit", "--no-fund"], cwd=web, check=True)
                subprocess.run(["npm", "run", "build"], cwd=web, check=True)
            except (OSError, subprocess.CalledProcessError) as exc:
                print(f"setup.py: warning: the view's page is not in this wheel: building it with npm failed ({exc})",
                      file=sys.stderr)
                return []
        return sorted(p for p in glob.glob(os.path.join(VIEW_BUNDLE, "**", "*"), recursive=True)
                      if os.path.isfile(p) and not os.path.basename(p).startswith("."))

    def _build_fmus(self) -> list[str]:
        # Outside the source tree's build/fmus/, which belongs to `make fmus` and the dev venv:
        # this Python's fmpy headers would change its recorded flags and rebuild it.
        out = os.path.join(os.path.abspath(self.get_finalized_command("build").build_temp), "fmus")
        # One compiler a core: 5 s here on 2 cores instead of 10.
        command = ["make", f"-j{os.cpu_count() or 1}", "--no-print-directory", "-C", os.path.join(ROOT, "fmus"),
                   f"PYTHON={sys.executable}", f"BUILD={out}"]
        try:
            subprocess.run(command, check=True)
        except (OSError, subprocess.CalledProcessError) as exc:
            raise ExecError(f"fmus/Makefile: building the project's FMUs failed ({exc}); "
                            "they need make, gcc and the build requirements of pyproject.toml") from exc
        fmus = sorted(glob.glob(os.path.join(out, "*.fmu")))
        if not fmus:
            raise ExecError(f"fmus/Makefile built no FMU into {out}")
        return fmus

    def _copy(self, source: str, target: str) -> None:
        self.mkpath(os.path.dirname(target))
        self.copy_file(source, target)
        self._data_outputs.append(target)

    def get_outputs(self, include_bytecode=True):
        return super().get_outputs(include_bytecode) + getattr(self, "_data_outputs", [])


class WithMachineCode(Distribution):
    """The FMUs hold machine code: installed to platlib, in a wheel for this platform only."""

    def has_ext_modules(self):
        return True


class PlatformWheel(bdist_wheel):
    """A wheel for this platform, for any Python 3: the FMUs call no CPython ABI."""

    def get_tag(self):
        _, _, platform = super().get_tag()
        return "py3", "none", platform


class EggInfoWithSources(egg_info):
    """The sdist's file list (setuptools gathers it here, not in sdist) with what the wheel's
    build needs beyond the packages: the FMUs' C and Python sources, the schemas, the scenarios."""

    def find_sources(self):
        super().find_sources()
        for folder in SDIST_FOLDERS:
            self.filelist.extend(path for path in sorted(glob.glob(f"{folder}/**/*", recursive=True))
                                 if os.path.isfile(path) and "__pycache__" not in path and "node_modules" not in path)


setup(distclass=WithMachineCode,
      cmdclass={"build_py": BuildPyWithData, "bdist_wheel": PlatformWheel, "egg_info": EggInfoWithSources})
