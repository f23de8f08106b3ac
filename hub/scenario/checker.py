"""Loads a scenario file and checks all of it before anything is built; every problem is reported at once."""
from __future__ import annotations

import json
import math
import re
from dataclasses import replace
from pathlib import Path

import jsonschema

from hub.bus.settings import BusSettings
from hub.bus.tls import TlsSettings
from hub.bus.tls import problems as tls_problems
from hub.core import flowgraph
from hub.core.errors import Problem, ScenarioError
from hub.core.flow import Condition, Mode
from hub.core.logic_spec import OPTIONS as LOGIC_OPTIONS
from hub.core.logic_spec import fmu_parameters
from hub.core.module import Module
from hub.core.registry import Registry, UnknownModule, default_registry, did_you_mean
from hub.core.resources import SCHEMAS
from hub.core.slots import Direction, Slot, SlotRef, SlotType
from hub.scenario.exercise import check_exercise
from hub.scenario.expectations import Expectation, NoJam
from hub.scenario.extends import read_document
from hub.scenario.faults import check_faults
from hub.scenario.model import FlowSpec, ObjectSpec, RunSettings, Scenario, is_plant  # noqa: F401 (re-exported)
from hub.scenario.yamlsource import Lines, format_path, line_of

_SLOT_REF = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*){1,2}$")


def _is_ref(value) -> bool:
    return isinstance(value, str) and bool(_SLOT_REF.match(value))


def _dict(value) -> dict:
    return value if isinstance(value, dict) else {}


def _list(value) -> list:
    return value if isinstance(value, list) else []


def load_scenario(path, overrides: dict | None = None, registry: Registry | None = None, *,
                  blame: bool = True) -> Scenario:
    """Read, override (dotted keys, e.g. {"run.physics_rate": 1000}), check and return a scenario.
    `blame`: problems of an overridden value are placed at `--set`; a caller that places them
    itself (a campaign, at its own lines) reads them at the file's lines they replaced."""
    path = Path(path)
    document, problems = read_document(path)
    if document is None:
        raise ScenarioError(problems)
    data, lines = document.data, document.lines
    problems += _apply_overrides(data, overrides or {}, str(path))
    problems += _unfit_numbers(data, (), lines, document.file_at)
    checker = _Checker(path, data, lines, registry or default_registry(), document.file_at)
    # A value given with --set is blamed on --set, not on the line of the file it replaced.
    checker.overridden = set(overrides or {}) if blame else set()
    checker.problems[:0] = [checker.blamed(p) for p in problems]
    # A value already reported (not finite, an unknown tag) is not judged again by the schema.
    checker.settled = {p.path for p in problems if p.path}
    return checker.check()


#: The largest magnitude of a scenario's numbers: the integers a double holds exactly. Beyond it
#: an integer loses digits as a float, and products of such numbers (ticks from seconds, a step's
#: ticks) overflow to infinity, where the checker would fail converting them back.
LARGEST = 2 ** 53


def _unfit_numbers(node, path: tuple, lines: Lines, file_at) -> list[Problem]:
    """Every NaN, infinity or number beyond ±LARGEST in the document, reported at its place and
    replaced by None: no number of a scenario may be non-finite (JSON Schema's `number` would
    take them) or out of that range."""
    found = []
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in list(items):
        message = None
        if isinstance(value, float) and not math.isfinite(value):
            message = f"{value!r} is not a finite number"
        elif isinstance(value, (int, float)) and not isinstance(value, bool) and abs(value) > LARGEST:
            message = f"{value!r} is out of range: a scenario's numbers stay within ±2**53 (about 9.0e15)"
        if message is not None:
            found.append(Problem(file_at(path + (key,)), line_of(lines, path + (key,)), format_path(path + (key,)),
                                 message))
            node[key] = None
        elif isinstance(value, (dict, list)):
            found += _unfit_numbers(value, path + (key,), lines, file_at)
    return found


