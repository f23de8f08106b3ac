"""Every Dask call of planthub: the cluster a campaign's cases run on — an embedded LocalCluster on loopback, or an existing scheduler — and the cases handed to it and collected.

A case is one task of one thread: the task only waits for the case's child process
(hub/campaign/case.py), so a worker gets one thread per case it runs at once, and the
LocalCluster one worker per core. Dask itself re-runs a task whose worker died on another
worker `distributed.scheduler.allowed-failures` times before it reports the task's KilledWorker;
the embedded cluster sets that to 0 so that this file's own rule holds: one more run
elsewhere, then the case is reported lost. An existing scheduler keeps its own setting (start it
with DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES=0 for the same rule).

The embedded cluster's processes only wait for children, so it also leaves out what Dask does for
a cluster that computes (EMBEDDED): a worker's profiler sampling its threads every 10 ms, the
event-loop and system monitors' ticks: the CPU they took goes to the cases' own processes on a
machine of a few cores (the campaigns' figures in tests/README.md).
"""
from __future__ import annotations

import logging
import os
import signal
import uuid
from contextlib import contextmanager
from dataclasses import dataclass

import dask
from distributed import Client, Event, LocalCluster, as_completed, wait
from distributed.client import FutureCancelledError, FuturesCancelledError
from distributed.scheduler import KilledWorker

from hub.campaign.case import run_case
from hub.core.errors import PlanthubError

CONNECT = 30.0   # s for the embedded cluster to start; an existing scheduler: distributed.comm.timeouts.connect
CLOSE = 30.0     # s to close the client and the embedded cluster
ASK = 2.0        # s a case waits for the scheduler to say whether the campaign stops (else: it does not, yet)
#: Dask's settings for the embedded LocalCluster (its workers get them from their nannies)
EMBEDDED = {"distributed.scheduler.allowed-failures": 0,   # this file's rule: one more run, then lost
            "distributed.worker.profile.enabled": False,
            "distributed.admin.tick.interval": "1s",
            "distributed.admin.system-monitor.interval": "1s",
            "distributed.worker.memory.monitor-interval": "1s"}


class ClusterError(PlanthubError):
    """The cluster could not be started or reached, or failed under a running campaign."""


@dataclass
class Finished:
    """A case the cluster is done with: its result (hub/campaign/case.py), or `lost` saying why its
    worker never returned one."""

    index: int
    result: dict | None
    lost: str | None
    attempt: int


def _task(spec: dict, stop: str) -> dict:
    """Runs on a worker: the case, stopping when the campaign's event is set."""
    event = Event(stop)

    def stopped() -> bool:
        # Event.is_set() waits for the scheduler without a limit: a scheduler that stops answering
        # would hold the loop that enforces the case's time limit
        try:
            return event.client.sync(event.client.scheduler.event_is_set, name=event.name, callback_timeout=ASK)
        except TimeoutError:   # no answer yet: asked again at the next look
            return False
        except Exception:   # noqa: BLE001 — the scheduler is gone: nobody is waiting for this case any more
            return True

    return run_case(spec, stopped)


def dask_setup(worker) -> None:
    """Dask's preload hook, run in each process of the embedded LocalCluster's workers as it starts:
    a terminal's Ctrl-C reaches the whole process group, workers too, and the campaign — not a
    worker dying of it — decides what a Ctrl-C stops."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def _asking(cluster: Cluster, what: str):
    """The choke point of a running campaign's calls to Dask: whatever Dask raises — a scheduler
    gone, a connection closed — is a ClusterError naming the cluster and what was asked."""
    try:
        yield
    except ClusterError:
        raise
    except Exception as exc:   # noqa: BLE001 — Dask's errors have no common base; each is the cluster's failure
        raise ClusterError(f"{cluster.where()} failed while {what}: {type(exc).__name__}: {exc}") from None


@dataclass
class Stopped:
    """What stopping a campaign's cases left: the cases that came back, what cut the wait short, and
    the signal's KeyboardInterrupt if that was a second Ctrl-C or SIGTERM."""

    ended: list[Finished]
    trouble: str | None
    signal: KeyboardInterrupt | None = None


