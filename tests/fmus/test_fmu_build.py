"""fmus/Makefile: valid FMUs in the FMI layout, incremental rebuilds; warnings and bad descriptions fail the build."""

import shutil
import subprocess
import sys
import zipfile

import pytest
from fmpy.validation import validate_fmu

from .fmu_support import FMUS_DIR, MODELS, NETS, VERSIONS, run_make

PLATFORMS = {2: "linux64", 3: "x86_64-linux"}


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model", MODELS + NETS)
def test_fmu_passes_fmpy_validation(fmu_build, model, version):
    assert validate_fmu(str(fmu_build / f"{model}-fmi{version}.fmu")) == []


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model", MODELS + NETS)
def test_fmu_holds_description_and_binary_only(fmu_build, model, version):
    with zipfile.ZipFile(fmu_build / f"{model}-fmi{version}.fmu") as archive:
        names = archive.namelist()
    assert sorted(names) == sorted(["modelDescription.xml", f"binaries/{PLATFORMS[version]}/{model}.so"])


@pytest.mark.skipif(shutil.which("nm") is None, reason="needs nm from binutils")
@pytest.mark.parametrize("version", VERSIONS)
def test_binary_exports_only_fmi_functions(fmu_build, version):
    # Hidden framework symbols cannot clash with those of another FMU in the same process.
    library = fmu_build / "timer" / f"fmi{version}" / "binaries" / PLATFORMS[version] / "timer.so"
    output = subprocess.run(["nm", "-D", "--defined-only", str(library)], capture_output=True, text=True,
                            check=True).stdout
    symbols = [line.split()[-1] for line in output.splitlines()]
    assert symbols and all(symbol.startswith(f"fmi{version}") for symbol in symbols), symbols


def test_up_to_date_build_does_nothing(fmu_build):
    assert run_make(fmu_build, "-q").returncode == 0


def test_changed_model_rebuilds_only_that_model(fmu_build):
    # -W pretends the file changed without touching it; -n only prints the commands.
    result = run_make(fmu_build, "-n", "-W", "models/timer/model.c")
    assert result.returncode == 0, result.stderr
    assert "timer/fmi2/binaries/linux64/timer.so" in result.stdout
    assert "timer/fmi3/binaries/x86_64-linux/timer.so" in result.stdout
    assert "belt_drive" not in result.stdout


def test_changed_description_regenerates_that_model(fmu_build):
    result = run_make(fmu_build, "-n", "-W", "models/belt_drive/model.yaml")
    assert "generate.py models/belt_drive" in result.stdout
    assert "timer" not in result.stdout


def _write_model(models_dir, name, yaml_text, c_text):
    model_dir = models_dir / name
    model_dir.mkdir(parents=True)
    (model_dir / "model.yaml").write_text(yaml_text)
    (model_dir / "model.c").write_text(c_text)


MINIMAL_YAML = """name: {name}
fmi_versions: [3]
variables:
  - name: out
    type: real
    causality: output
    start: 0.0
"""


def test_model_with_a_warning_fails_the_build(tmp_path):
    _write_model(tmp_path / "models", "noisy", MINIMAL_YAML.format(name="noisy"), """#include "model.h"
static Status step(Instance *inst, double t, double h)
{
    int unused;
    (void)t;
    (void)h;
    inst->var.out = 1.0;
    return STATUS_OK;
}
const ModelHooks MODEL_HOOKS = {.initialize = NULL, .step = step};
""")
    result = run_make(tmp_path / "build", models_dir=tmp_path / "models")
    assert result.returncode != 0
    assert "unused variable" in result.stderr and "-Werror" in result.stderr
    assert not (tmp_path / "build" / "noisy-fmi3.fmu").exists()


def test_description_problems_are_all_reported_with_file_and_line(tmp_path):
    _write_model(tmp_path / "models", "broken", """name: broken
variables:
  - name: speed
    type: reel
    causality: output
  - name: ramp
    type: real
    causality: parameter
    min: 0
    strat: 1.0
""", "")
    result = subprocess.run([sys.executable, str(FMUS_DIR / "generate.py"), str(tmp_path / "models" / "broken"),
                             str(tmp_path / "build")], capture_output=True, text=True)
    assert result.returncode == 1
    model_yaml = tmp_path / "models" / "broken" / "model.yaml"
    assert f"{model_yaml}:3: variable 'speed': type is 'reel': did you mean 'real'?" in result.stderr
    assert f"{model_yaml}:6: variable 'ramp': unknown key 'strat' (did you mean 'start'?)" in result.stderr
    assert f"{model_yaml}:6: variable 'ramp': a parameter needs a start value" in result.stderr
    make = run_make(tmp_path / "build", models_dir=tmp_path / "models")
    assert make.returncode != 0 and "did you mean 'real'?" in make.stderr
