"""The FMU adapter: every FMI call planthub makes goes through this file and, for model exchange, fmi_me.py (FMUs loaded with fmpy)."""
from __future__ import annotations

import ctypes
import functools
import itertools
import operator
import shutil
import tempfile
import time
import zipfile
from collections import deque
from dataclasses import dataclass
from math import copysign
from pathlib import Path
from xml.etree import ElementTree

import msgpack
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.fmi3 import FMU3Slave

from hub.core import scratch
from hub.core.errors import CheckpointError, PlanthubError, SimulationError
from hub.core.logic_spec import CO_SIMULATION, MODEL_EXCHANGE
from hub.core.slots import INT_RANGE, SlotType
from hub.logic.fmi_variables import FmuVariable, map_variables

# Where each FMI version keeps this platform's binary.
_PLATFORM = {"2.0": "linux64", "3.0": "x86_64-linux"}
_STATUS = ["ok", "warning", "discard", "error", "fatal", "pending"]
_LOG_LINES = 20


class FmuError(PlanthubError):
    """An FMU file cannot be used: the message names the file and the cause."""


@dataclass(frozen=True)
class FmuInterface:
    """What a scenario check needs of an FMU: its version, identity, its variables as slots
    (hub/logic/fmi_variables.py: array elements one each), what is not mapped, with the reason,
    and the interfaces it offers with a binary for this platform (co-simulation first)."""

    path: Path
    fmi_version: str
    model_name: str
    guid: str
    variables: dict[str, FmuVariable]
    variable_steps: bool       # canHandleVariableCommunicationStepSize (co-simulation)
    unmapped: tuple[tuple[str, str], ...] = ()   # (variable, why it has no slot)
    identifiers: tuple[tuple[str, str], ...] = ()   # (interface, modelIdentifier), preferred first
    states: int = 0            # continuous states (model exchange)
    event_indicators: int = 0  # model exchange
    completed_step: bool = False   # model exchange: needsCompletedIntegratorStep
    event_mode: bool = False   # FMI 3 co-simulation: hasEventMode (events handled by the importer)
    get_set_state: tuple[str, ...] = ()     # the interfaces declaring canGetAndSetFMUstate (FMI 3: …FMUState)
    serialize_state: tuple[str, ...] = ()   # the interfaces declaring canSerializeFMUstate (FMI 3: …FMUState)

    def of(self, causality: str) -> list[FmuVariable]:
        return [v for v in self.variables.values() if v.causality == causality]

    @property
    def interfaces(self) -> tuple[str, ...]:
        return tuple(kind for kind, _ in self.identifiers)

    @property
    def kind(self) -> str:
        """The interface planthub uses unless a scenario picks another: co-simulation where offered."""
        return self.identifiers[0][0]

    def identifier_of(self, kind: str) -> str:
        return dict(self.identifiers)[kind]

    def missing_state_flag(self, kind: str) -> str | None:
        """The capability flag the `kind` interface lacks for a checkpoint (FMU states got, set and
        turned into bytes), spelled as its FMI version spells it; None when it has both."""
        spelled = "FMUstate" if self.fmi_version == "2.0" else "FMUState"
        if kind not in self.get_set_state:
            return f"canGetAndSet{spelled}"
        if kind not in self.serialize_state:
            return f"canSerialize{spelled}"
        return None


def inspect_fmu(path: Path) -> FmuInterface:
    """Read an FMU's interface without loading its binary; FmuError says why it cannot be used.

    Each version of a file is read once: the scenario check, the slot table and the build of
    an object (and every object naming the same FMU) share the reading, keyed by the file's
    resolved path, modification time and size, so an FMU rebuilt between two loads is read again.
    """
    path = Path(path)
    if not path.is_file():
        raise FmuError(f"{path}: no such FMU file")
    stat = path.stat()
    key = (str(path.resolve()), stat.st_mtime_ns, stat.st_size)
    if key not in _INSPECTED:
        _INSPECTED[key] = _read_interface(path)
    return _INSPECTED[key]


_INSPECTED: dict[tuple[str, int, int], FmuInterface] = {}


