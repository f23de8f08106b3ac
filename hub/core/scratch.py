"""The scratch folder: every temporary file of a planthub process lives in one folder named with its pid, removed at exit, and swept by the next run once that process is gone (a kill -9 runs no clean-up)."""
from __future__ import annotations

import atexit
import os
import re
import shutil
import tempfile
from pathlib import Path

#: Where a process the hub starts (a participant, `planthub serve-fmu`) finds the hub's folder, so
#: that what it leaves behind is swept with the hub's.
ENVIRONMENT = "PLANTHUB_SCRATCH"
_NAME = re.compile(r"^planthub-(\d+)-[a-z0-9_]{8}$")   # tempfile.mkdtemp(prefix="planthub-<pid>-")
_OWNER = "owner"   # in the folder: "<pid> <start time>", the start time as in /proc/<pid>/stat

_folder: Path | None = None
_owner: int | None = None   # the pid that made _folder and removes it at exit (None: it is another's)
_swept = False


def folder() -> Path:
    """This process's scratch folder, made on first use: the one a launching hub named in
    PLANTHUB_SCRATCH, or else a new `planthub-<pid>-<random>` in the system's temporary folder (the
    folders of planthub processes that are gone are swept first)."""
    global _folder, _owner
    if _folder is not None and _folder.is_dir():
        return _folder
    inherited = os.environ.get(ENVIRONMENT)
    if inherited and Path(inherited).is_dir():
        _folder, _owner = Path(inherited), None
        return _folder
    sweep()
    pid = os.getpid()
    made = Path(tempfile.mkdtemp(prefix=f"planthub-{pid}-"))
    (made / _OWNER).write_text(f"{pid} {_start_time(pid) or ''}\n")
    if _owner is None:
        atexit.register(remove)
    _folder, _owner = made, pid
    return made


def adopt(path: str | os.PathLike) -> None:
    """Work in another process's folder (an isolated FMU's worker in its hub's); it is that
    process's to remove."""
    global _folder, _owner
    _folder, _owner = Path(path), None


def remove() -> None:
    """Remove this process's own folder (at exit; also before the process ends by os._exit)."""
    global _folder, _owner
    if _folder is not None and _owner == os.getpid():
        shutil.rmtree(_folder, ignore_errors=True)
        _folder, _owner = None, None


def sweep(where: str | os.PathLike | None = None) -> list[Path]:
    """Remove the scratch folders (of this user, in `where`, default the system's temporary folder)
    whose process is gone: its pid is not alive, or is a later process's (another start time than
    the one the folder was made with). Once per process unless `where` is given; the removed folders."""
    global _swept
    if where is None:
        if _swept:
            return []
        _swept = True
    removed = []
    try:
        entries = list(Path(where or tempfile.gettempdir()).iterdir())
    except OSError:
        return removed
    for entry in entries:
        match = _NAME.match(entry.name)
        if match is None or int(match.group(1)) == os.getpid() or _folder is not None and entry == _folder:
            continue
        try:
            info = entry.lstat()
        except OSError:
            continue
        if not entry.is_dir() or entry.is_symlink() or info.st_uid != os.getuid():
            continue   # only real folders of this user: a shared /tmp holds others' too
        if _gone(int(match.group(1)), entry):
            shutil.rmtree(entry, ignore_errors=True)
            removed.append(entry)
    return removed


def _gone(pid: int, path: Path) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        pass   # alive, another user's: the start time tells whether it is the folder's process
    try:
        stamp = (path / _OWNER).read_text().split()
    except OSError:
        return False   # being made right now (the owner file follows the folder), or unreadable: kept
    started = _start_time(pid)
    return len(stamp) == 2 and started is not None and stamp[1] != started


def _start_time(pid: int) -> str | None:
    """When the process started, in clock ticks since boot (field 22 of /proc/<pid>/stat); None
    where there is no /proc."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    # The command name (field 2) is in parentheses and may hold spaces and parentheses itself.
    return text.rsplit(")", 1)[1].split()[19]
