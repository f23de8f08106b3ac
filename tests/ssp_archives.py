"""SSP archives the tests build from the project's own FMUs: an SSD written here, zipped with build/fmus' FMUs and .ssv files.

The controller `timer_belt` (TIMER_BELT):

    system input  blocked ──► timer.start       timer.remaining ──► drive.speed_setpoint
    system input  go      ──► drive.run         drive.speed     ──► system output speed
                                                drive.running   ──► system output running
                                                timer.elapsed   ──► system output done

A rising `blocked` arms the timer; the drive's setpoint is the time the timer has left, so the
belt pushes away what blocked it, slower and slower, and stops when the timer fires. The drive's
ramp is set inline on its component (2.0), the timer's period by the system's parameter set
resources/tuning.ssv (`timer.period`, TUNING).
"""
from __future__ import annotations

import os
import zipfile
from pathlib import Path

from hub.core.resources import BUILT_FMUS

HEAD = ('<?xml version="1.0" encoding="UTF-8"?>\n'
        '<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
        'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
        'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="timer_belt">\n')

TIMER_BELT = HEAD + """\
  <ssd:System name="controller">
    <ssd:Connectors>
      <ssd:Connector name="blocked" kind="input"><ssc:Boolean/></ssd:Connector>
      <ssd:Connector name="go" kind="input"><ssc:Boolean/></ssd:Connector>
      <ssd:Connector name="speed" kind="output"><ssc:Real unit="m/s"/></ssd:Connector>
      <ssd:Connector name="running" kind="output"><ssc:Boolean/></ssd:Connector>
      <ssd:Connector name="done" kind="output"><ssc:Boolean/></ssd:Connector>
    </ssd:Connectors>
    <ssd:ParameterBindings>
      <ssd:ParameterBinding source="resources/tuning.ssv"/>
    </ssd:ParameterBindings>
    <ssd:Elements>
      <ssd:Component name="timer" source="resources/timer.fmu">
        <ssd:Connectors>
          <ssd:Connector name="start" kind="input"><ssc:Boolean/></ssd:Connector>
          <ssd:Connector name="elapsed" kind="output"><ssc:Boolean/></ssd:Connector>
          <ssd:Connector name="remaining" kind="output"><ssc:Real unit="s"/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
      <ssd:Component name="drive" source="resources/belt_drive.fmu">
        <ssd:Connectors>
          <ssd:Connector name="run" kind="input"><ssc:Boolean/></ssd:Connector>
          <ssd:Connector name="speed_setpoint" kind="input"><ssc:Real/></ssd:Connector>
          <ssd:Connector name="speed" kind="output"><ssc:Real unit="m/s"/></ssd:Connector>
          <ssd:Connector name="running" kind="output"><ssc:Boolean/></ssd:Connector>
        </ssd:Connectors>
        <ssd:ParameterBindings>
          <ssd:ParameterBinding>
            <ssd:ParameterValues>
              <ssv:ParameterSet version="1.0" name="drive">
                <ssv:Parameters>
                  <ssv:Parameter name="ramp"><ssv:Real value="2.0"/></ssv:Parameter>
                </ssv:Parameters>
              </ssv:ParameterSet>
            </ssd:ParameterValues>
          </ssd:ParameterBinding>
        </ssd:ParameterBindings>
      </ssd:Component>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startConnector="blocked" endElement="timer" endConnector="start"/>
      <ssd:Connection startConnector="go" endElement="drive" endConnector="run"/>
      <ssd:Connection startElement="timer" startConnector="remaining" endElement="drive" endConnector="speed_setpoint"/>
      <ssd:Connection startElement="drive" startConnector="speed" endConnector="speed"/>
      <ssd:Connection startElement="drive" startConnector="running" endConnector="running"/>
      <ssd:Connection startElement="timer" startConnector="elapsed" endConnector="done"/>
    </ssd:Connections>
  </ssd:System>
</ssd:SystemStructureDescription>
"""


def parameter_set(values: dict[str, tuple[str, str]], name: str = "tuning") -> str:
    """An .ssv: parameter name → (SSP type, value as XML text)."""
    rows = "".join(f'    <ssv:Parameter name="{n}"><ssv:{t} value="{v}"/></ssv:Parameter>\n'
                   for n, (t, v) in values.items())
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
            f'version="1.0" name="{name}">\n  <ssv:Parameters>\n{rows}  </ssv:Parameters>\n</ssv:ParameterSet>\n')


TUNING = parameter_set({"timer.period": ("Real", "0.8")})

#: The archive's FMUs: member → built FMU
FMUS = {"resources/timer.fmu": BUILT_FMUS / "timer-fmi2.fmu",
        "resources/belt_drive.fmu": BUILT_FMUS / "belt_drive-fmi2.fmu"}


def write_ssp(path: Path, ssd: str | None = TIMER_BELT, ssv: str | None = TUNING, fmus: dict | None = None,
              extra: dict[str, str | bytes] | None = None) -> Path:
    """An .ssp at `path`: the SSD (None: left out), resources/tuning.ssv (None: left out), the FMUs
    (member → file) and any `extra` members."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        if ssd is not None:
            archive.writestr("SystemStructure.ssd", ssd)
        if ssv is not None:
            archive.writestr("resources/tuning.ssv", ssv)
        for member, source in (FMUS if fmus is None else fmus).items():
            archive.write(source, member)
        for member, data in (extra or {}).items():
            archive.writestr(member, data)
    return path


def timer_belt() -> Path:
    """build/ssp/timer_belt.ssp, written again when an FMU in it is newer (for tests that need a
    real SSP at import, as the slot-table test does; without `make fmus` it stays unwritten)."""
    path = BUILT_FMUS.parent / "ssp" / "timer_belt.ssp"
    if not all(source.is_file() for source in FMUS.values()):
        return path
    newest = max(source.stat().st_mtime for source in FMUS.values())
    if not path.is_file() or path.stat().st_mtime < newest:
        # Written beside and renamed: another test process (pytest -n) may be reading it.
        partial = write_ssp(path.with_name(f"{path.stem}.{os.getpid()}.partial"))
        os.replace(partial, path)
    return path
