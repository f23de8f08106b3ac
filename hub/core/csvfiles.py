"""Reading back the CSV files a run writes (recording.csv, events.csv): what makes one unreadable
said with its name, and a last line cut short — a hub killed while writing it — told apart from a
broken one. `planthub plot` and the view's playback read them through here."""
from __future__ import annotations

import csv
from contextlib import contextmanager
from pathlib import Path

from hub.core.errors import PlanthubError


@contextmanager
def reading(path: Path):
    """The file open for csv; an undecodable or unreadable file is a PlanthubError naming it."""
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            yield handle
    except (UnicodeDecodeError, csv.Error) as exc:
        raise PlanthubError(f"{path} is not a CSV file planthub wrote: {exc}") from None
    except OSError as exc:
        raise PlanthubError(f"cannot read {path}: {exc.strerror or exc}") from None


def body_rows(reader, path: Path, width: int, cut):
    """(line, row) of the rows after the header (line 1), each `width` columns. A last row cut short
    is left out and `cut(text)` told of it; a short row elsewhere is a PlanthubError with its line."""
    row, line = next(reader, None), 2
    while row is not None:
        following = next(reader, None)   # a short row is forgiven only as the last one
        if len(row) != width:
            if following is None:
                cut(f"{path}:{line}: the last line is cut short ({len(row)} of {width} columns)")
                return
            raise PlanthubError(f"{path}:{line}: {len(row)} columns, but its header names {width}")
        yield line, row
        row, line = following, line + 1
