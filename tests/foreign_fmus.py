"""FMUs that stand in for other exporters' (tests/fmu_models/foreign): hand-written C against the FMI
headers, not the project's framework, with every FMI function they do not implement generated here
as a stub that returns an error (fmpy binds every function of the standard when it loads an FMU)."""
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import fmpy

SOURCES = Path(__file__).resolve().parent / "fmu_models" / "foreign"
HEADERS = Path(fmpy.__file__).parent / "c-code"
_PLATFORM = {2: "linux64", 3: "x86_64-linux"}
_DEFINED = re.compile(r"^[A-Za-z0-9_ *]+?\b(fmi[23]\w+)\s*\(", re.MULTILINE)
_TYPEDEF = re.compile(r"typedef\s+([\w\s*]+?)\s*\b(fmi[23]\w+)TYPE\s*\(([^;]*?)\)\s*;", re.DOTALL)


def stubs(version: int, defined: set[str]) -> str:
    """C definitions of every function of fmi<version>FunctionTypes.h not in `defined`: each returns an error."""
    text = (HEADERS / f"fmi{version}FunctionTypes.h").read_text()
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.DOTALL)
    out = [f'#include "fmi{version}Functions.h"', ""]
    for returns, name, params in _TYPEDEF.findall(text):
        if name in defined:
            continue
        returns = " ".join(returns.split())
        body = {"void": "", f"fmi{version}Status": f"return fmi{version}Error;"}.get(returns, "return 0;")
        out.append(f"{returns} {name}({' '.join(params.split())}) {{ {body} }}")
    return "\n".join(out) + "\n"


def build(name: str, version: int, out: Path) -> Path:
    """Compile tests/fmu_models/foreign/<name>.c with its stubs and package it with <name>.xml: out/<name>.fmu."""
    source = SOURCES / f"{name}.c"
    work = out / f"{name}-build"
    work.mkdir(parents=True, exist_ok=True)
    defined = set(_DEFINED.findall(source.read_text()))
    (work / "stubs.c").write_text(stubs(version, defined))
    library = work / f"{name}.so"
    subprocess.run(["gcc", "-std=c99", "-O2", "-fPIC", "-shared", "-Wall", "-Werror", "-Wno-unused-parameter",
                    f"-I{HEADERS}", "-o", str(library), str(source), str(work / "stubs.c"), "-Wl,-z,defs"],
                   check=True, capture_output=True, text=True)
    fmu = out / f"{name}.fmu"
    with zipfile.ZipFile(fmu, "w") as archive:
        archive.write(SOURCES / f"{name}.xml", "modelDescription.xml")
        archive.write(library, f"binaries/{_PLATFORM[version]}/{name}.so")
    return fmu


if __name__ == "__main__":   # python -m tests.foreign_fmus OUT: the stand-in FMUs, for README's example
    import sys

    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "build/foreign")
    folder.mkdir(parents=True, exist_ok=True)
    for name, version in (("enum2", 2), ("typed3", 3), ("ball2", 2), ("tank3", 3), ("ticks3", 3), ("stair", 3)):
        print(build(name, version, folder))


def build_python_fmu(out: Path) -> Path:
    """tests/fmu_models/python/belt_drive_py.py exported by PythonFMU into `out`: an FMU another tool
    built (its description declares no FMU state)."""
    source = Path(__file__).resolve().parent / "fmu_models" / "python" / "belt_drive_py.py"
    subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", str(source), "-d", str(out)],
                   check=True, capture_output=True)
    return out / "belt_drive_py.fmu"
