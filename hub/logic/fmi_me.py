"""Model exchange: an FMU's equations integrated by the hub between communication points (the FMU adapter's second file)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model

from hub.core.errors import CheckpointError, SimulationError
from hub.core.logic_spec import CO_SIMULATION, MODEL_EXCHANGE
from hub.logic.fmi import FmuInterface, FmuSlave, held


@dataclass(frozen=True)
class Integration:
    """Which of an FMU's interfaces runs and, for model exchange, how it is integrated.

    `interface`: co-simulation or model-exchange, None for the FMU's own preference (co-simulation
    where it offers it). `solver`: cvode — SUNDIALS CVODE as fmpy ships it (BDF, variable step,
    state events located by root finding) — or euler — explicit, in equal steps of at most
    `max_step`, a state event taken at the end of the step in which its indicator changed sign.
    `max_step`: the longest internal step, s (cvode: unlimited when None). `tolerance`: cvode's
    relative tolerance (its absolute one is that times each state's nominal value, as fmpy sets it).
    """

    interface: str | None = None
    solver: str = "cvode"
    max_step: float | None = None
    tolerance: float = 1e-6


def open_fmu(interface: FmuInterface, instance: str, inputs: list[str], outputs: list[str], parameters: dict,
             start_time: float = 0.0, step_timeout: float = 10.0,
             integration: Integration | None = None) -> FmuSlave:
    """A running instance of the interface `integration` picks: co-simulation, stepped by the FMU
    itself, or model exchange, integrated here."""
    integration = integration or Integration()
    if (integration.interface or interface.kind) == CO_SIMULATION:
        return FmuSlave(interface, instance, inputs, outputs, parameters, start_time, step_timeout)
    return FmuModel(interface, instance, inputs, outputs, parameters, start_time, step_timeout, integration)


class FmuModel(FmuSlave):
    """One model-exchange instance: a logic slave whose `step(t, h)` integrates the FMU's
    continuous states from t to t + h with its inputs held, handling events as FMI prescribes:

    - a changed input at a communication point is an input event (event mode, the inputs set
      there, the discrete states updated, the solver restarted);
    - a time event (nextEventTime) ends an integration interval exactly at its time;
    - a state event (an event indicator changing sign) ends it where the solver finds it;
    - a step event (completedIntegratorStep asking for one) after an accepted step.

    Each event: enterEventMode, the discrete states iterated to a fixed point (bounded), back to
    continuous-time mode, the solver restarted from the new states. Outputs are read in
    continuous-time mode at t + h.

    Checkpoints (`save`/`restore`): with the euler solver, the FMU's state plus the inputs it
    holds, its next time event and the event indicators the solver compares with — everything a
    step reads — so a restored instance goes on bit for bit. With cvode they are refused with a
    CheckpointError: CVODE's history (its order, step size and Nordsieck array) carries over
    communication points, and fmpy's binding can neither read nor set it, so a restored run would
    restart the solver and differ in the last bits.
    """

    KIND = MODEL_EXCHANGE
    STEP = "integrate"
    _CLASSES = {"2.0": FMU2Model, "3.0": FMU3Model}

    def __init__(self, interface: FmuInterface, instance: str, inputs: list[str], outputs: list[str],
                 parameters: dict, start_time: float = 0.0, step_timeout: float = 10.0,
                 integration: Integration = Integration()):
        self.integration = integration
        self._solver = None
        self._inputs = None
        self._fault = None
        super().__init__(interface, instance, inputs, outputs, parameters, start_time, step_timeout)

    def _instantiate_options(self) -> dict:
        return {}

    def _begin(self) -> None:
        # exitInitializationMode leaves a model in event mode: settle it, then integrate.
        self._next_event = self.update_discrete_states()
        self._call("enterContinuousTimeMode", self._fmu.enterContinuousTimeMode)
        self._solver = self._call("start the solver", self._make_solver)
        self._do_step = self._integrate

    def _make_solver(self):
        fmu, nx, nz = self._fmu, self.interface.states, self.interface.event_indicators
        get_dx = fmu.getDerivatives if self._v2 else fmu.getContinuousStateDerivatives
        callbacks = dict(nx=nx, nz=nz, get_x=self._guard(fmu.getContinuousStates),
                         set_x=self._guard(fmu.setContinuousStates), get_dx=self._guard(get_dx),
                         get_z=self._guard(fmu.getEventIndicators))
        if self.integration.solver == "euler":
            return _Euler(set_time=self._guard(fmu.setTime), max_step=self.integration.max_step, **callbacks)
        from fmpy.sundials import CVodeSolver

        return _Stopping(CVodeSolver(get_nominals=self._guard(fmu.getNominalsOfContinuousStates),
                                     set_time=self._guard(fmu.setTime), input=_HeldInputs(), startTime=self.time,
                                     maxStep=self.integration.max_step or math.inf,
                                     relativeTolerance=self.integration.tolerance, maxNumSteps=100_000, **callbacks))

    def _guard(self, function):
        """`function` as a solver callback: a failing FMI call inside the solver is kept and raised
        once the solver returns (an exception cannot cross the C solver's frames)."""
        def call(*args):
            if self._fault is None:
                try:
                    return function(*args)
                except Exception as exc:
                    self._fault = exc
        return call

    def set_inputs(self, values: list) -> None:
        values = list(values)
        if held(values, self._inputs, self._reals):
            return
        self._call("enterEventMode", self._fmu.enterEventMode)
        self._call("set inputs", self._in.set, values)
        self._inputs = values
        self._event()

    def _checkpoint_capable(self, what: str) -> None:
        super()._checkpoint_capable(what)
        if self.integration.solver != "euler":
            raise CheckpointError(
                f"FMU instance {self.instance!r} ({self.interface.path}): cannot {what} its state: it is integrated "
                f"with {self.integration.solver}, whose history between communication points (order, step size, "
                f"Nordsieck array) fmpy's CVODE binding cannot save, so a restored run would not be bit-identical; "
                f"integrate it with solver: euler to checkpoint it")

    def _save_own(self):
        timed, at = self._next_event
        return {"inputs": self._inputs, "next_event": [bool(timed), float(at)], "z": self._solver.z.tolist()}

    def _restore_own(self, own) -> None:
        where = f"FMU instance {self.instance!r} ({self.interface.path.name})"
        try:
            inputs, (timed, at), z = own["inputs"], own["next_event"], own["z"]
            if not (inputs is None or len(inputs) == self._in.count) or len(z) != len(self._solver.z):
                raise ValueError("inputs or event indicators of another count")
            self._solver.z[:] = z
        except (TypeError, KeyError, ValueError) as exc:
            raise CheckpointError(f"{where}: the saved state of its solver does not fit: {exc}") from None
        self._inputs = inputs
        self._next_event = (bool(timed), float(at))

    def _integrate(self, now: float, h: float) -> None:
        end = now + h
        for _ in range(self.MAX_EVENTS):
            if now >= end:
                return
            timed, at = self._next_event
            target = min(end, at) if timed and at > now else end
            state_event, reached = self._solver.step(now, target)
            self._raise_fault()
            self._fmu.setTime(reached)
            step_event = False
            if self.interface.completed_step:
                step_event, terminate = self._fmu.completedIntegratorStep()
                if terminate:
                    raise SimulationError(self._failure(f"the FMU asked to terminate the simulation at "
                                                        f"{reached:.9g} s (completedIntegratorStep)"))
            now = self.time = reached
            if state_event or step_event or (timed and reached >= at):
                self._call("enterEventMode", self._fmu.enterEventMode)
                self._event()
        raise SimulationError(self._failure(f"more than {self.MAX_EVENTS} events between two communication "
                                            f"points: the model chatters"))

    def _event(self) -> None:
        """The rest of an event, from event mode: discrete states settled, continuous time again,
        the solver restarted from the states the event left."""
        self._next_event = self.update_discrete_states()
        self._call("enterContinuousTimeMode", self._fmu.enterContinuousTimeMode)
        self._call("restart the solver", self._solver.reset, self.time)
        self._raise_fault()

    def _raise_fault(self) -> None:
        """The FMI call that failed inside the solver, raised now that the solver has returned."""
        if self._fault is not None:
            fault, self._fault = self._fault, None
            raise fault

    def close(self) -> None:
        self._solver = None   # unused from here; CVODE's memory goes with the solver object (its callbacks run no more)
        super().close()


class _Stopping:
    """fmpy's CVODE solver made to stop at the target: it integrates in CV_NORMAL mode, past the
    target, and interpolates back, so the FMU's equations would be evaluated beyond a time event or
    a communication point (a table's end, an outlet already closed). A stop time set before each
    call (SUNDIALS clears it once reached) keeps every evaluation at or before the target."""

    def __init__(self, solver):
        from ctypes import c_void_p

        from fmpy.sundials.libraries import sundials_cvode
        from fmpy.sundials.sundials_types import sunrealtype

        self.solver = solver
        self._stop = sundials_cvode.CVodeSetStopTime
        self._stop.argtypes = [c_void_p, sunrealtype]

    def step(self, t: float, target: float) -> tuple[bool, float]:
        """(a state event ended the interval, the time reached)."""
        status = self._stop(self.solver.cvode_mem, target)
        if status < 0:
            raise RuntimeError(f"CVodeSetStopTime({target!r}) returned {status}")
        _, roots, reached = self.solver.step(t, target)   # a stop at the target is no event: roots say
        return bool(roots.any()), reached

    def reset(self, time: float) -> None:
        self.solver.reset(time)


class _HeldInputs:
    """fmpy's solver re-applies input signals at every root function call; here inputs are held
    over a communication step, set once at its start."""

    def apply(self, time, **_) -> None:
        pass


class _Euler:
    """Explicit Euler in equal steps of at most `max_step` from t to the target; a state event
    ends the interval at the step in which an event indicator changed sign.

    Written here rather than taken from fmpy's ForwardEuler, which steps once per call and
    compares the indicators with their values before the last event, so an event that resets a
    state (a bounce) is found again on the next step.
    """

    def __init__(self, nx, nz, get_x, set_x, get_dx, get_z, set_time, max_step):
        self.nx, self.nz, self.max_step = nx, nz, max_step
        self.get_x, self.set_x, self.get_dx, self.get_z, self.set_time = get_x, set_x, get_dx, get_z, set_time
        self.x, self.dx = np.zeros(nx), np.zeros(nx)
        self.z, self.before = np.zeros(nz), np.zeros(nz)
        self._x, self._dx, self._z = (np.ctypeslib.as_ctypes(a) if a.size else None for a in (self.x, self.dx, self.z))
        self.reset(None)

    def reset(self, time) -> None:
        if self.nz:
            self.get_z(self._z, self.nz)

    def step(self, t: float, target: float):
        start, span = t, target - t
        n = max(1, math.ceil(span / self.max_step - 1e-9))
        for i in range(n):
            t1 = target if i == n - 1 else start + (i + 1) * span / n
            if self.nx:
                self.get_x(self._x, self.nx)
                self.get_dx(self._dx, self.nx)
                self.x += (t1 - t) * self.dx
            self.set_time(t1)
            if self.nx:
                self.set_x(self._x, self.nx)
            t = t1
            if self.nz:
                self.before[:] = self.z
                self.get_z(self._z, self.nz)
                crossed = (self.before > 0) != (self.z > 0)
                if crossed.any():
                    return True, t1
        return False, target
