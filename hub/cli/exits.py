"""The command line's exit codes, one per thing a caller (a CI job) acts on differently, and the table `--help` shows."""
from __future__ import annotations

from hub.core.errors import PlanthubError

OK = 0
FAILED = 1        # the run failed (a participant lost, an FMU's error), an expectation failed, `compare` found a deviation, an FMU does not fit
USAGE = 2         # the command line is wrong: argparse's own code for it
BAD_SCENARIO = 3  # the scenario, or a file it names, does not pass its checks
INTERRUPTED = 130  # Ctrl-C: 128 + SIGINT, as shells report it (SIGTERM: 143, hub/run/interruption.py)

# A usage error means fix the command line; a bad scenario means fix the file (the message names
# file and line) — a CI job that builds its command line tells its own mistake from a user's input.
TABLE = """\
exit codes:
  0    ok: the run ended (or an operator stopped it), every expectation held, the
       scenario or the FMU checks out
  1    failed: the run failed (a participant lost, an FMU's error), an expectation
       failed, or check-fmu found a blocker (its warnings alone exit 0)
  2    usage: the command line is wrong (an unknown option or module, a bad --set or
       --realtime, a scenario without `expect:` given to `test`)
  3    bad scenario: the scenario, or a file it names, does not pass its checks (each
       problem named with its file and line)
  130  interrupted (Ctrl-C; 143: SIGTERM): `run` ends at its next point and prints and
       writes the summary so far; `test` judges what ran (the rest: not judged) and
       writes its JUnit file"""


class UsageError(PlanthubError):
    """The command line asks for something that cannot be (exit code 2), found after argparse."""
