"""`pip install .` of a clone into a fresh virtual environment: from another folder, the installed
`planthub` validates, describes and runs shipped scenarios with the project's own FMUs.

What a clone holds is copied to tmp_path without build/, so the schemas, the scenarios and the
FMUs can only come from the wheel (setup.py compiles the FMUs while pip builds it, in pip's
isolated build environment). The pinned dependencies are installed once per set of pins into a
folder of the user's cache, which the fresh environment sees (a .pth file); `pip check` then
proves they meet every requirement the wheel's metadata names. Their wheels come from a
wheelhouse in the same cache, downloaded once per set of pins: pip's own cache keeps nothing on
this machine (the package index's answers reach it without caching headers), and the ~200 MB of
wheels (pybullet alone is 100 MB) took most of a minute to fetch; installing them took 31 s more.
The installed commands run with numba's JIT off (NUMBA_DISABLE_JIT): compiling the physics loops
is 25 s of an installed package's first run, they are the same files as the clone's, and
tests/physics/test_kernels.py runs the physics tests both ways.
Measured on the 2-core machine with the cache filled: the set-up 17 s (nearly all of it pip
building the wheel — the FMUs compiled one a core, the view's page bundled — and installing it
into a venv made without a pip of its own), the commands 3 s; 89 s the first time (the wheels
downloaded and installed).
"""
from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from .helpers import ROOT

pytestmark = pytest.mark.slow   # builds a wheel and installs it into a fresh environment

CACHE = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "planthub"


def _clean_env(**extra) -> dict:
    # No PYTHONPATH: the source tree must not leak into the installed planthub.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return {**env, "PIP_DISABLE_PIP_VERSION_CHECK": "1", "NUMBA_DISABLE_JIT": "1", **extra}


def _run(args, **kwargs) -> subprocess.CompletedProcess:
    proc = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    command = " ".join(map(str, args))
    assert proc.returncode == 0, f"{command} failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}"
    return proc


def copy_clone(target: Path) -> Path:
    """The files a clone of the work tree would hold, as they are now (committed or not)."""
    listed = _run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT).stdout
    for name in filter(None, listed.split("\0")):
        source = ROOT / name
        if source.is_file():   # a tracked file deleted in the work tree is not in the clone-to-be
            (target / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target / name)
    return target


def _pins() -> tuple[list[str], str]:
    """The build requirements, and every pin the install needs (runtime and build) as one text."""
    build = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    return build, "pip wheel\n" + (ROOT / "requirements.txt").read_text() + "\n".join(build)


def _once(name: str, make) -> Path:
    """CACHE/NAME-<hash of the pins>, made by `make(folder)` the first time (two test runs at once
    make it once: a lock; a half-made one is made again: a stamp written last)."""
    folder = CACHE / f"{name}-{hashlib.sha256(_pins()[1].encode()).hexdigest()[:16]}"
    CACHE.mkdir(parents=True, exist_ok=True)
    with open(CACHE / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder / ".complete").exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            (folder / ".complete").touch()
    return folder


def wheelhouse() -> Path:
    """Every pinned wheel the install needs, runtime and build; a pin published only as source is
    built into a wheel there, since the install takes nothing from the index to build it."""
    build, _ = _pins()
    return _once("wheelhouse", lambda folder: _run(
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--wheel-dir", folder, "-r", ROOT / "requirements.txt",
         *build], env=_clean_env()))