def _apply_overrides(data, overrides: dict, file: str) -> list[Problem]:
    problems = []
    for key, value in overrides.items():
        parts = key.split(".")
        node = data
        for part in parts[:-1]:
            if not isinstance(node, dict):
                break
            node = node.setdefault(part, {})
        if not isinstance(node, dict):
            problems.append(Problem(file, None, key, "override does not name a mapping entry"))
        else:
            node[parts[-1]] = value
    return problems


def _resolve_paths(params: dict, schema: dict, base: Path) -> dict:
    """Parameters marked `"x-path": true` in a module's schema are relative to the scenario file."""
    out = dict(params)
    for key, prop in schema.get("properties", {}).items():
        if prop.get("x-path") and isinstance(out.get(key), str):
            out[key] = str((base / out[key]).resolve())
        elif "properties" in prop and isinstance(out.get(key), dict):   # a section: `tls: {certificate, key}`
            out[key] = _resolve_paths(out[key], prop, base)
    return out


def _bus_settings(bus: dict, base: Path) -> BusSettings:
    """The `run.bus` section (already checked by the schema) with defaults filled in; the TLS
    files are relative to the scenario's folder."""
    d = BusSettings()

    def get(key, kind, section=bus, default=d):   # a bad value is already reported by the schema
        value = section.get(key)
        ok = isinstance(value, kind) and not (isinstance(value, bool) and kind is not bool)
        return value if ok else getattr(default, key)

    strings = lambda key: tuple(x for x in get(key, (list, tuple)) if isinstance(x, str))
    tls = None
    if isinstance(bus.get("tls"), dict):
        section, t = bus["tls"], TlsSettings()
        path = lambda key: str((base / section[key]).resolve()) if isinstance(section.get(key), str) else None
        tls = TlsSettings(path("ca"), path("certificate"), path("key"), get("mutual", bool, section, t),
                          get("verify_name", bool, section, t))
    access = bus.get("access")
    control = None
    if isinstance(access, dict) and isinstance(access.get("control"), list):
        control = tuple(x for x in access["control"] if isinstance(x, str))
    watch = tuple(x for x in access.get("watch", ()) if isinstance(x, str)) if isinstance(access, dict) else ()
    instructor = tuple(x for x in access.get("instructor", ()) if isinstance(x, str)) if isinstance(access, dict) \
        else ()
    return BusSettings(get("mode", str), strings("listen"), strings("connect"), get("scouting", bool),
                       float(get("lease", (int, float))), get("on_loss", str),
                       float(get("publish_period", (int, float))), strings("expose"), tls=tls,
                       control=control, publish=get("publish", str), watch=watch,
                       instructor=instructor)


def _replaced(schema: dict, key: str, value) -> str | None:
    """What to write instead of a key the schema no longer takes (its `x-replaced`: key → its
    value as written in YAML → the replacement; "*" for any value), or None for a key it never had."""
    instead = schema.get("x-replaced", {}).get(key)
    if instead is None:
        return None
    written = value if isinstance(value, str) else json.dumps(value)
    return f"{key} is gone: write `{instead.get(written, instead.get('*'))}` instead"


def _scenario_schema() -> dict:
    return json.loads((SCHEMAS / "scenario.schema.json").read_text())


