"""`planthub check-fmu`'s verdicts: blockers exit 1, findings the hub can live with are warnings (exit 0).

    cannot load · neither co-simulation nor model exchange (scheduled execution only) · no binary → ✗, exit 1
    variables without a slot · fmpy validation notes                                        → !, exit 0
"""
import subprocess
import sys
import zipfile

import pytest

from .foreign_fmus import build
from .helpers import ROOT


@pytest.fixture(scope="module")
def typed3(tmp_path_factory):
    return build("typed3", 3, tmp_path_factory.mktemp("foreign"))


def planthub(*args):
    return subprocess.run([sys.executable, "-m", "hub", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)


def rewrite(source, target, edit_xml=lambda x: x, edit_binary=None):
    with zipfile.ZipFile(source) as src, zipfile.ZipFile(target, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = edit_xml(data.decode()).encode()
            elif edit_binary is not None:
                data = edit_binary(data)
            dst.writestr(item, data)
    return target


COSIM = '<CoSimulation modelIdentifier="typed3" canHandleVariableCommunicationStepSize="true"/>'
CLOCK = ('<Clock name="tick" valueReference="17" causality="input" intervalVariability="constant" '
         'intervalDecimal="0.01"/>\n  </ModelVariables>')


def test_an_fmu_with_unmapped_extras_is_usable_with_warnings(typed3):
    proc = planthub("check-fmu", typed3)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0] == f"{typed3}: FMI 3.0 co-simulation, model 'typed3'"
    assert lines[1].startswith("  target slots  mode (int from Enumeration, start 1, items slow=1, fast=2, stop=3), "
                               "x32 (real from Float32, start 0), count16 (int from UInt16, start 7), ")
    assert "blob (string from Binary, start '0102'), u_0 (real, start 1), u_1 (real, start 2)" in lines[1]
    assert lines[3].startswith("  settable      gain32 (real from Float32, start 1.5, 0 … 10), "
                               "limit16 (int from UInt16, start 1000, 0 … 50000), A_0_0 (real, start 1)")
    assert lines[-2:] == ["  ! not mapped: n: a structural parameter (it sizes u): planthub keeps its start value 3",
                          "  ✓ usable, with 1 warning (above)"]


def test_a_clock_in_a_cosimulation_fmu_is_a_warning(typed3, tmp_path):
    fmu = rewrite(typed3, tmp_path / "clocked.fmu", lambda x: x.replace("</ModelVariables>", CLOCK))
    proc = planthub("check-fmu", fmu)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert ("  ! not mapped: tick: a Clock: clocks need scheduled execution or event mode, which planthub does "
            "not support\n") in proc.stdout
    assert proc.stdout.endswith("  ✓ usable, with 2 warnings (above)\n")


def test_a_scheduled_execution_fmu_gets_the_exact_verdict(typed3, tmp_path, write_scenario):
    fmu = rewrite(typed3, tmp_path / "scheduled.fmu", lambda x: x.replace(
        COSIM, '<ScheduledExecution modelIdentifier="typed3"/>').replace("</ModelVariables>", CLOCK))
    proc = planthub("check-fmu", fmu)
    assert proc.returncode == 1
    verdict = (f"{fmu}: scheduled execution: not supported (the FMU offers neither co-simulation nor model "
               f"exchange, only scheduled execution; planthub runs those two)")
    assert proc.stderr == f"planthub: {verdict}\n"
    path = write_scenario(f"planthub: 1\nobjects:\n  t: {{module: fmu, file: {fmu}}}\n")
    proc = planthub("validate", path)
    assert proc.returncode == 3, proc.stderr
    assert f"{path}:3: objects.t.file: {verdict}" in proc.stderr


@pytest.mark.parametrize("name, version", [("ball2", 2), ("tank3", 3)])
def test_a_model_exchange_fmu_is_usable(tmp_path, name, version):
    """Model exchange only: the hub integrates it (tests/test_model_exchange.py), and says so."""
    fmu = build(name, version, tmp_path)
    proc = planthub("check-fmu", fmu)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.startswith(f"{fmu}: FMI {version}.0 model exchange (integrated by planthub: `solver:` cvode "
                                  f"or euler), model '{name}'\n")
    assert proc.stdout.endswith("  ✓ passes fmpy's validation\n")


def test_a_model_exchange_binary_that_does_not_instantiate_is_a_blocker(typed3, tmp_path):
    """typed3's binary has no model-exchange functions of its own (generated stubs fail): probed, not believed."""
    fmu = rewrite(typed3, tmp_path / "me.fmu", lambda x: x.replace(COSIM, '<ModelExchange modelIdentifier="typed3"/>'))
    proc = planthub("check-fmu", fmu)
    assert proc.returncode == 1
    assert proc.stdout.startswith(f"{fmu}: FMI 3.0 model exchange")
    assert "  ✗ cannot load: FMU instance 'check-fmu' (me.fmu) at t = 0 s: instantiate failed" in proc.stdout


def test_an_fmu_without_a_binary_for_this_platform_is_a_blocker(typed3, tmp_path):
    fmu = tmp_path / "elsewhere.fmu"
    with zipfile.ZipFile(typed3) as src, zipfile.ZipFile(fmu, "w") as dst:
        for item in src.infolist():
            dst.writestr(item.filename.replace("x86_64-linux", "aarch64-darwin"), src.read(item.filename))
    proc = planthub("check-fmu", fmu)
    assert proc.returncode == 1
    assert proc.stderr == (f"planthub: {fmu}: no binary for this platform (binaries/x86_64-linux/typed3.so); "
                           f"the FMU has: aarch64-darwin\n")


def test_an_fmu_whose_binary_does_not_load_is_a_blocker(typed3, tmp_path):
    fmu = rewrite(typed3, tmp_path / "broken.fmu", edit_binary=lambda data: b"not a shared library")
    proc = planthub("check-fmu", fmu)
    assert proc.returncode == 1
    blocker = proc.stdout.splitlines()[-1]
    assert blocker.startswith("  ✗ cannot load: FMU instance 'check-fmu' (broken.fmu) at t = 0 s: load the binary "
                              "failed: Failed to load shared library ")
    assert blocker.endswith("typed3.so: file too short")


def test_validate_names_what_is_not_mapped(typed3, write_scenario):
    path = write_scenario(f"planthub: 1\nobjects:\n  t: {{module: fmu, file: {typed3}}}\n")
    proc = planthub("validate", path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ("planthub: warning: objects.t.file: typed3.fmu: n is not mapped: a structural parameter "
                           "(it sizes u): planthub keeps its start value 3\n")


def test_describe_says_an_input_keeps_its_start_value():
    proc = planthub("describe", "fmu")
    assert proc.returncode == 0
    assert "each FMU input variable; the FMU's start value until fed" in proc.stdout
    assert "Binary → string of hex" in proc.stdout
