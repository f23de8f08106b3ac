"""The body recording: every body's pose and the moving parts' state over a run, for playback
(`planthub view RUN_DIR`), in `bodies.arrows` beside the scene document `scene.json`.

An Arrow IPC stream (pyarrow), one row per recorded point and one column per field of the bodies
message (schemas/scene.schema.json `bodies_message`): `tick`, then list columns — `rows`
(uint16), `poses` (float32, 7 per row), `flags` (uint8), `destinations` (string), `parts`
(uint8), `moving` (float32), `triggers` (uint8), `arms` (float32). Columnar, so each field's
values lie together and compress (zstd) well; a stream, so the batches written before a kill -9
stay readable (a batch every BATCH points: by count, not by the clock, so that the same run gives
the same bytes; at the bottling plant's 4× real time that is every 0.1 s of wall time).
Why not CSV: 150 bottles × 7 numbers per point are 1050 columns, written as text; why not
Parquet: its footer is written at the end, and a run killed outright would leave nothing
readable. The figures of each choice: `make bench` (tests/bench_view.py).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.ipc as ipc

from hub.core.errors import PlanthubError
from hub.core.observer import BodyLook

NAME = "bodies.arrows"
SCENE = "scene.json"
BATCH = 25   # points per batch written

_LISTS = {"rows": pa.uint16(), "poses": pa.float32(), "flags": pa.uint8(), "destinations": pa.string(),
          "parts": pa.uint8(), "moving": pa.float32(), "triggers": pa.uint8(), "arms": pa.float32()}
_WIRE = {"rows": "<u2", "poses": "<f4", "flags": "u1", "parts": "u1", "moving": "<f4", "triggers": "u1", "arms": "<f4"}
SCHEMA = pa.schema([("tick", pa.int64()), *((name, pa.list_(kind)) for name, kind in _LISTS.items())])


class BodyRecorder:
    """An observer (hub/core/observer.py) that writes the bodies at every `every`-th tick into
    `directory/bodies.arrows`, and the scene document (bytes) into `directory/scene.json`."""

    def __init__(self, directory: Path, world, scene: bytes, *, every: int = 1, looks=()):
        self.world = world
        self.every = max(1, int(every))
        self.looks = [look for look in looks if isinstance(look, BodyLook)]
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        (self.directory / SCENE).write_bytes(scene)
        self._sink = pa.OSFile(str(self.directory / NAME), "wb")
        self._writer = ipc.new_stream(self._sink, SCHEMA, options=ipc.IpcWriteOptions(compression="zstd"))
        self._columns: dict[str, list] = {name: [] for name in ("tick", *_LISTS)}
        self.points = 0
        self._closed = False

    def observe(self, tick: int, signals=None, events=()) -> None:
        if tick % self.every:
            return
        state = self.world.scene_state()
        c = self._columns
        c["tick"].append(tick)
        c["rows"].append(state.rows)
        c["poses"].append(state.poses.reshape(-1))
        c["parts"].append(state.parts)
        c["moving"].append(state.moving)
        c["triggers"].append(state.triggers)
        c["arms"].append(state.arms.reshape(-1))
        looked = {}
        for look in self.looks:
            looked.update(look.look(state.rows.tolist()))
        c["flags"].append(np.frombuffer(looked.get("flags", bytes(len(state.rows))), np.uint8))
        c["destinations"].append(looked.get("destinations", [""] * len(state.rows)))
        self.points += 1
        if len(c["tick"]) >= BATCH:
            self.flush()

    def flush(self) -> None:
        """Write what was gathered as one batch and push it to the file."""
        c = self._columns
        if not c["tick"]:
            return
        arrays = [pa.array(c["tick"], pa.int64())]
        for name, kind in _LISTS.items():
            parts = c[name]
            offsets = np.zeros(len(parts) + 1, np.int32)
            np.cumsum([len(p) for p in parts], out=offsets[1:])
            if name == "destinations":
                values = pa.array([d for p in parts for d in p], pa.string())
            else:
                values = pa.array(np.concatenate(parts) if parts else np.zeros(0), kind)
            arrays.append(pa.ListArray.from_arrays(pa.array(offsets), values))
        self._writer.write_batch(pa.RecordBatch.from_arrays(arrays, schema=SCHEMA))
        self._sink.flush()
        self._columns = {name: [] for name in c}

    def close(self, reason: str = "") -> None:
        if self._closed:
            return
        self._closed = True
        try:
            self.flush()
            self._writer.close()
        finally:
            self._sink.close()


class BodyRecording:
    """A body recording read back (all of it in memory: 150 bottles over 150 s at 50 points per s
    are about 30 MB as arrays). `ticks` is sorted; `message(i)` gives point i as the bodies
    message (bytes fields little-endian), what a view draws."""

    def __init__(self, directory: Path):
        directory = Path(directory)
        path = directory / NAME
        if not path.is_file():
            raise PlanthubError(f"{directory}: no body recording ({NAME}); record one with "
                                f"`planthub run --record-bodies` or `run.record_bodies: true`")
        batches = []
        try:
            with pa.OSFile(str(path), "rb") as source:
                reader = ipc.open_stream(source)
                if reader.schema != SCHEMA:
                    raise PlanthubError(f"{path}: not a planthub body recording (its columns: {reader.schema.names})")
                while True:
                    try:
                        batches.append(reader.read_next_batch())
                    except StopIteration:
                        break
                    except (pa.ArrowInvalid, OSError):
                        break   # a run killed while writing: the batches before are whole
        except pa.ArrowInvalid as exc:
            raise PlanthubError(f"{path}: not an Arrow stream ({exc})") from None
        self.table = pa.Table.from_batches(batches, SCHEMA)
        self.ticks = np.asarray(self.table.column("tick").to_numpy(), np.int64)
        self._columns = {name: self.table.column(name).combine_chunks() if len(self.table) else None
                         for name in _LISTS}

    def __len__(self) -> int:
        return len(self.ticks)

    def index_at(self, tick: int) -> int:
        """The last recorded point at or before `tick` (the first if none is)."""
        return max(0, int(np.searchsorted(self.ticks, tick, side="right")) - 1)

    def message(self, i: int, rate: int) -> dict:
        tick = int(self.ticks[i])
        out = {"tick": tick, "time": tick / rate}
        for name in _LISTS:
            values = self._columns[name][i].values
            if name == "destinations":
                out[name] = values.to_pylist()
            else:
                out[name] = values.to_numpy(zero_copy_only=False).astype(_WIRE[name]).tobytes()
        return out
