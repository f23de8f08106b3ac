"""JUnit XML for CI systems: one test case per expectation of a scenario."""
from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree

from hub.scenario.expectations import Outcome


def write_junit(path: Path, suite: str, outcomes: list[Outcome], seconds: float) -> None:
    failures = sum(not o.passed for o in outcomes)
    root = ElementTree.Element("testsuites", tests=str(len(outcomes)), failures=str(failures))
    node = ElementTree.SubElement(root, "testsuite", name=suite, tests=str(len(outcomes)),
                                  failures=str(failures), errors="0", time=f"{seconds:.3f}")
    for outcome in outcomes:
        case = ElementTree.SubElement(node, "testcase", classname=suite, name=outcome.expectation.name)
        if not outcome.passed:
            failure = ElementTree.SubElement(case, "failure", message=outcome.message)
            failure.text = f"expected {outcome.expectation.describe()}: {outcome.message}"
    ElementTree.indent(root)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    ElementTree.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
