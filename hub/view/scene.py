"""The scene document (schemas/scene.schema.json): everything a view draws that does not move by
itself — the objects with their modules and slots, the geometry each one built, every body's
shape and id — made once, when the run starts.

JSON rather than glTF: what a view needs is what the parts *are* (a belt's centre line, a
switch's blade, a light barrier's volume, an arm's URDF and joint names, which object owns
what), so that it can colour, label, light up and operate them; glTF would carry triangles and
lose all of that, and the primitives (boxes, belt strips, cylinders) are a few lines to mesh.
"""
from __future__ import annotations

import json

from hub.bus.tls import common_name
from hub.core.errors import PlanthubError

FORMAT = "planthub-scene"
VERSION = 1


def scene_document(plant, run: str) -> dict:
    """The scene of a built plant (hub/run/plant.py) whose world has started."""
    world = plant.world
    scene, b = world.scene, world.bodies
    slots: dict[str, list] = {}
    for ref, index in plant.index.items():
        slot = plant.signals.slots[index]
        slots.setdefault(ref.obj, []).append([f"{ref.component}.{ref.slot}", slot.type.value, slot.direction.value])
    objects = {spec.name: {"module": spec.module_name, "slots": slots.get(spec.name, [])}
               for spec in plant.scenario.objects}
    bodies = [{"row": row, "id": b.labels[row], "object": scene.body_owners.get(row, ""),
               "radius": float(b.radii[row]), "height": 2.0 * float(b.half_heights[row])}
              for row in range(len(b.labels))]
    return {"format": FORMAT, "version": VERSION, "run": run, "physics_rate": world.rate,
            "access": access(plant.scenario.run.bus), "objects": objects, "items": scene.items, "bodies": bodies}


def access(settings) -> dict | None:
    """Who may do what on this run's bus (run.bus.access), for a view to tell its operator why its
    panel is off; None: no access control (any process that reaches the bus may command)."""
    if settings is None or settings.control is None:
        return None
    control = list(dict.fromkeys(settings.control))
    own = common_name(settings.tls.certificate) if settings.tls is not None and settings.tls.certificate else None
    if own:   # the hub's own, as the bus's rules add it
        control = list(dict.fromkeys([*control, own]))
    instructor = list(dict.fromkeys([*settings.instructor, *([own] if own else [])]))
    return {"control": control, "watch": list(dict.fromkeys(settings.watch)), "instructor": instructor}


def refusal(scene: dict, name: str | None) -> str | None:
    """Why a view whose certificate names `name` may not command this run (None: it may). An
    instructor may: its commands go on the instructor's key (hub/bus/commands.py)."""
    rules = scene.get("access")
    if not rules:
        return None
    if name is None:
        return ("the run's bus is under access control (run.bus.access) and this view shows no "
                "certificate: it may watch at most")
    if name in rules.get("control", []) or name in rules.get("instructor", []):
        return None
    allowed = ", ".join(rules.get("control", [])) or "nobody"
    return (f"this view's certificate names {name!r}, which may only watch this run "
            f"(run.bus.access.control: {allowed})")


def not_instructor(scene: dict, name: str | None) -> str | None:
    """Why a view whose certificate names `name` is not an instructor's of this run (None: it is —
    without access control, any view is, as any may command)."""
    rules = scene.get("access")
    if not rules:
        return None
    if name is None:
        return "the run's bus is under access control (run.bus.access) and this view shows no certificate"
    if name in rules.get("instructor", []):
        return None
    allowed = ", ".join(rules.get("instructor", [])) or "nobody"
    return f"this view's certificate names {name!r}, not an instructor (run.bus.access.instructor: {allowed})"


def scene_bytes(plant, run: str) -> bytes:
    """The document as it goes on the bus: compact UTF-8 JSON."""
    return json.dumps(scene_document(plant, run), separators=(",", ":"), allow_nan=False).encode("utf-8")


def read_scene(data: bytes, what: str, hint: str = "") -> dict:
    """A scene document read back (from the hub's answer, or a run folder's scene.json): the
    version this code draws, with a whole positive physics rate; else a PlanthubError naming `what`
    (`hint`: where such a document comes from)."""
    try:
        scene = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise PlanthubError(f"{what} is not JSON: {exc}") from None
    if not isinstance(scene, dict) or scene.get("format") != FORMAT:
        raise PlanthubError(f"{what} is not a {FORMAT} document{hint}")
    if scene.get("version") != VERSION:
        raise PlanthubError(f"{what} is version {scene.get('version')!r}; this view reads version {VERSION}")
    rate = scene.get("physics_rate")
    if not isinstance(rate, int) or isinstance(rate, bool) or rate <= 0:
        raise PlanthubError(f"{what}: physics_rate is {rate!r}, not a positive whole number of ticks per s")
    return scene
