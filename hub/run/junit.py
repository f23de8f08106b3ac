"""JUnit XML for CI systems: one test case per expectation of a scenario, judged on one run."""
from __future__ import annotations

from datetime import datetime
from pathlib import Path
from xml.etree import ElementTree

from hub.scenario.expectations import Outcome


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
    run_case = error is not None or interrupted is not None
    failures = sum(o.judged and not o.passed for o in outcomes) + (interrupted is not None)
    skipped = sum(not o.judged for o in outcomes)
    tests, errors = (len(outcomes) + run_case, 0) if error is None else (1, 1)
    root = ElementTree.Element("testsuites", tests=str(tests), failures=str(failures), errors=str(errors),
                               time=f"{seconds:.3f}")
    node = ElementTree.SubElement(root, "testsuite", name=suite, tests=str(tests), failures=str(failures),
                                  errors=str(errors), skipped=str(skipped), time=f"{seconds:.3f}",
                                  timestamp=timestamp.isoformat(timespec="seconds"), hostname=hostname or "localhost")
    if properties:
        props = ElementTree.SubElement(node, "properties")
        for name, value in properties:
            ElementTree.SubElement(props, "property", name=name, value=value)
    share = f"{seconds / tests:.3f}"
    for outcome in outcomes:
        case = ElementTree.SubElement(node, "testcase", classname=suite, name=outcome.expectation.name, time=share)
        if not outcome.judged:
            ElementTree.SubElement(case, "skipped", message=outcome.message)
        elif not outcome.passed:
            failure = ElementTree.SubElement(case, "failure", message=outcome.message)
            failure.text = f"expected {outcome.expectation.describe()}: {outcome.message}"
    if error is not None:
        case = ElementTree.SubElement(node, "testcase", classname=suite, name="the run", time=share)
        ElementTree.SubElement(case, "error", message=error.splitlines()[0] if error else "").text = error
    elif interrupted is not None:
        case = ElementTree.SubElement(node, "testcase", classname=suite, name="the run", time=share)
        ElementTree.SubElement(case, "failure", message=interrupted).text = interrupted
    ElementTree.SubElement(node, "system-out").text = output
    ElementTree.indent(root)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    ElementTree.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