def _read_interface(path: Path) -> FmuInterface:
    if not zipfile.is_zipfile(path):
        raise FmuError(f"{path}: not an FMU (an FMU is a zip archive)")
    with zipfile.ZipFile(path) as archive:
        names = set(archive.namelist())
        if "modelDescription.xml" not in names:
            raise FmuError(f"{path}: no modelDescription.xml in the archive")
        try:
            # The version decides which schema applies, so read it before fmpy validates.
            root = ElementTree.fromstring(archive.read("modelDescription.xml"))
        except ElementTree.ParseError as exc:
            raise FmuError(f"{path}: modelDescription.xml is not XML: {exc}") from None
    version = root.get("fmiVersion", "")
    if version not in _PLATFORM:
        raise FmuError(f"{path}: FMI {version or '(no fmiVersion)'} is not supported "
                       f"(planthub loads FMI 2.0 and 3.0 FMUs, co-simulation or model exchange)")
    try:
        md = read_model_description(str(path))
    except Exception as exc:  # fmpy reports schema and XML problems with several exception types
        raise FmuError(f"{path}: modelDescription.xml is not valid: {exc}") from None
    offered = [(kind, part) for kind, part in ((CO_SIMULATION, md.coSimulation), (MODEL_EXCHANGE, md.modelExchange))
               if part is not None]
    if not offered:
        if getattr(md, "scheduledExecution", None) is not None:
            raise FmuError(f"{path}: scheduled execution: not supported (the FMU offers neither co-simulation "
                           f"nor model exchange, only scheduled execution; planthub runs those two)")
        raise FmuError(f"{path}: the FMU offers no interface planthub runs (co-simulation or model exchange)")
    binaries = {kind: f"binaries/{_PLATFORM[version]}/{part.modelIdentifier}.so" for kind, part in offered}
    identifiers = tuple((kind, part.modelIdentifier) for kind, part in offered if binaries[kind] in names)
    if not identifiers:
        found = sorted({n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2})
        raise FmuError(f"{path}: no binary for this platform ({binaries[offered[0][0]]}); the FMU has: "
                       f"{', '.join(found) or 'none'}")
    # fmpy keeps no min/max of UInt types nor a Binary's maxSize: the XML's own attributes fill in.
    listed = root.find("ModelVariables")
    attributes = {}
    for element in (listed if listed is not None else ()):
        typed = element if version == "3.0" else next(iter(element), None)
        if element.get("name") is not None and typed is not None:
            attributes[element.get("name")] = dict(typed.attrib)
    variables, unmapped = map_variables(md.modelVariables, attributes, version == "2.0")
    cs, me = md.coSimulation, md.modelExchange
    return FmuInterface(path, version, md.modelName, md.guid, variables,
                        bool(cs and cs.canHandleVariableCommunicationStepSize), tuple(unmapped), identifiers,
                        states=md.numberOfContinuousStates if me else 0,
                        event_indicators=md.numberOfEventIndicators if me else 0,
                        completed_step=bool(me and me.needsCompletedIntegratorStep),
                        event_mode=bool(cs and version == "3.0" and getattr(cs, "hasEventMode", False)),
                        # fmpy reads both versions' flags into the FMI 2 spelling
                        get_set_state=tuple(k for k, part in offered if part.canGetAndSetFMUstate),
                        serialize_state=tuple(k for k, part in offered if part.canSerializeFMUstate))


def validate(path: Path) -> list[str]:
    """fmpy's own checks of an FMU (model description, structure, names): a list of problems."""
    from fmpy.validation import validate_fmu

    return [str(p).strip() for p in validate_fmu(str(path))]


def compare(fmu: FmuInterface, reference: FmuInterface) -> list[str]:
    """What `fmu` lacks to stand in for `reference`: inputs and outputs by name and slot type."""
    problems = []
    for causality in ("input", "output"):
        for want in reference.of(causality):
            have = fmu.variables.get(want.name)
            if have is None or have.causality != causality:
                problems.append(f"missing {causality} {want.name!r} ({want.type.value})")
            elif have.type is not want.type:
                problems.append(f"{causality} {want.name!r} is {have.type.value} here but {want.type.value} "
                                f"in {reference.path.name}")
    for name in sorted(n for n, v in reference.variables.items() if v.causality == "parameter"):
        if name not in fmu.variables:
            problems.append(f"no parameter {name!r} (a scenario setting it would be rejected)")
    return problems


