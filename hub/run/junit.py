"""JUnit XML for CI systems: one test case per expectation of a scenario, judged on one run (and the suite writer a campaign's file shares)."""
from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from xml.etree import ElementTree

from hub.core.files import written
from hub.scenario.expectations import Outcome


@dataclass(frozen=True)
class TestCase:
    """One <testcase>: its `result` is passed, failure, error or skipped; a mark other than passed
    carries `message` and, if given, `text`; `output` is the case's own <system-out>."""

    __test__ = False   # not a pytest class, whatever its name

    classname: str
    name: str
    result: str = "passed"
    message: str = ""
    text: str | None = None
    seconds: float | None = None
    output: str | None = None


def write_suite(path: Path, suite: str, cases: list[TestCase], seconds: float, *, timestamp: datetime,
                hostname: str = "", properties: list[tuple[str, str]] = (), output: str | None = None) -> None:
    """One <testsuite> of `cases`, its counts taken from them, written whole (hub/core/files.py)."""
    count = {kind: str(sum(c.result == kind for c in cases)) for kind in ("failure", "error", "skipped")}
    root = ElementTree.Element("testsuites", tests=str(len(cases)), failures=count["failure"], errors=count["error"],
                               time=f"{seconds:.3f}")
    node = ElementTree.SubElement(root, "testsuite", name=suite, tests=str(len(cases)), failures=count["failure"],
                                  errors=count["error"], skipped=count["skipped"], time=f"{seconds:.3f}",
                                  timestamp=timestamp.isoformat(timespec="seconds"), hostname=hostname or "localhost")
    if properties:
        props = ElementTree.SubElement(node, "properties")
        for name, value in properties:
            ElementTree.SubElement(props, "property", name=name, value=value)
    for case in cases:
        element = ElementTree.SubElement(node, "testcase", classname=case.classname, name=case.name)
        if case.seconds is not None:
            element.set("time", f"{case.seconds:.3f}")
        if case.result != "passed":
            mark = ElementTree.SubElement(element, case.result, message=case.message)
            if case.text is not None:
                mark.text = case.text
        if case.output is not None:
            ElementTree.SubElement(element, "system-out").text = case.output
    if output is not None:
        ElementTree.SubElement(node, "system-out").text = output
    ElementTree.indent(root)
    with written(path, "wb") as file:
        ElementTree.ElementTree(root).write(file, encoding="utf-8", xml_declaration=True)


def write_junit(path: Path, suite: str, outcomes: list[Outcome], seconds: float, *, timestamp: datetime,
                hostname: str = "", properties: list[tuple[str, str]] = (), output: str = "",
                error: str | None = None, interrupted: str | None = None) -> None:
    """One <testsuite> for the run: `timestamp` when it started, `seconds` of wall time,
    `properties` (scenario, seed, each --set, how it ended) and the run's printed summary as
    <system-out>. Every case was judged on the one run, so each gets an even share of its time:
    CI systems add the cases' times up, and they add up to the run's. `error`: the run failed
    before anything could be judged — one case, "the run", in error. `interrupted`: how a signal
    ended the run — a case "the run" that failed, beside the expectations, those it left
    unjudged skipped."""
    share = seconds / max(1, len(outcomes) + (interrupted is not None) if error is None else 1)
    cases = []
    for outcome in outcomes:
        if not outcome.judged:
            cases.append(TestCase(suite, outcome.expectation.name, "skipped", outcome.message, seconds=share))
        elif not outcome.passed:
            cases.append(TestCase(suite, outcome.expectation.name, "failure", outcome.message, seconds=share,
                                  text=f"expected {outcome.expectation.describe()}: {outcome.message}"))
        else:
            cases.append(TestCase(suite, outcome.expectation.name, seconds=share))
    if error is not None:
        cases.append(TestCase(suite, "the run", "error", error.splitlines()[0] if error else "", error, share))
    elif interrupted is not None:
        cases.append(TestCase(suite, "the run", "failure", interrupted, interrupted, share))
    write_suite(path, suite, cases, seconds, timestamp=timestamp, hostname=hostname, properties=properties,
                output=output)