def dependencies(wheels: Path) -> Path:
    """A folder holding the pinned runtime dependencies, installed from `wheels`."""
    return _once("dependencies", lambda folder: _run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-index", "--find-links", wheels,
         "--target", folder, "-r", ROOT / "requirements.txt"], env=_clean_env()))


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(the venv's bin folder, the clone, a folder that is neither) after `pip install CLONE`."""
    tmp = tmp_path_factory.mktemp("packaging")
    clone = copy_clone(tmp / "clone")
    assert not (clone / "build").exists()
    wheels = wheelhouse()
    site = dependencies(wheels)
    # Without a pip of its own (4 s of the venv's making): this pip installs into it (`--python`).
    _run([sys.executable, "-m", "venv", "--without-pip", tmp / "venv"])
    bin_ = tmp / "venv" / "bin"
    pip = [sys.executable, "-m", "pip", "--python", bin_ / "python"]
    purelib = _run([bin_ / "python", "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"]).stdout.strip()
    (Path(purelib) / "planthub-dependencies.pth").write_text(f"{site}\n")
    # --no-index also holds for the isolated build environment (pip hands it on); PIP_CONSTRAINT
    # pins the build requirements' own dependencies.
    _run([*pip, "install", "--quiet", "--no-index", "--find-links", wheels, "--no-deps",
          clone], cwd=tmp, env=_clean_env(PIP_CONSTRAINT=str(clone / "requirements.txt")))
    checked = _run([*pip, "check"], cwd=tmp, env=_clean_env())
    assert checked.stdout.strip() == "No broken requirements found.", checked.stdout
    elsewhere = tmp / "elsewhere"
    elsewhere.mkdir()
    return bin_, clone, elsewhere


def planthub(installed, *args) -> subprocess.CompletedProcess:
    bin_, _, elsewhere = installed
    return subprocess.run([str(bin_ / "planthub"), *map(str, args)], capture_output=True, text=True,
                          cwd=elsewhere, env=_clean_env())


def packaged_root(installed) -> Path:
    bin_, _, elsewhere = installed
    proc = _run([bin_ / "python", "-c", "from hub.core.resources import ROOT; print(ROOT)"],
                cwd=elsewhere, env=_clean_env())
    return Path(proc.stdout.strip())


def test_the_installed_hub_reads_its_files_from_the_package(installed):
    root = packaged_root(installed)
    assert root.is_relative_to(installed[0].parent) and root.parts[-2:] == ("hub", "data")
    assert (root / "schemas" / "scenario.schema.json").is_file()
    assert (root / "build" / "fmus" / "track_switch-fmi2.fmu").is_file()
    assert (root / "scenarios" / "paper" / "acceleration.yaml").is_file()   # `planthub report paper` runs these
    assert (root / "build" / "view" / "index.html").is_file()   # the page `planthub view` serves
    assert (root / "build" / "view" / "assets" / "main.js").is_file()


def test_the_installed_version_is_the_projects(installed):
    bin_, _, elsewhere = installed
    proc = _run([bin_ / "python", "-c", "import hub; print(hub.__version__)"], cwd=elsewhere, env=_clean_env())
    assert proc.stdout.strip() == tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]


def test_validate_a_shipped_scenario(installed):
    scenario = installed[1] / "scenarios" / "switch_logic.yaml"
    proc = planthub(installed, "validate", scenario)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(f"{scenario}: ok — 8 objects, 3 flows")


def test_validate_the_packaged_copy_of_a_scenario_naming_an_fmu_by_relative_path(installed):
    # belt_ramp_fmu.yaml says `file: ../build/fmus/belt_drive-fmi2.fmu`: the package data keeps the layout.
    scenario = packaged_root(installed) / "scenarios" / "belt_ramp_fmu.yaml"
    proc = planthub(installed, "validate", scenario)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(f"{scenario}: ok")


def test_describe_a_module(installed):
    proc = planthub(installed, "describe", "switch")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("switch: Track switch")
    assert "  blade.to_working       void    target" in proc.stdout


def test_run_a_shipped_scenario_with_the_projects_own_fmu(installed, tmp_path):
    out = tmp_path / "out"
    proc = planthub(installed, "run", installed[1] / "scenarios" / "switch_logic.yaml", "--out", out)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("planthub run switch_logic")
    assert f"recording    {out / 'recording.csv'}" in proc.stdout
    assert "sw.logic.WorkingPos_marked" in (out / "recording.csv").read_text().splitlines()[0]
    # The switch's Petri-net FMU moved the blade: B, read first, went into the branch.
    assert any(line.endswith(",branch_end.bin.taken,B") for line in (out / "events.csv").read_text().splitlines())
