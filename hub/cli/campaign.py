"""`planthub campaign`: a campaign file's cases run on a Dask cluster (embedded, or an existing scheduler), written as campaign.json, cases.csv and one JUnit file."""
from __future__ import annotations

import argparse
import json
import logging
import signal
from datetime import datetime
from pathlib import Path

from hub.cli.exits import FAILED, OK, UsageError
from hub.cli.options import verbosity
from hub.core import scratch

_log = logging.getLogger(__name__)


def add_command(sub, parents=(), formatter=argparse.HelpFormatter, epilog: str = ""):
    """The `campaign` subcommand; returns its handler."""
    campaign = sub.add_parser(
        "campaign", parents=parents, formatter_class=formatter,
        help="run many cases of scenarios (a matrix of --set values × seeds) at once on a Dask cluster",
        description="Run every case of a campaign file (schemas/campaign.schema.json): each scenario × each\n"
                    "combination of its matrix × each seed, each case a `planthub test` child process on a\n"
                    "worker of a Dask cluster. Without --scheduler a LocalCluster on 127.0.0.1 (one worker a\n"
                    "core) is started and stopped with the campaign. Prints a line per finished case with the\n"
                    "campaign's progress, then a table; writes DIR/campaign.json, DIR/cases.csv and each\n"
                    "case's run folder under DIR/cases/. Exit 1 if a case failed; Ctrl-C stops the campaign\n"
                    "and writes what finished.",
        epilog="example:\n  planthub campaign campaigns/speeds.yaml --out runs/speeds --junit runs/speeds.xml\n"
               "  planthub campaign campaigns/speeds.yaml --out runs/again --only-failed runs/speeds "
               "--scheduler tcp://10.0.0.5:8786\n\n" + epilog)
    campaign.add_argument("file", type=Path, metavar="FILE", help="the campaign file (YAML)")
    campaign.add_argument("--out", type=Path, metavar="DIR", help="folder for the results (default: runs/campaign_<name>)")
    campaign.add_argument("--junit", type=Path, metavar="FILE.xml", help="also write the verdicts as JUnit XML")
    where = campaign.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="use this existing Dask scheduler, e.g. tcp://10.0.0.5:8786 (its workers must see "
                            "the campaign's files and DIR at the same paths, and run this planthub)")
    where.add_argument("--workers", type=_count, metavar="N", help="workers of the embedded LocalCluster "
                                                                   "(default: one a core)")
    campaign.add_argument("--only-failed", type=Path, metavar="DIR",
                          help="run only the cases that did not pass in the campaign written to DIR")
    campaign.set_defaults(command_parser=campaign)
    return _campaign


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of workers, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"needs at least 1 worker, got {value}")
    return value


def _campaign(args) -> int:
    from hub.campaign.cluster import Cluster, ClusterError
    from hub.campaign.plan import load_campaign
    from hub.campaign.results import table, write_results
    from hub.campaign.runner import Terminated, interruption, not_run, run_campaign

    scratch.sweep()
    campaign = load_campaign(args.file)   # a bad file: exit 3, every problem named
    out = args.out or Path("runs") / f"campaign_{campaign.name}"
    if args.only_failed is not None:
        if out.resolve() == args.only_failed.resolve():
            raise UsageError(f"--out {out} is the campaign whose failures are run again; write them elsewhere")
        campaign = _only_failed(campaign, args.only_failed)
    started = datetime.now().replace(microsecond=0)

    def terminate(signum, frame):
        raise Terminated()

    if not campaign.cases:   # --only-failed after a campaign that passed
        from hub.campaign.runner import Outcome

        write_results(Outcome(campaign, out, "no cluster", [], "no case to run"), args.junit, started)
        print(f"planthub campaign {campaign.name}: no case to run")
        return OK
    previous, sigint = signal.signal(signal.SIGTERM, terminate), signal.getsignal(signal.SIGINT)
    cluster = Cluster(args.scheduler, args.workers, quiet=verbosity(args) < 1)
    outcome = None
    try:
        try:
            with cluster:
                _log.info(f"planthub campaign: {len(campaign.cases)} cases on {cluster.describe()}")
                say = (lambda line: None) if verbosity(args) < 0 else None
                outcome = run_campaign(campaign, out, cluster, progress=say)
        except ClusterError as exc:   # nothing ran; the files say so, as for any campaign that went wrong
            outcome = not_run(campaign, out, cluster.where(), str(exc))
            _log.error(f"planthub campaign: {exc}")
        except KeyboardInterrupt as exc:   # a Ctrl-C or SIGTERM while the cluster started, or as it closed
            if outcome is None:
                signalled = interruption(exc)
                outcome = not_run(campaign, out, cluster.where(), f"interrupted ({signalled})", interrupted=signalled)
            else:
                outcome.interrupted = outcome.interrupted or interruption(exc)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)   # the files are written whole: a signal now is not heard
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        write_results(outcome, args.junit, started)
    finally:
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, sigint)
    print("\n".join(table(outcome)))
    if outcome.interrupted is not None:
        return 143 if outcome.interrupted == "SIGTERM" else 130
    return OK if outcome.passed else FAILED


def _only_failed(campaign, folder: Path):
    """The cases of `campaign` that did not pass in the campaign written to `folder`, by label."""
    from dataclasses import replace

    path = folder / "campaign.json"
    try:
        earlier = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise UsageError(f"--only-failed {folder}: cannot read the earlier campaign's results {path}: "
                         f"{getattr(exc, 'strerror', None) or exc}") from None
    try:
        failed = {case["label"] for case in earlier["cases"] if case["verdict"] != "passed"}
    except (KeyError, TypeError):
        raise UsageError(f"--only-failed {folder}: {path} is no campaign's results (`planthub campaign --out`): "
                         "no list of cases with their label and verdict") from None
    cases = tuple(case for case in campaign.cases if case.label in failed)
    unknown = failed - {case.label for case in cases}
    if unknown:
        _log.warning("planthub campaign: %d failed case(s) of %s are not in %s any more: %s", len(unknown), path,
                     campaign.path, ", ".join(sorted(unknown)[:5]))
    return replace(campaign, cases=cases)