class _Checker:
    """Collects every problem of one scenario, each with file, line and path."""

    def __init__(self, path: Path, data, lines: Lines, registry: Registry, file_at=None):
        self.file = str(path)
        # The file each value was written in: a scenario that extends another holds the base's too.
        self.file_at = file_at or (lambda _path: self.file)
        self.path = path
        self.data = data
        self.lines = lines
        self.registry = registry
        self.problems: list[Problem] = []
        self.broken: set[str] = set()
        self.settled: set[str] = set()     # paths already reported while reading: not judged again
        self.rejected: list[tuple] = []    # paths the schema rejected: the meaning checks skip them
        self.overridden: set[str] = set()  # dotted keys given with --set

    def problem(self, path: tuple, message: str) -> None:
        where = format_path(path)
        if any(where == s or where.startswith((s + ".", s + "[")) for s in self.settled):
            return
        self.problems.append(self.blamed(Problem(self.file_at(path), line_of(self.lines, path), where, message)))

    def blamed(self, problem: Problem) -> Problem:
        """A problem at or under a value given with --set, placed there rather than in the file."""
        where = problem.path
        if any(where == key or where.startswith((key + ".", key + "[")) for key in self.overridden):
            return replace(problem, file="--set", line=None)
        return problem

    def intact(self, path: tuple) -> bool:
        """Whether the schema found nothing wrong at or below `path`."""
        return not any(r[:len(path)] == path for r in self.rejected)

    def check(self) -> Scenario:
        """Check shape (JSON Schema) and meaning together, so one run reports every problem.

        Parts the schema already rejected are skipped by the meaning checks, not judged twice.
        """
        self.validate(self.data, _scenario_schema(), ())
        if not isinstance(self.data, dict):
            raise ScenarioError(self.problems)
        return self.build()

    def validate(self, data, schema: dict, at: tuple) -> bool:
        """Report what `data` breaks of `schema`; whether it broke anything, a value already
        reported while reading (a NaN, now None) included."""
        validator = jsonschema.Draft202012Validator(schema)
        errors = sorted(validator.iter_errors(data), key=lambda e: [str(p) for p in e.absolute_path])
        for error in errors:
            where = at + tuple(error.absolute_path)
            self.rejected.append(where)
            if error.validator == "additionalProperties":
                known = error.schema.get("properties", {})
                for key in sorted(set(error.instance) - set(known)):
                    self.problem(where + (key,), _replaced(error.schema, key, error.instance[key])
                                 or f"unknown key {key!r}{did_you_mean(key, known)}")
            elif error.validator == "required":
                self.problem(where, error.message.replace("is a required property", "is missing"))
            else:
                self.problem(where, error.message)
        return bool(errors)

    # --- meaning --------------------------------------------------------------------------
    def build(self) -> Scenario:
        data = self.data
        run = self.run = self.run_settings(_dict(data.get("run")))
        objects, slot_tables = self.objects(_dict(data.get("objects")), self.defaults(_dict(data.get("defaults"))))
        self.orders(run, objects)
        # The logic's own wiring comes first, so a scenario's flows into the same slot win.
        flows = self.wiring(objects, slot_tables) + self.flows(_list(data.get("flows")), slot_tables)
        record = self.record(_list(data.get("record")), slot_tables)
        plant = is_plant(objects)
        expect = self.expectations(_list(data.get("expect")), slot_tables, run, plant)
        faults = check_faults(self, _list(data.get("faults")), slot_tables, run)
        exercise = check_exercise(self, data.get("exercise"), plant)
        order = self.order(flows, objects)
        if self.problems:
            raise ScenarioError(self.problems)
        return Scenario(self.path, data.get("name", self.path.stem), data.get("description", ""),
                        run, tuple(objects), tuple(flows), tuple(record), tuple(expect), order,
                        tuple(faults), exercise)

    def run_settings(self, run: dict) -> RunSettings:
        def setting(key, default, kind=(int, float)):
            value = run.get(key)
            ok = isinstance(value, kind) and not isinstance(value, bool) and value > 0
            return value if ok else default   # a bad value is already reported by the schema

        rate = setting("physics_rate", 150, int)
        step = setting("communication_step", None)
        substeps = 1
        if step is not None:
            exact = step * rate
            substeps = round(exact)
            if substeps < 1 or not math.isclose(exact, substeps, rel_tol=1e-9, abs_tol=1e-9):
                lo, hi = max(1, math.floor(exact)), max(1, math.ceil(exact))
                self.problem(("run", "communication_step"),
                             f"{step} s is not a whole number of physics ticks at {rate} Hz "
                             f"(nearest: {lo / rate:.6g} s = {lo} ticks, {hi / rate:.6g} s = {hi} ticks)")
                substeps = lo
        ticks = round(setting("duration", 10) * rate)
        end = max(1, math.ceil(ticks / substeps)) * substeps
        watch = run["watch"] if isinstance(run.get("watch"), dict) else {}   # bad values: the schema reports them
        return RunSettings(
            rate, substeps, end, setting("seed", 0, int),
            event_driven=run.get("event_driven") is True,
            master=run.get("master") if run.get("master") in ("jacobi", "gauss-seidel") else "jacobi",
            jam_after=float(setting("jam_after", 5.0)),
            sleep_after=float(run["sleep_after"]) if type(run.get("sleep_after")) in (int, float)
            and run["sleep_after"] >= 0 else 0.05,
            orders=setting("orders", None, int),
            bus=self.bus_settings(run["bus"]) if isinstance(run.get("bus"), dict) else None,
            max_speed=float(watch["max_speed"]) if type(watch.get("max_speed")) in (int, float)
            and watch["max_speed"] > 0 else None,
            on_violation=watch.get("on_violation") if watch.get("on_violation") in ("stop", "remove") else "stop",
            record_bodies=self.body_period(run.get("record_bodies"), rate, substeps),
            solver_iterations=setting("solver_iterations", None, int),
            integrator=run.get("integrator") if run.get("integrator") in ("exact", "explicit") else "exact")

    @staticmethod
    def body_period(value, rate: int, substeps: int) -> int:
        """`run.record_bodies` in ticks: true every point, a number of seconds rounded to points (at
        least one); 0 for false or a bad value (the schema reports it)."""
        if value is True:
            return substeps
        if type(value) in (int, float) and value > 0 and math.isfinite(value):
            return max(1, round(value * rate / substeps)) * substeps
        return 0

    def orders(self, run: RunSettings, objects) -> None:
        """`run.orders` needs sinks to deliver to, and no more orders than the sources put out."""
        if run.orders is None:
            return
        if not any(obj.module.TAKES_OUT for obj in objects):
            self.problem(("run", "orders"), f"{run.orders} orders, but no sink takes bottles out: "
                                            "add a `sink` object or leave out run.orders")
            return
        if self.problems:
            return   # a source with bad parameters cannot say what it holds; its problem is reported
        supply = sum(obj.module.supply(obj.name, obj.params, run.seed) for obj in objects)
        if run.orders > supply:
            self.problem(("run", "orders"), f"{run.orders} orders, but the sources put out only {supply} bottles")

    def bus_settings(self, section: dict) -> BusSettings:
        bus = _bus_settings(section, self.path.parent)
        for place, message in tls_problems(bus.tls, bus.listen, bus.connect, listening=bus.mode != "client",
                                           control=bus.control):
            self.problem(("run", "bus") + place, message)
        return bus

    def defaults(self, specs: dict) -> dict[str, dict]:
        """The `defaults` section: module name → parameters its objects get unless they set them."""
        out = {}
        for module, params in specs.items():
            if module not in self.registry:
                self.problem(("defaults", module), f"unknown module {module!r}{self.registry.suggest(module)}")
            elif isinstance(params, dict):
                out[module] = params
        return out

    def objects(self, specs: dict, defaults: dict[str, dict]):
        objects, tables, ids = [], {}, {}
        for name, spec in specs.items():
            at = ("objects", name)
            if not isinstance(spec, dict) or not isinstance(spec.get("module"), str):
                continue
            try:
                module = self.registry.get(spec["module"])
            except UnknownModule as exc:
                self.problem(at + ("module",), str(exc))
                continue
            own = {k: v for k, v in spec.items() if k not in ("module", "logic")}
            params = {**defaults.get(spec["module"], {}), **own}
            if self.validate(params, module.PARAMETERS, at):
                continue   # its meaning is not judged on parameters of the wrong shape
            params = _resolve_paths(module.with_defaults(params), module.PARAMETERS, self.path.parent)
            logic = self.logic(at, module, spec["module"], spec.get("logic"), params)
            if logic is None and spec.get("logic") is not None:
                continue
            found = module.check(params) or module.check_run(params, self.run)
            for where, message in found:
                self.problem(at + where, message)
            if found:
                continue
            if "id" in params:
                if params["id"] in ids:
                    self.problem(at + ("id",), f"duplicate id {params['id']!r} (also used by object {ids[params['id']]!r})")
                ids.setdefault(params["id"], name)
            if self.references(at, params, module.PARAMETERS, {o.name: o.module_name for o in objects},
                               failed=set(list(specs)[:list(specs).index(name)]) - set(tables)):
                continue
            logic_module = self.registry.get("fmu") if logic is not None else None
            objects.append(ObjectSpec(name, module, spec["module"], params, logic, logic_module))
            slots = dict(module.slots(params))
            if logic is not None:
                slots.update(logic_module.slots(logic))
            tables[name] = {(comp, s.name): s for comp, group in slots.items() for s in group}
            for member, groups in module.members(name, params).items():
                if member in specs or member in tables:
                    self.problem(at, f"object {name!r} makes {member!r}, a name object "
                                     f"{member!r} has already: rename one of them")
                    continue
                tables[member] = {(comp, s.name): s for comp, group in groups.items() for s in group}
        self.broken = set(specs) - set(tables)   # objects already reported: their slots are not judged
        return objects, tables

    def logic(self, at: tuple, module: type[Module], module_name: str, value, params: dict) -> dict | None:
        """The `fmu` parameters of the state logic attached with `logic:`, or None (problems noted)."""
        if value is None:
            return None
        if module.LOGIC is None:
            self.problem(at + ("logic",), f"module {module_name!r} has no state logic to attach")
            return None
        if value != "default" and not isinstance(value, dict):
            self.problem(at + ("logic",), f"expected `default` or a mapping of {', '.join(LOGIC_OPTIONS['properties'])}, "
                                          f"got {value!r}")
            return None
        if isinstance(value, dict) and self.validate(value, LOGIC_OPTIONS, at + ("logic",)):
            return None
        if value == "default" and not module.LOGIC.default_file.is_file():
            self.problem(at + ("logic",), f"the default logic of {module_name!r}, {module.LOGIC.default_file}, "
                                          f"is not built: run `make fmus`")
            return None
        fmu = self.registry.get("fmu")
        logic = fmu.with_defaults(fmu_parameters(module.LOGIC, value, self.path.parent, params))
        found = fmu.check(logic) or fmu.check_run(logic, self.run)
        for where, message in found:
            self.problem(at + ("logic",) + where, message)
        return None if found else logic

    def references(self, at: tuple, params: dict, schema: dict, before: dict[str, str], failed=()) -> bool:
        """Parameters marked `"x-object": [modules]` name an object of one of those modules declared
        earlier in the file (a belt placed `after` another); report any that does not. One that
        names an object already reported (`failed`) is not judged: its problem is that object's."""
        bad = False
        for key, prop in schema.get("properties", {}).items():
            kinds, name = prop.get("x-object"), params.get(key)
            if not kinds or not isinstance(name, str):
                continue
            if name in failed:
                bad = True   # built on a broken object: skipped, but not reported again
                continue
            if before.get(name) not in kinds:
                candidates = [n for n, m in before.items() if m in kinds]
                what = f"object {name!r} is a {before[name]}, not a {' or '.join(kinds)}" if name in before else \
                    f"no {' or '.join(kinds)} {name!r} is declared before this object"
                self.problem(at + (key,), what + did_you_mean(name, candidates))
                bad = True
        return bad

    def resolve(self, text: str, at: tuple, tables: dict, direction: Direction | None):
        """`obj.comp.slot` or `obj.slot` → (SlotRef, Slot), or None with a problem recorded."""
        parts = text.split(".")
        obj = parts[0]
        if obj not in tables:
            if obj not in self.broken:
                self.problem(at, f"unknown object {obj!r} in {text!r}{did_you_mean(obj, tables)}")
            return None
        table = tables[obj]
        if len(parts) == 3:
            key = (parts[1], parts[2])
            found = [key] if key in table else []
        else:
            found = [k for k in table if k[1] == parts[1]]
        if len(found) > 1:
            options = ", ".join(f"{obj}.{c}.{s}" for c, s in found)
            self.problem(at, f"{text!r} is ambiguous: name the component ({options})")
            return None
        if not found:
            asked = ".".join(parts[1:])
            names = [f"{c}.{s}" for c, s in table] + sorted({s for _, s in table})
            self.problem(at, f"object {obj!r} ({self.module_of(obj)}) has no slot {asked!r}{did_you_mean(asked, names)}")
            return None
        (comp, name), = found
        slot: Slot = table[(comp, name)]
        ref = SlotRef(obj, comp, name)
        if direction is not None and slot.direction is not direction:
            role = "read from" if direction is Direction.SOURCE else "written to"
            self.problem(at, f"{ref} is a {slot.direction.value} slot and cannot be {role} here")
            return None
        return ref, slot

    def module_of(self, obj: str) -> str:
        return self.data["objects"][obj]["module"]

    def wiring(self, objects: list[ObjectSpec], tables: dict) -> list[FlowSpec]:
        """The flows inside objects whose state logic is attached (LogicSpec.wiring)."""
        out = []
        for spec in objects:
            if spec.logic is None:
                continue
            at = ("objects", spec.name, "logic")
            for source, target in spec.module.LOGIC.wiring:
                src = self.resolve(f"{spec.name}.{source}", at, tables, Direction.SOURCE)
                tgt = self.resolve(f"{spec.name}.{target}", at, tables, Direction.TARGET)
                if src and tgt and src[1].type is not tgt[1].type:
                    self.problem(at, f"the logic's wiring does not fit: {src[0]} is {src[1].type.value} "
                                     f"but {tgt[0]} is {tgt[1].type.value}")
                elif src and tgt:
                    out.append(FlowSpec(src[0], tgt[0], src[1].type, Condition.SOURCE, Mode.CONTINUOUS,
                                        None, line_of(self.lines, at)))
        return out

    def flows(self, specs: list, tables: dict) -> list[FlowSpec]:
        out = []
        for i, spec in enumerate(specs):
            at = ("flows", i)
            if not (isinstance(spec, dict) and _is_ref(spec.get("from")) and _is_ref(spec.get("to"))):
                continue
            if spec.get("mode", "continuous") not in ("continuous", "singular") or \
                    spec.get("when", "source") not in ("source", "target", "both", "either"):
                continue
            src = self.resolve(spec["from"], at + ("from",), tables, Direction.SOURCE)
            tgt = self.resolve(spec["to"], at + ("to",), tables, Direction.TARGET)
            mode = Mode(spec.get("mode", "continuous"))
            rearm = None
            if _is_ref(spec.get("rearm")):
                r = self.resolve(spec["rearm"], at + ("rearm",), tables, Direction.SOURCE)
                if r and r[1].type is not SlotType.VOID:
                    self.problem(at + ("rearm",), f"re-arm slot {r[0]} must be void, not {r[1].type.value}")
                elif r and mode is not Mode.SINGULAR:
                    self.problem(at + ("rearm",), "only a singular flow can be re-armed (add mode: singular)")
                rearm = r[0] if r else None
            if src and tgt and src[1].type is not tgt[1].type:
                self.problem(at, f"type mismatch: {src[0]} is {src[1].type.value} but {tgt[0]} is {tgt[1].type.value}"
                                 f"{self.event_hint(src, tgt)}")
            elif src and tgt:
                out.append(FlowSpec(src[0], tgt[0], src[1].type, Condition(spec.get("when", "source")),
                                    mode, rearm, line_of(self.lines, at)))
        return out

    def event_hint(self, src: tuple, tgt: tuple) -> str:
        """How to join an event (void) and a Boolean, said after their type mismatch; "" for other pairs.

        An FMU's Boolean variable is a void slot once it is listed in the object's `events`; any other
        event becomes a value through a `constant` object fed by it."""
        if {src[1].type, tgt[1].type} != {SlotType.VOID, SlotType.BOOL}:
            return ""
        boolean = src if src[1].type is SlotType.BOOL else tgt
        obj = boolean[0].obj
        spec = self.data["objects"][obj]
        if spec.get("module") == "fmu":
            renamed = {slot: var for var, slot in (spec.get("map") or {}).items()}
            variable = renamed.get(boolean[0].slot, boolean[0].slot)
            return (f" (an FMU's Boolean is an event when listed in its `events:`: add {variable!r} to "
                    f"objects.{obj}.events)")
        if src[1].type is SlotType.VOID:
            return " (an event carries no value: a `constant` object's value.set turns it into one)"
        return ""

    def record(self, specs: list, tables: dict):
        out = []
        for i, text in enumerate(specs):
            if not _is_ref(text):
                continue
            r = self.resolve(text, ("record", i), tables, None)
            if r:
                out.append((r[0], r[1].type))
        return out

    def expectations(self, specs: list, tables: dict, run: RunSettings, plant: bool) -> list[Expectation | NoJam]:
        out = []
        for i, spec in enumerate(specs):
            at = ("expect", i)
            if not isinstance(spec, dict) or not self.intact(at):
                continue   # the schema's problem is reported; judging its meaning would only guess
            if "jams" in spec:
                others = sorted(set(spec) - {"name", "jams"})
                if others:
                    self.problem(at, f"`jams: none` stands alone (with a `name`), not with {', '.join(others)}")
                elif not plant:
                    self.problem(at + ("jams",), "jams are watched in a plant, a scenario with a source or a "
                                                 "sink; this one has neither")
                elif spec["jams"] == "none":
                    out.append(NoJam(spec.get("name") or "no jam", line_of(self.lines, at)))
                continue
            if "slot" not in spec:
                self.problem(at, "give `slot` (a slot's value, with `is` or `always`) or `jams: none`")
                continue
            if not _is_ref(spec.get("slot")):
                continue
            if ("is" in spec) == ("always" in spec):
                self.problem(at, "give exactly one of `is` (a value at a time) and `always` (at every point)")
                continue
            if "at" in spec and "always" in spec:
                self.problem(at + ("at",), "`at` goes with `is`; `always` is judged at every point")
                continue
            slot = self.resolve(spec["slot"], at + ("slot",), tables, None)
            when = self.resolve(spec["when"], at + ("when",), tables, Direction.SOURCE) if _is_ref(spec.get("when")) else None
            show = self.resolve(spec["show"], at + ("show",), tables, None) if _is_ref(spec.get("show")) else None
            if when and when[1].type is not SlotType.VOID:
                self.problem(at + ("when",), f"{when[0]} is {when[1].type.value}; `when` takes a void slot")
                continue
            if slot is None or (_is_ref(spec.get("when")) and when is None) or (_is_ref(spec.get("show")) and show is None):
                continue
            key = "is" if "is" in spec else "always"
            (op, raw), = spec[key].items()
            kind = slot[1].type
            try:
                value = (SlotType.BOOL if kind is SlotType.VOID else kind).coerce(raw)
            except ValueError as exc:
                self.problem(at + (key, op), f"{slot[0]} is {kind.value}: {exc}")
                continue
            tick = round(spec["at"] * run.physics_rate) if "at" in spec else None
            name = spec.get("name") or f"{spec['slot']} {op} {raw!r}"
            if "allow_empty" in spec and not (key == "always" and when):
                self.problem(at + ("allow_empty",), "`allow_empty` goes with `always` and `when`: only those can "
                                                    "go unjudged")
                continue
            out.append(Expectation(name, slot[0], kind, op, value, key == "always", tick,
                                   when[0] if when else None, show[0] if show else None, line_of(self.lines, at),
                                   spec.get("allow_empty") is True))
        return out

    def order(self, flows: list[FlowSpec], objects: list[ObjectSpec]):
        feed = []
        for spec in objects:
            for comp, pairs in spec.module.feedthrough(spec.params).items():
                key = f"{spec.name}.{comp}"
                feed.append(flowgraph.Feedthrough(
                    key, frozenset(f"{key}.{t}" for t, _ in pairs), frozenset(f"{key}.{s}" for _, s in pairs)))
        edges = [flowgraph.FlowEdge(str(f.source), str(f.target), str(f.rearm) if f.rearm else None) for f in flows]
        plan = flowgraph.plan(edges, feed)
        for loop in plan.loops:
            steps = "; ".join(f"line {flows[i].line}: {flows[i].source} → {flows[i].target}" for i in loop)
            self.problems.append(Problem(self.file, flows[loop[0]].line, "flows",
                                         f"flows form a zero-delay loop ({steps}); break it with a component that delays"))
        return plan.order
