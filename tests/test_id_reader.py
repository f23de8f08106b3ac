"""ID reader: enter → stay → leave in order, the id read on entry and on leaving, the manifest's state."""
import csv

from .plant_watch import run_watched


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


SCENE = """
planthub: 1
run: {duration: 3.0, physics_rate: 150}
objects:
  belt: {module: conveyor, position: [0, 0, 0], length: 2.0, speed: 0.5}
  source: {module: source, position: [0.04, 0, 0], interval: 0.6,
           bottles: [{id: X7, destination: north}, {id: Y8, destination: south}]}
  reader: {module: id_reader, position: [1.0, 0, 0.05]}
record: [reader.trigger.on_enter, reader.trigger.on_stay, reader.trigger.on_leave, reader.trigger.object,
         reader.trigger.left, reader.trigger.destination, reader.trigger.filled]
"""


def test_events_in_order_enter_stay_leave_with_the_ids(write_scenario, tmp_path):
    _, _, watch = run_watched(write_scenario(SCENE), tmp_path)
    watch.assert_sound()
    data = rows(tmp_path / "recording.csv")
    marks = []
    for r in data:
        if r["reader.trigger.on_enter"] == "1":
            marks.append(("enter", r["reader.trigger.object"], r["reader.trigger.destination"]))
        elif r["reader.trigger.on_leave"] == "1":
            marks.append(("leave", r["reader.trigger.left"]))
        elif r["reader.trigger.on_stay"] == "1":
            if marks[-1] != ("stay",):
                marks.append(("stay",))
    assert marks == [("enter", "X7", "north"), ("stay",), ("leave", "X7"),
                     ("enter", "Y8", "south"), ("stay",), ("leave", "Y8")]
    events = [(e["slot"], e["detail"]) for e in rows(tmp_path / "events.csv") if e["slot"].startswith("reader")]
    assert events == [("reader.trigger.on_enter", "X7"), ("reader.trigger.on_leave", "X7"),
                      ("reader.trigger.on_enter", "Y8"), ("reader.trigger.on_leave", "Y8")]
    assert all(r["reader.trigger.filled"] == "0" for r in data)
