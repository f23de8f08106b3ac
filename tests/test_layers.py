"""The house's layers (hub/README.md): no file under hub/ imports `modules`, no import cycle among
hub/'s files, and each subpackage imports only the ones below it.

Every import statement is read with `ast`, including those inside functions (a lazy import is
still a dependency) and under `if TYPE_CHECKING:`."""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

from .helpers import ROOT

HUB = ROOT / "hub"

#: subpackage → the subpackages it may import (besides itself). The order of hub/README.md's table.
ALLOWED = {
    "core": set(),
    "bus": {"core"},
    "scenario": {"core", "bus"},
    "physics": {"core"},
    "logic": {"core", "bus"},
    "view": {"core", "bus", "physics"},
    "run": {"core", "bus", "scenario", "physics", "logic", "view"},
    "reports": {"core", "scenario", "physics", "run"},
    "gateway": {"core", "bus", "scenario"},
    "campaign": {"core", "scenario", "run"},
    "cli": {"core", "bus", "scenario", "physics", "logic", "run", "reports", "view", "gateway", "campaign"},
}
#: files at the top of hub/: the public names users write, and what each stands for
TOP = {"__init__": {"run"}, "__main__": {"cli"}, "participant": {"bus"}, "live": {"bus"}}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, name: str | None = None, known=frozenset()) -> set[str]:
    """The absolute names of the modules `path` (the module `name`) imports. `from p import m`,
    where p.m is one of the `known` modules, imports p.m (p is then being imported already)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    here = (name or module_name(path)).split(".")
    package = here if path.name == "__init__.py" else here[:-1]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            name = ".".join(base + ([node.module] if node.module else []))
            inner = {f"{name}.{alias.name}" for alias in node.names}   # `from hub.bus import wire`
            found |= (inner & known) or {name} | inner
    return found


def hub_files() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(HUB.rglob("*.py"))}


def graph() -> dict[str, set[str]]:
    """hub module → the hub modules it imports (a package stands for its __init__)."""
    files = hub_files()
    known = frozenset(files)
    return {name: {i for i in imports(path, known=known) if i in files and i != name} for name, path in files.items()}


def test_no_file_of_hub_imports_the_plant_modules():
    offenders = [f"{name} imports {i}" for name, path in hub_files().items() for i in sorted(imports(path))
                 if i == "modules" or i.startswith("modules.")]
    assert not offenders, "the kernel knows no plant:\n" + "\n".join(offenders)


def test_the_layers_only_look_down():
    wrong = []
    for name, deps in graph().items():
        own = name.split(".")[1] if "." in name else "__init__"
        allowed = ALLOWED.get(own, TOP.get(own))
        assert allowed is not None, f"{name}: a file of hub/ in no layer; add it to hub/README.md's table and ALLOWED"
        for dep in sorted(deps):
            other = dep.split(".")[1] if "." in dep else "__init__"
            if other != own and other not in allowed:
                wrong.append(f"{name} imports {dep} ({own} may import {', '.join(sorted(allowed)) or 'nothing of hub'})")
    assert not wrong, "\n".join(wrong)


def test_no_import_cycle_among_the_files_of_hub():
    edges = graph()
    state: dict[str, int] = {}   # 1: on the path, 2: done
    cycles = []

    def visit(node, path):
        state[node] = 1
        for dep in sorted(edges.get(node, ())):
            if state.get(dep) == 1:
                cycles.append(" → ".join(path[path.index(dep):] + [dep]))
            elif dep not in state:
                visit(dep, path + [dep])
        state[node] = 2

    for node in sorted(edges):
        if node not in state:
            visit(node, [node])
    assert not cycles, "import cycles:\n" + "\n".join(cycles)


def test_the_checker_reads_every_import_form(tmp_path):
    """The walk above could pass by reading nothing: here it must find each kind of import."""
    source = tmp_path / "probe.py"
    source.write_text("import a.b\nfrom c import d\ndef f():\n    from e.f import g\n")
    assert {"a.b", "c", "c.d", "e.f", "e.f.g"} <= imports(source, "hub.x.probe")


def test_the_participant_library_is_light():
    """What a PLC author ships with their code loads none of the hub's heavy dependencies."""
    heavy = ["jsonschema", "yaml", "pybullet", "fmpy", "numpy", "lxml"]
    code = ("import sys, hub.participant, hub.live; from hub.participant import Participant, serve; "
            f"print(sorted(set({heavy!r}) & set(sys.modules)))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]", f"import hub.participant loads {proc.stdout.strip()}"


def test_readme_quotes_the_step_loop_from_the_masters_docstring():
    """The step loop is written down once, in hub.run.master.Master's docstring; hub/run/README.md quotes it."""
    import inspect

    from hub.run.master import Master

    readme = (ROOT / "hub" / "run" / "README.md").read_text(encoding="utf-8")
    start = readme.index("<!-- step loop:")
    quoted = readme[readme.index("\n", start) + 1:readme.index("<!-- end: step loop -->")].strip()
    paragraphs = inspect.getdoc(Master).split("\n\n")
    assert quoted == "\n\n".join(paragraphs[1:5]), "hub/run/README.md's step loop differs from Master's docstring"
