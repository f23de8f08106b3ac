"""Where the project's files are found: the JSON Schemas, the built FMUs and the shipped scenarios."""
from __future__ import annotations

from pathlib import Path

# In a source tree (a clone, an editable install) they sit beside hub/.
SOURCE_TREE = Path(__file__).resolve().parents[2]
SCHEMAS = SOURCE_TREE / "schemas"
BUILT_FMUS = SOURCE_TREE / "build" / "fmus"
SCENARIOS = SOURCE_TREE / "scenarios"
