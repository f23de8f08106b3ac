"""Where the project's files are found: the JSON Schemas, the built FMUs and the shipped scenarios.

They are in one of two places, with one layout (schemas/, build/fmus/, scenarios/):
- an installed wheel holds them as package data in hub/data/, which setup.py fills when it
  builds the wheel (the FMUs compiled by fmus/Makefile then);
- a source tree (a clone, an editable install) holds them beside hub/, its FMUs built by
  `make fmus`.
The package data keeps the source tree's layout so that a shipped scenario's relative
`file: ../build/fmus/….fmu` resolves in both. It is looked for first because an installed hub/
has site-packages beside it, whose schemas/ or scenarios/ could be another package's. Paths are
plain `Path`s, not importlib.resources traversables: fmpy and the schema loader open real files,
and a wheel is always installed unzipped.
"""
from __future__ import annotations

from pathlib import Path

_PACKAGE_DATA = Path(__file__).resolve().parents[1] / "data"
ROOT = _PACKAGE_DATA if _PACKAGE_DATA.is_dir() else Path(__file__).resolve().parents[2]
SCHEMAS = ROOT / "schemas"
BUILT_FMUS = ROOT / "build" / "fmus"
SCENARIOS = ROOT / "scenarios"
