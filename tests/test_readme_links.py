"""The documentation holds: every relative link of the project's Markdown files resolves (to a file, an
`#anchor` to a heading in it), and every command README.md shows is real — its `make` targets are the
Makefile's, its `planthub` commands parse with the command line's own parser (not run), and the
scenarios they name exist and pass their checks."""
from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from .helpers import ROOT

#: the Markdown files whose links are checked
DOCS = ["README.md", "hub/README.md", "hub/bus/README.md", "hub/campaign/README.md", "hub/cli/README.md",
        "hub/gateway/README.md", "hub/logic/README.md", "hub/physics/README.md", "hub/run/README.md",
        "hub/view/README.md", "fmus/README.md", "schemas/README.md", "schemas/wire.md", "tests/README.md"]

FENCE = re.compile(r"^```.*?^```", re.S | re.M)
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
HUB_COMMAND = (["planthub"], [".venv/bin/planthub"], ["python", "-m", "hub"], [".venv/bin/python", "-m", "hub"])


def prose(text: str) -> str:
    """The text without its fenced code blocks, nor inline code (a `[0](1)` there is no link)."""
    return re.sub(r"`[^`\n]*`", "", FENCE.sub("", text))


def anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    found, seen = set(), {}
    for line in FENCE.sub("", path.read_text(encoding="utf-8")).splitlines():
        match = re.match(r"#{1,6} (.+)", line)
        if match:
            base = anchor(match.group(1))
            count = seen.get(base, 0)
            seen[base] = count + 1
            found.add(base if count == 0 else f"{base}-{count}")
    return found


def test_an_anchor_is_what_github_makes_of_a_heading():
    assert anchor("Free transport (the default, `transport: free`)") == "free-transport-the-default-transport-free"
    assert anchor("Curves, joined belts, bottle models and the paper's tests") == \
        "curves-joined-belts-bottle-models-and-the-papers-tests"
    assert anchor("Choosing settings: speed against error") == "choosing-settings-speed-against-error"


@pytest.mark.parametrize("doc", DOCS)
def test_every_relative_link_resolves(doc):
    path = ROOT / doc
    broken = []
    for target in LINK.findall(prose(path.read_text(encoding="utf-8"))):
        if re.match(r"[a-z]+:", target):   # https:, mailto:
            continue
        file, _, fragment = target.partition("#")
        goal = (path.parent / file).resolve() if file else path
        if not goal.exists():
            broken.append(f"{target}: no file {goal.relative_to(ROOT) if goal.is_relative_to(ROOT) else goal}")
        elif fragment and goal.suffix == ".md" and fragment not in anchors(goal):
            broken.append(f"{target}: no heading '#{fragment}' in {goal.relative_to(ROOT)}")
    assert not broken, f"{doc}:\n" + "\n".join(broken)


# --- the commands README.md shows ----------------------------------------------------------------
def shown_commands(text: str) -> list[list[str]]:
    """Each command of README.md's shell blocks, split as the shell would, comments dropped."""
    commands = []
    for block in re.findall(r"^```(?:sh|bash|shell)\n(.*?)^```", text, re.S | re.M):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words:
                commands.append(words)
    return commands


def make_targets() -> set[str]:
    return set(re.findall(r"^([A-Za-z][\w-]*):", (ROOT / "Makefile").read_text(), re.M))


def hub_arguments(words: list[str]) -> list[str] | None:
    for prefix in HUB_COMMAND:
        if words[:len(prefix)] == prefix:
            return words[len(prefix):]
    return None


def test_readme_shows_commands():
    commands = shown_commands((ROOT / "README.md").read_text(encoding="utf-8"))
    assert ["make", "run"] in commands and ["make", "test"] in commands
    assert any(hub_arguments(c) for c in commands)


def test_every_command_readme_shows_is_real():
    from hub.cli.main import parser
    from hub.scenario.checker import load_scenario

    targets, wrong = make_targets(), []
    for words in shown_commands((ROOT / "README.md").read_text(encoding="utf-8")):
        shown = " ".join(words)
        if words[0] == "make":
            wrong += [f"{shown}: no target '{w}' in the Makefile" for w in words[1:] if "=" not in w and w not in targets]
            continue
        arguments = hub_arguments(words)
        if arguments is None:
            wrong.append(f"{shown}: neither make nor planthub")
            continue
        top, _ = parser()
        try:
            top.parse_args(arguments)
        except SystemExit:
            wrong.append(f"{shown}: planthub's parser refuses it")
        for word in arguments:
            if word.endswith((".yaml", ".yml")):
                if not (ROOT / word).is_file():
                    wrong.append(f"{shown}: no scenario {word}")
                else:
                    load_scenario(ROOT / word)   # raises ScenarioError naming each problem
    assert not wrong, "\n".join(wrong)


def test_the_first_scenario_in_readme_is_the_file():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    start = text.index("<!-- first scenario: scenarios/first.yaml -->")
    block = text[text.index("```yaml\n", start) + 8:text.index("```", text.index("```yaml\n", start) + 8)]
    assert block == (ROOT / "scenarios" / "first.yaml").read_text(encoding="utf-8")
    assert len(block.splitlines()) <= 15


def test_readme_is_a_front_door():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 250
    # no hand-copied benchmark figures: those are tests/README.md's, written by make bench
    figure = re.search(r".*\d\s*(µs|× real time|ms a tick|MB per).*", text)
    assert figure is None, figure.group(0)


def test_the_scenario_format_s_examples_load(tmp_path):
    """schemas/README.md's annotated scenario and campaign are real: each passes its checks, the
    campaign's scenario path read from beside a scenarios/ folder as the example says."""
    from hub.campaign.plan import load_campaign
    from hub.scenario.checker import load_scenario

    blocks = [b for b in re.findall(r"^```yaml\n(.*?)^```", (ROOT / "schemas" / "README.md").read_text(), re.S | re.M)
              if b.startswith("planthub: 1")]
    assert len(blocks) == 2
    scenario, campaign = blocks
    (tmp_path / "scenario.yaml").write_text(scenario)
    load_scenario(tmp_path / "scenario.yaml")
    (tmp_path / "campaigns").mkdir()
    (tmp_path / "scenarios").symlink_to(ROOT / "scenarios")
    (tmp_path / "campaigns" / "speeds.yaml").write_text(campaign)
    assert len(load_campaign(tmp_path / "campaigns" / "speeds.yaml").cases) == 16