class Cluster:
    """The cluster of one campaign: started (or connected) on entry, closed on exit."""

    def __init__(self, scheduler: str | None = None, workers: int | None = None, quiet: bool = True):
        self.scheduler = scheduler
        self.workers = workers or os.cpu_count() or 1
        self.quiet = quiet
        self.local = None
        self.client = None
        self.name = f"planthub-campaign-{uuid.uuid4().hex[:12]}"
        self.pending: dict = {}   # future → (index, spec, attempt)

    def __enter__(self) -> Cluster:
        if self.quiet:   # a killed worker is a case's business, reported with it, not a page of warnings
            named = [name for name in logging.root.manager.loggerDict if name.split(".")[0] in ("distributed", "tornado")]
            for name in ("distributed", "tornado", *named):   # Dask's configuration gives some their own level
                logging.getLogger(name).setLevel(logging.CRITICAL)
        try:
            if self.scheduler is None:
                with dask.config.set(EMBEDDED):
                    self.local = LocalCluster(n_workers=self.workers, threads_per_worker=1, processes=True,
                                              host="127.0.0.1", dashboard_address=None, preload=[__name__],
                                              silence_logs=logging.CRITICAL if self.quiet else logging.WARNING)
                self.client = Client(self.local, timeout=CONNECT)
            else:
                self.client = Client(self.scheduler)   # waits as long as Dask's configuration says
            self.stop = Event(self.name, client=self.client)
        except Exception as exc:   # noqa: BLE001 — unreachable, an address Dask cannot read, a cluster that failed
            self.close()
            if self.scheduler is not None and isinstance(exc, ValueError):
                raise ClusterError(f"cannot reach {self.where()}: not an address Dask can read "
                                   f"(tcp://HOST:PORT): {_said(exc)}") from None
            raise ClusterError(f"cannot reach {self.where()}: {_said(exc)}") from None
        except BaseException:   # a Ctrl-C or SIGTERM while the cluster starts: what started of it is stopped
            self.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def where(self) -> str:
        return f"scheduler {self.scheduler}" if self.scheduler is not None else "a LocalCluster on 127.0.0.1"

    def describe(self) -> str:
        with _asking(self, "asking for its workers"):
            threads = self.client.nthreads()
        return f"{self.where()}: {len(threads)} workers, {sum(threads.values())} cases at once"

    def slots(self) -> int:
        """How many cases run at once now (0: the cluster has no worker)."""
        with _asking(self, "asking for its workers"):
            return sum(self.client.nthreads().values())

    def submit(self, index: int, spec: dict, attempt: int = 1) -> None:
        with _asking(self, f"handing it case {index}"):
            future = self.client.submit(_task, spec, self.name, key=f"{self.name}-case{index}-try{attempt}",
                                        pure=False)
        self.pending[future] = (index, spec, attempt)

    def each(self, fn, items: list):
        """`fn(item)` for every item on the cluster's workers, as many at once as they have threads,
        yielding (item, what it returned) as each call ends — or the exception it raised. For work
        that is Python, not a scenario (`make stability`'s hard cases, which judge by their own
        checkers): it runs in the worker's process, so a worker that dies fails its call (Dask's
        KilledWorker; the embedded cluster tries no call twice)."""
        with _asking(self, "handing it work"):
            futures = {self.client.submit(fn, item, key=f"{self.name}-call{i}", pure=False): item
                       for i, item in enumerate(items)}
        with _asking(self, "waiting for its work"):
            for future in as_completed(futures):
                failed = future.exception()
                yield futures[future], failed if failed is not None else future.result()

    def running(self) -> int:
        """Cases a worker is running now: each worker's cases handed to it, up to its threads (the
        scheduler hands a worker more than it runs at once)."""
        mine = {f.key for f in self.pending}
        with _asking(self, "asking what its workers run"):
            threads = self.client.nthreads()
            processing = self.client.processing()
        return sum(min(threads.get(worker, 1), sum(key in mine for key in keys)) for worker, keys in processing.items())

    def finished(self, timeout: float) -> list[Finished]:
        """The cases that ended within `timeout` s (none: nothing ended yet). A case whose worker
        died is sent once more, then reported lost."""
        if not self.pending:
            return []
        with _asking(self, "waiting for its cases"):
            try:
                done, _ = wait(list(self.pending), timeout=timeout, return_when="FIRST_COMPLETED")
            except TimeoutError:
                done = []
            except FuturesCancelledError:   # cancelled on the scheduler (a restarted cluster): reported below
                done = [f for f in self.pending if f.done()]
            if self.client.status != "running":   # the client lost its scheduler and cancelled every case
                raise ClusterError(f"{self.where()} failed while waiting for its cases: the scheduler is gone")
        out = []
        for future in done:
            index, spec, attempt = self.pending.pop(future)
            try:
                out.append(Finished(index, future.result(), None, attempt))
            except KilledWorker as exc:
                if attempt == 1:
                    self.submit(index, spec, attempt + 1)
                else:
                    out.append(Finished(index, None, f"its worker died in both runs ({exc})", attempt))
            except FutureCancelledError:
                out.append(Finished(index, None, "cancelled", attempt))
            except Exception as exc:   # noqa: BLE001 — the task itself failed: the case's error, named
                out.append(Finished(index, None, f"{type(exc).__name__}: {exc}", attempt))
        return sorted(out, key=lambda f: f.index)

    def stop_cases(self, limit: float) -> Stopped:
        """Stop every case: those handed to a worker end (a running one writes its files), the others
        are cancelled at once. Never raises: a scheduler gone, or a second Ctrl-C, cuts the wait short."""
        trouble = signalled = None
        try:
            with _asking(self, "stopping its cases"):
                self.stop.set()
                handed = {key for keys in self.client.processing().values() for key in keys}
                self.client.cancel([f for f in self.pending if f.key not in handed])
                try:
                    wait([f for f in self.pending if f.key in handed], timeout=limit)
                except TimeoutError:
                    pass
        except ClusterError as exc:
            trouble = str(exc)
        except KeyboardInterrupt as exc:   # a second Ctrl-C or SIGTERM: no more waiting, what came back is kept
            trouble, signalled = "stopping the cases was interrupted", exc
        ended = []
        for future in list(self.pending):
            if future.status == "finished":
                index, spec, attempt = self.pending.pop(future)
                ended.append(Finished(index, future.result(), None, attempt))
        try:
            self.client.cancel(list(self.pending))
        except Exception:   # noqa: BLE001 — cancelling on a scheduler that may be gone: the client is closed next
            pass
        return Stopped(sorted(ended, key=lambda f: f.index), trouble, signalled)

    def close(self) -> None:
        if self.client is not None:
            try:
                self.client.close(timeout=CLOSE)
            except Exception:   # noqa: BLE001 — closing what may already be gone
                pass
            self.client = None
        if self.local is not None:
            try:
                self.local.close(timeout=CLOSE)
            except Exception:   # noqa: BLE001
                pass
            self.local = None


def _said(exc: BaseException) -> str:
    return str(exc) or type(exc).__name__
