"""Shared by the FMU tests: paths, running fmus/Makefile, and one FMU instance driven through fmpy."""

import subprocess
import sys
from pathlib import Path

import fmpy
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.fmi2 import defaultCallbacks as fmi2_default_callbacks
from fmpy.fmi3 import FMU3Slave

REPO = Path(__file__).resolve().parents[2]
FMUS_DIR = REPO / "fmus"
TEST_MODELS_DIR = Path(__file__).resolve().parent / "models"
TEST_NETS_DIR = Path(__file__).resolve().parent / "nets"
MODELS = ("belt_drive", "timer")
# Every net file in fmus/nets is an FMU: switch.pnml -> switch, robot_arm.net.yaml -> robot_arm.
NETS = tuple(sorted(path.name.split(".")[0] for path in (FMUS_DIR / "nets").iterdir()
                    if path.name.endswith((".pnml", ".net.yaml"))))
VERSIONS = (2, 3)


def run_make(build, *args, models_dir=None, nets_dir=None):
    """Run fmus/Makefile with the interpreter running the tests; return the CompletedProcess.

    With models_dir given and no nets_dir, no nets are built: a test of other models need not wait for them."""
    command = ["make", "-C", str(FMUS_DIR), f"PYTHON={sys.executable}", f"BUILD={build}"]
    if models_dir is not None:
        command.append(f"MODELS_DIR={models_dir}")
    if nets_dir is not None or models_dir is not None:
        command.append(f"NETS_DIR={nets_dir or ''}")
    return subprocess.run(command + list(args), capture_output=True, text=True, timeout=300)


def build(build_dir, models_dir=None, nets_dir=None):
    """Run make and return build_dir; fail with make's output if it fails."""
    result = run_make(build_dir, "-j2", models_dir=models_dir, nets_dir=nets_dir)
    assert result.returncode == 0, result.stdout + result.stderr
    return build_dir


class Instance:
    """One FMU instance through fmpy's low-level API, the same calls for FMI 2 and 3; log messages are kept."""

    def __init__(self, fmu, unzip_dir, name="instance", token=None, messages=None):
        self.description = fmpy.read_model_description(str(fmu))
        self.version = 2 if self.description.fmiVersion == "2.0" else 3
        self.variables = {v.name: v for v in self.description.modelVariables}
        self.messages = [] if messages is None else messages
        self.time = 0.0
        self.closed = False
        slave_class = FMU2Slave if self.version == 2 else FMU3Slave
        self.slave = slave_class(guid=token or self.description.guid, unzipDirectory=str(unzip_dir),
                                 modelIdentifier=self.description.coSimulation.modelIdentifier,
                                 instanceName=name)
        if self.version == 2:
            self._callbacks = fmi2CallbackFunctions()
            self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log_fmi2)
            self._callbacks.allocateMemory = fmi2_default_callbacks.allocateMemory
            self._callbacks.freeMemory = fmi2_default_callbacks.freeMemory
            self.slave.instantiate(callbacks=self._callbacks, loggingOn=True)
        else:
            self.slave.instantiate(loggingOn=True, logMessage=self._log_fmi3)

    def _log_fmi2(self, environment, instance_name, status, category, message):
        self.messages.append((status, category.decode(), message.decode()))

    def _log_fmi3(self, environment, status, category, message):
        self.messages.append((status, category.decode(), message.decode()))

    @property
    def errors(self):
        return [message for status, _, message in self.messages if status >= 3]

    def _accessor(self, verb, name):
        # fmpy names its accessors after the FMI type: getReal / getFloat64, setInteger / setInt32, ...
        variable = self.variables[name]
        return getattr(self.slave, verb + variable.type), variable.valueReference

    def get(self, name):
        getter, vr = self._accessor("get", name)
        value = getter([vr])[0]
        if self.variables[name].type == "Boolean":
            return bool(value)  # FMI 2 booleans arrive as int
        return value.decode() if isinstance(value, bytes) else value

    def set(self, name, value):
        setter, vr = self._accessor("set", name)
        setter([vr], [value])

    def initialize(self, start_time=0.0, **start_values):
        for name, value in start_values.items():
            self.set(name, value)
        if self.version == 2:
            self.slave.setupExperiment(startTime=start_time)
        self.slave.enterInitializationMode(**({"startTime": start_time} if self.version == 3 else {}))
        self.slave.exitInitializationMode()
        self.time = start_time

    def step(self, h):
        self.slave.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        self.time += h

    def close(self):
        if not self.closed:
            self.closed = True
            self.slave.freeInstance()