class FmuSlave:
    """One running co-simulation instance in the hub's process: a logic slave (hub.core.slave).

    Inputs and outputs are set and read through pre-allocated ctypes arrays grouped by type,
    one FMI call per type and direction per step. Every call goes through `_call`, which turns
    a failing status into a SimulationError naming the instance, the function, the time and
    the FMU's own last log lines. An FMI 3 FMU with event mode (hasEventMode) is instantiated
    with it and with early return allowed: its events are handled in event mode as they come,
    and a step it returned early from is continued to the communication point.
    """

    on_bus = False
    KIND = CO_SIMULATION
    STEP = "doStep"   # what a failing step is called in messages
    _CLASSES = {"2.0": FMU2Slave, "3.0": FMU3Slave}
    #: early returns one communication step may take: past it the FMU is taken to be stuck at an event
    MAX_EVENTS = 10_000

    def __init__(self, interface: FmuInterface, instance: str, inputs: list[str], outputs: list[str],
                 parameters: dict, start_time: float = 0.0, step_timeout: float = 10.0):
        self.interface = interface
        self.instance = instance
        self.time = start_time
        self.step_timeout = step_timeout
        self.busy_since = None   # time.monotonic() while inside doStep: the watchdog's clock
        self.log: deque[str] = deque(maxlen=_LOG_LINES)
        self._dir = Path(tempfile.mkdtemp(prefix=f"fmu-{instance}-", dir=scratch.folder()))
        self._fmu = None
        try:
            if self.KIND not in interface.interfaces:
                raise SimulationError(self._failure(f"the FMU offers no {self.KIND} interface with a binary "
                                                    f"for this platform"))
            extract(str(interface.path), str(self._dir))
            # A binary that does not load (a missing symbol, another platform) is named like a failing call.
            self._fmu = self._call("load the binary", self._CLASSES[interface.fmi_version], guid=interface.guid,
                                   unzipDirectory=str(self._dir), modelIdentifier=interface.identifier_of(self.KIND),
                                   instanceName=instance)
            self._v2 = interface.fmi_version == "2.0"
            self._instantiate()
            self._in = _Batches(self._fmu, self._v2, [interface.variables[n] for n in inputs])
            self._written = None   # the inputs last set, while the FMU holds them
            # Reals compare equal at 0.0 and −0.0, which an FMU may tell apart: their signs are compared too.
            self._reals = tuple(k for k, n in enumerate(inputs) if interface.variables[n].type is SlotType.REAL)
            self._out = _Batches(self._fmu, self._v2, [interface.variables[n] for n in outputs])
            parameters = _whole_arrays(interface, parameters)
            params = _Batches(self._fmu, self._v2, [interface.variables[n] for n in parameters])
            # Set once instantiated, before initialisation: where FMI 2 and 3 let a user set every
            # variable with initial exact or approx (hub/logic/fmi_variables.py FmuVariable.settable).
            if self._v2:
                self._call("setupExperiment", self._fmu.setupExperiment, startTime=start_time)
            self._call("set parameters", params.set, list(parameters.values()))
            if self._v2:
                self._call("enterInitializationMode", self._fmu.enterInitializationMode)
            else:
                self._call("enterInitializationMode", self._fmu.enterInitializationMode, startTime=start_time)
            self._call("exitInitializationMode", self._fmu.exitInitializationMode)
            self._begin()
        except BaseException:
            self.close()
            raise

    def _begin(self) -> None:
        """After initialisation: ready to step."""
        if self._v2:
            self._raw_do_step, self._do_step = _raw(self._fmu, "fmi2DoStep"), self._do_step_2
            return
        self._raw_do_step, self._do_step = _raw(self._fmu, "fmi3DoStep"), self._do_step_3
        # eventHandlingNeeded, terminateSimulation, earlyReturn, lastSuccessfulTime
        self._flags = tuple(c() for c in (ctypes.c_bool, ctypes.c_bool, ctypes.c_bool, ctypes.c_double))
        self._step_results = tuple(ctypes.byref(c) for c in self._flags)
        if self.interface.event_mode:   # exitInitializationMode left it in event mode
            self.update_discrete_states()
            self._call("enterStepMode", self._fmu.enterStepMode)

    def _instantiate(self) -> None:
        if self._v2:
            # The FMI 2 logger is variadic; fmpy's native proxy formats the message for us.
            from fmpy.logging import addLoggerProxy

            callbacks = fmi2CallbackFunctions()
            callbacks.logger = _fmi2_logger
            callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_libc.calloc)
            callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_libc.free)
            # fmpy's proxy keeps one Python logger for the whole process, so the messages are
            # routed back to their instance through the component environment pointer.
            self._env = next(_environments)
            _fmi2_slaves[self._env] = self
            callbacks.componentEnvironment = self._env
            addLoggerProxy(ctypes.byref(callbacks))
            self._callbacks = callbacks   # kept alive as long as the instance
            self._call("instantiate", self._fmu.instantiate, callbacks=callbacks, loggingOn=False)
        else:
            self._call("instantiate", self._fmu.instantiate, loggingOn=False, **self._instantiate_options(),
                       logMessage=lambda env, status, category, message: self._logged(status, category, message))

    def _instantiate_options(self) -> dict:
        event_mode = self.interface.event_mode
        return {"eventModeUsed": event_mode, "earlyReturnAllowed": event_mode}

    def update_discrete_states(self) -> tuple[bool, float]:
        """Event mode's fixed-point iteration (FMI 2 newDiscreteStates, FMI 3 updateDiscreteStates):
        (next time event defined, its time). An FMU asking to terminate, or not settling, stops the run."""
        update = self._fmu.newDiscreteStates if self._v2 else self._fmu.updateDiscreteStates
        for _ in range(_MAX_ITERATIONS):
            more, terminate, _, _, timed, next_time = self._call("updateDiscreteStates", update)
            if terminate:
                raise SimulationError(self._failure("the FMU asked to terminate the simulation (event update)"))
            if not more:
                return bool(timed), next_time
        raise SimulationError(self._failure(f"its discrete states did not settle in {_MAX_ITERATIONS} event "
                                            f"iterations"))

    def _logged(self, status, category, message) -> None:
        label = _STATUS[status] if 0 <= status < len(_STATUS) else str(status)
        text = (message or b"").decode("utf-8", "replace")
        self.log.append(f"[{label}] {(category or b'').decode('utf-8', 'replace')}: {text}")

    def _call(self, function: str, fn, *args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except SimulationError:
            raise   # already named (a step's own event handling)
        except Exception as exc:
            raise self._named(function, exc) from None

    def _named(self, function: str, exc: Exception) -> SimulationError:
        """What `_call` raises for a call that failed with `exc`."""
        if isinstance(exc, FMICallException):
            status = _STATUS[exc.status] if 0 <= exc.status < len(_STATUS) else str(exc.status)
            return SimulationError(self._failure(f"{exc.function} returned {status}"))
        return SimulationError(self._failure(f"{function} failed: {exc}"))

    def _failure(self, what: str) -> str:
        where = f"FMU instance {self.instance!r} ({self.interface.path.name}) at t = {self.time:.9g} s: {what}"
        if self.log:
            where += "\n  FMU log:\n" + "\n".join(f"    {line}" for line in self.log)
        return where

    # The three calls of every point have `_call` written out: a Python call less each, per FMU.
    def set_inputs(self, values: list) -> None:
        """Set the inputs of a step. An FMU holds its inputs until they are set again (FMI 2.0
        and 3.0 alike), so the same values as last time, bit for bit, are not written again: at
        most points of a plant (97 % in the bottling plant) nothing an FMU reads has changed."""
        if held(values, self._written, self._reals):
            return
        self._written = None   # a write that fails part way leaves the FMU's inputs unknown
        try:
            self._in.set(values)
        except SimulationError:
            raise
        except Exception as exc:
            raise self._named("set inputs", exc) from None
        self._written = list(values)

    def outputs(self) -> list:
        try:
            return self._out.get()
        except SimulationError:
            raise
        except Exception as exc:
            raise self._named("get outputs", exc) from None

    def step(self, t: float, h: float) -> None:
        self.time = t
        self.busy_since = time.monotonic()
        try:
            self._do_step(t, h)
        except SimulationError:
            raise
        except Exception as exc:
            raise self._named(self.STEP, exc) from None
        finally:
            self.busy_since = None
        self.time = t + h

    def _do_step_2(self, t: float, h: float) -> None:
        status = self._raw_do_step(self._fmu.component, t, h, 1)
        if status > 1:
            _check("fmi2DoStep", status)

    def _do_step_3(self, t: float, h: float) -> None:
        end = t + h
        for _ in range(self.MAX_EVENTS):
            _check("fmi3DoStep", self._raw_do_step(self._fmu.component, t, h, True, *self._step_results))
            events, terminate, early, reached = (f.value for f in self._flags)
            if terminate:
                raise SimulationError(self._failure(f"the FMU asked to terminate the simulation (doStep from "
                                                    f"{t:.9g} s)"))
            if events and self.interface.event_mode:
                self.time = reached if early else end
                self._call("enterEventMode", self._fmu.enterEventMode)
                self.update_discrete_states()
                self._call("enterStepMode", self._fmu.enterStepMode)
            if not early or reached >= end:
                return
            t, h = reached, end - reached   # returned early at an event: on to the communication point
        raise SimulationError(self._failure(f"returned early more than {self.MAX_EVENTS} times in one step"))

    # --- checkpoints (hub.core.slave): FMI's own FMU state, in bytes, beside what this side holds
    def save(self) -> bytes:
        """The FMU's serialized FMU state with the time and the inputs it holds (so that a restored
        slave skips the same writes this one would), packed with msgpack under `_STATE_FORMAT`."""
        self._checkpoint_capable("save")
        return msgpack.packb({"format": _STATE_FORMAT, "guid": self.interface.guid, "kind": self.KIND,
                              "time": self.time, "inputs": self._written, "fmu": self._fmu_state(),
                              "own": self._save_own()}, use_bin_type=True)

    def restore(self, state: bytes) -> None:
        """Put back what `save` gave, in this instance or another made the same way: the FMU's state
        set from its bytes (the FMU checks them: its model, size, magic), then this side's."""
        self._checkpoint_capable("restore")
        saved = self._read_state(state)
        self._written = None   # until the FMU holds the saved inputs: a failed restore leaves them unknown
        self._restore_own(saved["own"])   # checked before the FMU is touched
        self._set_fmu_state(saved["fmu"])
        self.time = saved["time"]
        self._written = saved["inputs"]

    def _save_own(self):
        """What a subclass holds beside the FMU (msgpack data)."""
        return None

    def _restore_own(self, own) -> None:
        pass

    def _checkpoint_capable(self, what: str) -> None:
        flag = self.interface.missing_state_flag(self.KIND)
        if flag is not None:
            raise CheckpointError(f"FMU instance {self.instance!r} ({self.interface.path}): cannot {what} its state: "
                                  f"its modelDescription.xml does not declare {flag}=\"true\" for {self.KIND}, so "
                                  f"it cannot be checkpointed")
        if self._fmu is None:
            raise CheckpointError(f"FMU instance {self.instance!r} ({self.interface.path.name}): cannot {what} its "
                                  f"state: it is closed")

    def _checkpoint(self, function: str, fn, *args):
        """`_call`, its failure a CheckpointError (the same message: instance, function, FMU log)."""
        try:
            return self._call(function, fn, *args)
        except SimulationError as exc:
            raise CheckpointError(str(exc)) from None

    def _fmu_state(self) -> bytes:
        fmu = self._fmu
        state = self._checkpoint("getFMUState", fmu.getFMUState)
        try:
            return self._checkpoint("serializeFMUState", fmu.serializeFMUState, state)
        finally:
            self._checkpoint("freeFMUState", fmu.freeFMUState, state)

    def _set_fmu_state(self, data: bytes) -> None:
        fmu = self._fmu
        state = self._checkpoint("deserializeFMUState", fmu.deserializeFMUState, data)
        try:
            self._checkpoint("setFMUState", fmu.setFMUState, state)
        finally:
            self._checkpoint("freeFMUState", fmu.freeFMUState, state)

    def _read_state(self, data) -> dict:
        """The fields of bytes `save` made for an instance of this FMU; CheckpointError naming the
        instance and what does not fit."""
        where = f"FMU instance {self.instance!r} ({self.interface.path.name})"
        try:
            saved = msgpack.unpackb(data, raw=False, strict_map_key=True) \
                if isinstance(data, (bytes, bytearray)) else None
        except Exception as exc:   # msgpack raises several types for bytes that are not its own
            raise CheckpointError(f"{where}: the saved state cannot be read ({type(exc).__name__}: {exc})") from None
        if not (isinstance(saved, dict) and saved.get("format") == _STATE_FORMAT):
            raise CheckpointError(f"{where}: the saved state is not an FMU slave's ({_STATE_FORMAT})")
        if saved.get("guid") != self.interface.guid or saved.get("kind") != self.KIND:
            raise CheckpointError(f"{where}: the saved state is of another FMU (guid {saved.get('guid')}, "
                                  f"{saved.get('kind')}), not of this one (guid {self.interface.guid}, {self.KIND})")
        inputs, time_ = saved.get("inputs"), saved.get("time")
        if not (inputs is None or (isinstance(inputs, list) and len(inputs) == self._in.count)):
            raise CheckpointError(f"{where}: the saved state holds {len(inputs) if isinstance(inputs, list) else 'no'}"
                                  f" inputs, this instance has {self._in.count}")
        if not isinstance(time_, (int, float)) or not isinstance(saved.get("fmu"), bytes):
            raise CheckpointError(f"{where}: the saved state holds no time or no FMU state")
        return saved

    def close(self) -> None:
        fmu, self._fmu = self._fmu, None
        if fmu is not None and getattr(fmu, "component", None):
            try:
                fmu.terminate()
            except Exception:
                pass   # closing after an error: the instance may refuse; freeing still matters
            fmu.freeInstance()
        _fmi2_slaves.pop(getattr(self, "_env", None), None)
        shutil.rmtree(self._dir, ignore_errors=True)


#: names the layout of `FmuSlave.save`'s bytes; a later layout gets another
_STATE_FORMAT = "planthub.fmu-slave/1"


def _route_fmi2_log(env, name, status, category, message) -> None:
    slave = _fmi2_slaves.get(env)
    if slave is not None:
        slave._logged(status, category, message)


#: event iterations one event may take before the FMU is taken to chatter
_MAX_ITERATIONS = 100
_fmi2_slaves: dict[int, FmuSlave] = {}
_environments = itertools.count(1)
_fmi2_logger = fmi2CallbackLoggerTYPE(_route_fmi2_log)
_libc = ctypes.CDLL(None)
_libc.calloc.restype = ctypes.c_void_p
_libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
_libc.free.argtypes = [ctypes.c_void_p]


def _whole_arrays(interface: FmuInterface, parameters: dict) -> dict:
    """FMI 3 writes an array whole: elements a scenario leaves out keep their start values."""
    out = dict(parameters)
    for name in parameters:
        array = interface.variables[name].array
        if array:
            for element in interface.variables.values():
                if element.array == array:
                    out.setdefault(element.name, element.start)
    return out


class _Batches:
    """Variables grouped by FMI type, each group with ready value-reference and value arrays.

    An FMI 3 array is one value reference with many values: its elements sit side by side in
    the group's value array, in FMI's row-major order. Integers and Float32s are checked against
    their range before they are written; a Binary travels as hex.
    """

    def __init__(self, fmu, v2: bool, variables: list[FmuVariable]):
        self.fmu = fmu
        self.count = len(variables)
        self.variables = variables
        self.groups = []
        families = _FAMILY2 if v2 else _FAMILY3
        for fmi_type in dict.fromkeys(v.fmi_type for v in variables):
            members = [i for i, v in enumerate(variables) if v.fmi_type == fmi_type]
            family, ctype = families[fmi_type]
            sizes = dict.fromkeys(variables[i].vr for i in members)
            start = 0
            for vr in sizes:
                size = next(variables[i].size for i in members if variables[i].vr == vr)
                sizes[vr], start = start, start + size
            positions = [sizes[variables[i].vr] + variables[i].element for i in members]
            vrs = (ctypes.c_uint32 * len(sizes))(*sizes)
            values = (ctype * start)()
            prefix = "fmi2" if v2 else "fmi3"
            get, set_ = f"{prefix}Get{family}", f"{prefix}Set{family}"
            kind = variables[members[0]].type
            # A C integer or float would wrap or overflow to inf silently; a Binary is decoded from hex.
            check_writes = kind is SlotType.INT or fmi_type in ("Binary", "Float32")
            binary = (ctypes.c_size_t * start)() if fmi_type == "Binary" else None
            check_reads = fmi_type == "UInt64"   # the one type that holds more than an int slot's 64 signed bits
            self.groups.append((members, positions, kind, check_writes, check_reads, binary, vrs, values, start,
                                get, _raw(fmu, get), set_, _raw(fmu, set_)))
        self._v2 = v2
        # Read, a group's values leave its C array in one slice and reach the variables' order
        # through one itemgetter: a Python call per value cost more than the FMI calls themselves.
        self._reads = tuple((_pick(positions, n), _convert(kind, type(buf)._type_), members if check_reads else None,
                             binary, vrs, buf, n, get, getter)
                            for members, positions, kind, _, check_reads, binary, vrs, buf, n, get, getter, _, _
                            in self.groups)
        # Written, a group that fills its C array in order takes its values in one slice.
        self._whole = tuple(_pick(members, self.count) if positions == list(range(n)) and kind is not SlotType.STRING
                            and binary is None else None
                            for members, positions, kind, _, _, binary, _, _, n, *_ in self.groups)
        gathered = [i for members, *_ in self.groups for i in members]   # the variable of each value read
        where = {i: k for k, i in enumerate(gathered)}
        self._order = _pick([where[i] for i in range(self.count)], len(gathered))

    def set(self, values: list) -> None:
        component = self.fmu.component
        for (members, positions, kind, check_writes, _, binary, vrs, buf, n, _, _, name, setter), whole \
                in zip(self.groups, self._whole):
            if check_writes:
                for i in members:
                    try:
                        self.variables[i].check(values[i])
                    except ValueError as exc:
                        v = self.variables[i]
                        raise ValueError(f"{v.causality} {v.name!r} ({v.fmi_type}): {exc}") from None
            if binary is not None:
                keep = [bytes.fromhex(values[i]) for i in members]   # alive until the call returns
                for k, data in zip(positions, keep):
                    buf[k] = ctypes.cast(ctypes.c_char_p(data), ctypes.POINTER(ctypes.c_uint8))
                    binary[k] = len(data)
                _check(name, setter(component, vrs, len(vrs), binary, buf, n))
                continue
            if whole is not None:
                buf[:] = whole(values)
            else:
                for k, i in zip(positions, members):
                    buf[k] = _to_c(kind, values[i])
            if self._v2:
                status = setter(component, vrs, len(vrs), buf)
            else:   # FMI 3 getters and setters also take the number of values (arrays may differ)
                status = setter(component, vrs, len(vrs), buf, n)
            if status > 1:
                _check(name, status)

    def get(self) -> list:
        gathered = []
        component = self.fmu.component
        for pick, convert, unsigned, binary, vrs, buf, n, name, getter in self._reads:
            if binary is not None:
                _check(name, getter(component, vrs, len(vrs), binary, buf, n))
                gathered += [ctypes.string_at(buf[k], binary[k]).hex() if buf[k] else "" for k in pick(range(n))]
                continue
            status = getter(component, vrs, len(vrs), buf) if self._v2 else getter(component, vrs, len(vrs), buf, n)
            if status > 1:
                _check(name, status)
            values = pick(buf[:])
            if convert is not None:
                values = list(map(convert, values))
            if unsigned is not None:
                self._check_range(unsigned, values)
            gathered += values
        return self._order(gathered)

    def _check_range(self, members: list[int], values: list) -> None:
        """A UInt64 holds more than an int slot's 64 signed bits: past them the run stops."""
        for i, value in zip(members, values):
            if value > INT_RANGE[1]:
                v = self.variables[i]
                raise ValueError(f"{v.causality} {v.name!r} ({v.fmi_type}) is {value}, above "
                                 f"{INT_RANGE[1]}, the largest value an int slot carries")


def held(values: list, last: list | None, reals: tuple[int, ...]) -> bool:
    """Whether `values` are the inputs `last` written, bit for bit: equal, and the reals at
    positions `reals` of the same sign (0.0 == −0.0, which an FMU may tell apart)."""
    if last is None or values != last:
        return False
    return not reals or all(copysign(1.0, values[k]) == copysign(1.0, last[k]) for k in reals)


def _pick(positions: list[int], size: int):
    """A function taking the values at `positions` of a list of `size`, as a list."""
    if positions == list(range(size)):
        return list
    if len(positions) == 1:
        k = positions[0]
        return lambda values: [values[k]]
    if not positions:
        return lambda values: []
    take = operator.itemgetter(*positions)
    return lambda values: list(take(values))


def _raw(fmu, name: str):
    """The FMI function itself (fmpy has set its argument types), without fmpy's Python wrapper:
    at every communication point that wrapper costs more than the call."""
    return getattr(fmu.dll, name)


def _check(function: str, status: int) -> None:
    if status > 1:   # ok and warning pass; discard, error, fatal, pending do not
        raise FMICallException(function=function, status=status)


# FMI type → (function family, C type), per FMI version. An Enumeration is written with the
# Integer functions in FMI 2 and the Int64 ones in FMI 3, as each standard says.
_FAMILY2 = {
    "Real": ("Real", ctypes.c_double), "Integer": ("Integer", ctypes.c_int32),
    "Enumeration": ("Integer", ctypes.c_int32), "Boolean": ("Boolean", ctypes.c_int32),
    "String": ("String", ctypes.c_char_p),
}
_FAMILY3 = {
    "Float64": ("Float64", ctypes.c_double), "Float32": ("Float32", ctypes.c_float),
    "Int8": ("Int8", ctypes.c_int8), "UInt8": ("UInt8", ctypes.c_uint8),
    "Int16": ("Int16", ctypes.c_int16), "UInt16": ("UInt16", ctypes.c_uint16),
    "Int32": ("Int32", ctypes.c_int32), "UInt32": ("UInt32", ctypes.c_uint32),
    "Int64": ("Int64", ctypes.c_int64), "UInt64": ("UInt64", ctypes.c_uint64),
    "Enumeration": ("Int64", ctypes.c_int64), "Boolean": ("Boolean", ctypes.c_bool),
    "String": ("String", ctypes.c_char_p), "Binary": ("Binary", ctypes.POINTER(ctypes.c_uint8)),
}


def _to_c(kind: SlotType, value):
    if kind is SlotType.STRING:
        return value.encode("utf-8")
    return value


# C types whose array elements are already what _from_c makes of them (float, int, bool).
_NATIVE = {
    SlotType.REAL: (ctypes.c_double, ctypes.c_float),
    SlotType.BOOL: (ctypes.c_bool,),
    SlotType.INT: (ctypes.c_int8, ctypes.c_uint8, ctypes.c_int16, ctypes.c_uint16, ctypes.c_int32, ctypes.c_uint32,
                   ctypes.c_int64, ctypes.c_uint64),
}


def _convert(kind: SlotType, ctype):
    """What turns a value of a C array of `ctype` into the slot's value: None when nothing has to."""
    if ctype in _NATIVE.get(kind, ()):
        return None
    # bool, float, int: what _from_c calls, without a Python call per value
    return {SlotType.BOOL: bool, SlotType.REAL: float, SlotType.INT: int}.get(kind) or functools.partial(_from_c, kind)


def _from_c(kind: SlotType, value):
    if kind is SlotType.STRING:
        return (value or b"").decode("utf-8")
    if kind is SlotType.BOOL:
        return bool(value)
    if kind is SlotType.REAL:
        return float(value)
    return int(value)
