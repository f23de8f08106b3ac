"""Files written whole or not at all: to a hidden partial file beside the target, synced, then renamed over it."""
from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def written(path: Path, mode: str = "w", **options):
    """`path` open for writing (`mode` "w" or "wb", `options` as open() takes them), in its place
    only once the block ends without an exception: a reader, or a run killed meanwhile, never finds
    half a file. Its folder is made if need be."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    try:
        with open(partial, mode, **options) as file:
            yield file
            file.flush()
            os.fsync(file.fileno())
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
